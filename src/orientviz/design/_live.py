"""A design that answers each change at once: low-rank updates of the design's cofactors.

Making point j control with weights P_j = diag(1/σ²) (1/m²), or changing or removing its
control, adds ΔP_j to the point's 3×3 block of the normal equations N — values change, the
structure does not (a design's points are all unknowns: its control is weighted). With A
selecting the point's coordinates, each change is one step of the Sherman-Morrison-Woodbury
formula from the current cofactors Q:

    Q' = (N + Aᵀ ΔP A)⁻¹ = Q − C M Cᵀ,   C = Q Aᵀ,   M = (I + ΔP A C)⁻¹ ΔP.

The current columns C are those of the base design, C0 = Q0 Aᵀ — three solves with its
factorised reduced camera system (right-hand side −Σ T_a of the point's rays,
T = W V⁻¹) and one back-substitution to all points (Q_kj = δ_kj V_j⁻¹ − Σ_b T_bᵀ
Q_c(i_b, j)), kept per point — less the earlier steps' C_s M_s C_sᵀ Aᵀ. A step costs
those (the solves once per point) and the update of the shown quantities, whatever the
number of earlier changes; undo restores the terms before the step:

* point and station covariances: Q_kk − C_k M C_kᵀ;
* per ray with h = P½ J C (2 × r): the block P½ J Q Jᵀ P½ loses h M hᵀ, so the
  redundancy numbers gain diag(h M hᵀ) and the ray's gains K = Q Jᵀ P½ lose C M hᵀ;
* from these the reliability (:func:`orientviz.bundle.ray_reliability`), ellipsoids,
  weak spots and summary (:func:`orientviz.design._quality.quality_from_arrays`).

Every number equals a new :func:`orientviz.design.assess_block` of the changed design up
to rounding (``tests/design/test_live.py``). Changes of the image σ, the flight or the
strips change N itself: :meth:`LiveDesign.rebuild` forms and factors it again.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..block import CONTROL, TIE, Block
from ..bundle import RayGains, ray_reliability
from ..bundle.problem import BundleProblem, BundleState, point_setup
from ..bundle.reduced import factor_reduced
from ..errors import InputError
from ._design import assess_block
from ._quality import DesignQuality, quality_from_arrays

F64 = NDArray[np.float64]

#: After this many update steps the design is formed and factored again.
MAX_STEPS: int = 40


@dataclass(frozen=True)
class Change:
    """One change of a design: point ``point`` gets control σ ``sigma`` (m, NaN = that
    coordinate not given; all NaN = tie point); ``before`` is what it had."""

    point: int
    sigma: tuple[float, float, float]
    before: tuple[float, float, float]

    def describe(self, ids: list[str]) -> str:
        """The change in words."""

        def txt(s):
            s = np.asarray(s)
            if not np.isfinite(s).any():
                return "tie"
            return (
                "control σ " + "/".join("–" if not np.isfinite(v) else f"{v:g}" for v in s) + " m"
            )

        return f"point {ids[self.point]}: {txt(self.before)} → {txt(self.sigma)}"


def _weights(sig) -> F64:
    s = np.asarray(sig, float)
    return np.where(np.isfinite(s), 1.0 / np.where(np.isfinite(s), s, 1.0) ** 2, 0.0)


class LiveDesign:
    """A design block whose quality follows each change of its control at once.

    Parameters
    ----------
    block : Block
        A design block (:func:`orientviz.design.design_block`): planned geometry,
        error-free observations, weighted control.
    spec : dict
        Its geometry (needs ``base_m``).
    level, alpha0, beta0 : float
        Ellipsoid probability; test level and power of the reliability.

    Attributes
    ----------
    block : Block
        The current design (control as changed).
    changes : list of Change
        The changes since the last :meth:`rebuild`, in order (:meth:`undo` takes the
        last back).
    history : list of str
        Every change in words, including those before a rebuild.
    """

    def __init__(
        self, block: Block, spec: dict[str, Any], *, level: float = 0.95,
        alpha0: float = 0.001, beta0: float = 0.80, auxiliary: list | None = None,
    ) -> None:  # fmt: skip
        self.spec = spec
        #: auxiliary data with strip offsets (a border of the normal equations): then each
        #: change is assessed anew (exact, slower), not by the update formula
        self.auxiliary = list(auxiliary or [])
        self.level, self.alpha0, self.beta0 = level, alpha0, beta0
        self.history: list[str] = []
        self._undo_base: list[Change] = []
        self.rebuild(block.copy())

    # ------------------------------------------------------------------ the base design
    def rebuild(self, block: Block | None = None) -> DesignQuality:
        """Form and factor the normal equations of the current (or given) design again."""
        if block is not None:
            self.block = block
        b = self.block
        res, q = assess_block(
            b, self.spec, level=self.level, alpha0=self.alpha0, beta0=self.beta0,
            auxiliary=self.auxiliary,
        )  # fmt: skip
        self.changes = []
        self._stack = []
        self.base_quality = self._quality = q
        self.result = res
        if self.auxiliary:
            self._w = self._weights_now()
            return q
        prob = BundleProblem(b, point_setup(b, "weighted"))
        if prob.points.n != b.n_points:
            raise InputError("a live design needs weighted control (σ > 0) at every point")
        st = BundleState(b.images.X0, b.images.angles, b.points.xyz, np.zeros(0), np.zeros(0))
        rw, Je, Jp = prob.residuals(st, jac=True)
        ne = prob.normal(st, rw, Je, Jp)
        self._fac = factor_reduced(prob.reduced, ne.blocks)
        self._prob, self._T, self._Vinv = prob, ne.T, ne.Vinv
        sw = prob.obs.weight[:, :, None]
        self._Jew, self._Jpw = Je * sw, Jp * sw
        n = b.n_observations
        idx = prob.obs.index
        rn = np.asarray(res.redundancy_numbers[: 2 * n]).reshape(n, 2)
        unk = prob.points.unknown
        #: the current cofactor terms (points by column, images, rays in the problem's order)
        self._cur = _Current(
            Qp=np.asarray(res.cofactor_groups["points"])[unk],
            Qe=np.asarray(res.cofactor_groups["exterior"]),
            r=rn[idx],
            rxy=np.asarray(res.redundancy_xy)[idx],
            Ke=np.asarray(res.ray_gains.exterior)[idx],
            Kp=np.asarray(res.ray_gains.points)[idx],
        )
        self._w = self._weights_now()  # the weights the current terms belong to
        self._cols: dict[int, tuple[F64, F64]] = {}
        #: per step: (weights, terms, quality) before it, and its (Cc, Cp, M)
        self._stack: list[tuple[F64, _Current, DesignQuality, tuple]] = []
        self.changes: list[Change] = []
        self.base_quality = self._quality = q
        self.result = res
        return q

    def _weights_now(self) -> F64:
        """Weights 1/σ² (1/m²) of the given coordinates of every point (p, 3)."""
        return _weights(self.block.points.sigma)

    def columns(self, point: int) -> tuple[F64, F64]:
        """Q0 at the three columns of a point: orientations (m, 6, 3), points (p, 3, 3)."""
        got = self._cols.get(point)
        if got is not None:
            return got
        prob, T = self._prob, self._T
        col = prob.points.column[point]
        rays = np.flatnonzero(prob.obs.column == col)
        m = self.block.n_images
        rhs = np.zeros((m, 6, 3))
        np.add.at(rhs, prob.obs.image[rays], -T[rays])
        Cc = self._fac.solve(rhs.reshape(6 * m, 3)).reshape(m, 6, 3)
        S = prob.reduced
        vo = prob.obs.var_rays
        oi = prob.obs.image
        Cp = -np.add.reduceat(T[vo].transpose(0, 2, 1) @ Cc[oi[vo]], S.pt_starts, axis=0)
        Cp[col] += self._Vinv[col]
        self._cols[point] = (Cc, Cp)
        return Cc, Cp

    # ------------------------------------------------------------------ changes
    def set_control(self, point: int, sigma_xyz: ArrayLike) -> DesignQuality:
        """Make ``point`` control with σ (m; NaN = coordinate not given, all NaN = tie).

        Returns the updated :class:`DesignQuality`.
        """
        s = np.asarray(sigma_xyz, float).reshape(3)
        if np.any(s[np.isfinite(s)] <= 0):
            raise InputError(f"sigma_xyz: a design weights its control, expected σ > 0, got {s}")
        before = tuple(float(v) for v in self.block.points.sigma[point])
        ch = Change(int(point), tuple(float(v) for v in s), before)
        self._apply_roles(ch.point, s)
        self.changes.append(ch)
        self.history.append(ch.describe(self.block.points.ids))
        if len(self._stack) >= MAX_STEPS:
            self.history.append("(normal equations formed and factored again)")
            return self.rebuild()
        return self.quality()

    def add_control(self, point: int, sigma: float = 0.02) -> DesignQuality:
        """Make ``point`` XYZ control with σ ``sigma`` (m) in each coordinate."""
        return self.set_control(point, (sigma, sigma, sigma))

    def remove_control(self, point: int) -> DesignQuality:
        """Make ``point`` a tie point."""
        return self.set_control(point, (np.nan, np.nan, np.nan))

    def undo(self) -> DesignQuality:
        """Take the last change since the last :meth:`rebuild` back."""
        if not self.changes:
            raise InputError("nothing to undo since the last rebuild")
        ch = self.changes.pop()
        self._apply_roles(ch.point, np.asarray(ch.before))
        self.history.append(f"undo: {ch.describe(self.block.points.ids)}")
        if self._stack:  # the terms before the change's step
            self._w, self._cur, self._quality, _ = self._stack.pop()
        return self.quality()

    def _apply_roles(self, point: int, s: F64) -> None:
        P = self.block.points
        given = np.isfinite(s)
        P.sigma[point] = np.where(given, s, np.nan)
        P.xyz_known[point] = np.where(given, P.xyz[point], np.nan)
        P.role[point] = CONTROL if given.any() else TIE

    # ------------------------------------------------------------------ the quality
    def current_columns(self, point: int) -> tuple[F64, F64]:
        """The current design's cofactors at the three columns of ``point``: orientations
        (m, 6, 3) and points by column (p, 3, 3); Q0's columns less each step's C M Cᵀ."""
        if self.auxiliary:
            raise InputError("no cofactor columns for a design with auxiliary data")
        Cc, Cp = self.columns(point)
        c = self._prob.points.column[point]
        for _, _, _, (Cs, Ps, Ms) in self._stack:
            B = Ms @ Ps[c].T  # (r, 3)
            Cc = Cc - Cs @ B
            Cp = Cp - Ps @ B
        return Cc, Cp

    def quality(self) -> DesignQuality:
        """The quality of the current design (by the update formula)."""
        w = self._weights_now()
        pts = np.flatnonzero(np.any(w != self._w, axis=1))
        if pts.size and self.auxiliary:  # a new assessment (the border has no update here)
            self._stack.append((self._w, None, self._quality, None))
            self._w = w
            self._quality = assess_block(
                self.block, self.spec, level=self.level, alpha0=self.alpha0, beta0=self.beta0,
                auxiliary=self.auxiliary,
            )[1]  # fmt: skip
        elif pts.size:
            self._step(pts, w)
        return self._quality

    def _step(self, pts: NDArray[np.int64], w: F64) -> None:
        """One rank-3k update from the current terms to the weights ``w`` at ``pts``."""
        cols = [self.current_columns(int(j)) for j in pts]
        Cc = np.concatenate([c[0] for c in cols], axis=2)  # (m, 6, r)
        Cp = np.concatenate([c[1] for c in cols], axis=2)  # (p, 3, r)
        prob = self._prob
        pc = prob.points.column[pts]
        G = Cp[pc].reshape(-1, Cp.shape[2])  # A C (r, r)
        d = (w - self._w)[pts].reshape(-1)
        M = np.linalg.solve(np.eye(d.size) + d[:, None] * G, np.diag(d))
        M = 0.5 * (M + M.T)
        c0 = self._cur
        oi, oc = prob.obs.image, prob.obs.column
        CpM = Cp @ M
        CcM = Cc @ M
        h = self._Jew @ Cc[oi] + self._Jpw @ Cp[oc]  # (n, 2, r)
        hM = h @ M
        dH = hM @ h.transpose(0, 2, 1)
        ht = h.transpose(0, 2, 1)
        cur = _Current(
            Qp=c0.Qp - CpM @ Cp.transpose(0, 2, 1),
            Qe=c0.Qe - CcM @ Cc.transpose(0, 2, 1),
            r=np.clip(c0.r + np.stack([dH[:, 0, 0], dH[:, 1, 1]], 1), 0.0, 1.0),
            rxy=c0.rxy + 0.5 * (dH[:, 0, 1] + dH[:, 1, 0]),
            Ke=c0.Ke - CcM[oi] @ ht,
            Kp=c0.Kp - CpM[oc] @ ht,
        )
        self._stack.append((self._w, c0, self._quality, (Cc, Cp, M)))
        self._w, self._cur = w, cur
        self._quality = self._assemble(cur)

    def _assemble(self, cur: _Current) -> DesignQuality:
        """Reliability, ellipsoids, weak spots and summary from the current terms."""
        b, prob = self.block, self._prob
        n = b.n_observations
        idx = prob.obs.index
        rn = np.full((n, 2), np.nan)
        rn[idx] = cur.r
        rx = np.full(n, np.nan)
        rx[idx] = cur.rxy
        ge, gp = np.full((n, 6, 2), np.nan), np.full((n, 3, 2), np.nan)
        ge[idx], gp[idx] = cur.Ke, cur.Kp
        adj = SimpleNamespace(
            redundancy_numbers=rn.reshape(-1), redundancy_xy=rx, ray_gains=RayGains(ge, gp)
        )
        rel = ray_reliability(adj, b, alpha0=self.alpha0, beta0=self.beta0)
        Qp_all = np.empty((b.n_points, 3, 3))
        Qp_all[prob.points.unknown] = cur.Qp
        return quality_from_arrays(
            b, Qp_all, cur.Qe, rn, rel, float(self.spec["base_m"]), self.level
        )


@dataclass(frozen=True)
class _Current:
    """The cofactor terms of a design that the shown quantities come from."""

    Qp: F64
    Qe: F64
    r: F64
    rxy: F64
    Ke: F64
    Kp: F64
