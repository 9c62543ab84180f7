"""The factorised normal equations of a base design and the columns of its inverse.

A :class:`DesignBase` holds what the live updates (:mod:`orientviz.design._live`) start
from: the bundle's normal equations of a design block (all points unknown: a design
weights its control), the factor of the reduced camera system S (points eliminated) and,
with auxiliary data, the border of their strip offsets g.

Columns of the base cofactors Q0 = N⁻¹ at chosen coordinates (an image's six, a point's
three) come from one multi-column solve with the factor: for image k the right-hand side
is the unit columns of its six unknowns, for point j it is −Σ_a T_a over the point's rays
(T = W V⁻¹); the image rows are S⁻¹ of it and the point rows follow by back-substitution,
Q_jk = δ V_j⁻¹ − Σ_b T_bᵀ Q_c(i_b, ·). With a border B (auxiliary offsets) the columns of
the bordered inverse add G F̃⁻¹ G_Ωᵀ, with G = A⁻¹B (images S⁻¹E, points
V⁻¹P_g − Σ T_bᵀ (S⁻¹E)_(i_b)) and F̃ = F − EᵀS⁻¹E the reduced border (the same algebra as
the bundle's precision, :mod:`orientviz.bundle.precision`). Only the image and point rows
are returned: nothing shown needs the offsets' own cofactors.

Points are indexed by the base block's point index, rays by its observation index.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..bundle import BundleOptions
from ..bundle.precision import BandSolver, bundle_precision
from ..bundle.problem import BundleProblem, BundleState, point_setup
from ..bundle.reduced import factor_reduced
from ..errors import InputError

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Block size (unknowns) of the banded selected inverse of a design (the bundle's
#: default is 96; benchmarks/README.md, "Block design", for the choice).
TAKAHASHI_BLOCK: int = 48


class DesignBase:
    """The factorised normal equations of a design block (constant once made).

    Parameters
    ----------
    block : Block
        A design block: planned geometry, every point with σ > 0 or a tie point (all
        points unknown).
    auxiliary : list of Auxiliary, optional
        Statoscope / APR / GNSS rows with strip offsets (a border of the system).

    Attributes
    ----------
    m, p : int
        Images and points of the base block.
    Jw : ndarray, shape (n, 2, 9)
        P½ J of every ray (block observation order): six exterior then three point
        columns (mm/m, mm/rad divided by σ in mm).
    """

    def __init__(self, block: Block, auxiliary: list | None = None) -> None:
        prob = BundleProblem(
            block, point_setup(block, "weighted"), auxiliary=auxiliary or None,
            options=BundleOptions(takahashi_block=TAKAHASHI_BLOCK),
        )  # fmt: skip
        if prob.points.n != block.n_points:
            raise InputError("a live design needs weighted control (σ > 0) at every point")
        st = BundleState(
            block.images.X0, block.images.angles, block.points.xyz, np.zeros(0),
            np.zeros(prob.na),
        )  # fmt: skip
        rw, Je, Jp = prob.residuals(st, jac=True)
        ne = prob.normal(st, rw, Je, Jp)
        self.fac = factor_reduced(prob.reduced, ne.blocks)
        self._lin = (st, rw, Je, Jp, ne)
        self.prob, self.T, self.Vinv = prob, ne.T, ne.Vinv
        self.m, self.p = block.n_images, block.n_points
        idx = prob.obs.index
        sw = prob.obs.weight[:, :, None]
        Jw = np.full((block.n_observations, 2, 9), np.nan)
        Jw[idx, :, :6], Jw[idx, :, 6:] = Je * sw, Jp * sw
        self.Jw = Jw
        self.pcol = np.asarray(prob.points.column)  # base point → column of the problem
        self.na = prob.na
        self._cache: dict[tuple[str, int], tuple[F64, F64]] = {}
        self._band: BandSolver | None = None  # solves with many columns (on demand)
        #: the border of the auxiliary offsets (E, F, P_g), made G = A⁻¹B and F̃⁻¹ by
        #: :meth:`_border` when columns are first asked for (a design that is only looked
        #: at does not pay for it)
        self._border_parts = (*prob.aux.border(prob, ne), ne.aux.Pg) if self.na else None
        self.Gc = self.Gp = self.Faa = None

    def _border(self) -> None:
        """G = A⁻¹B (images ``Gc`` (m, 6, na), points ``Gp`` (p, 3, na)) and F̃⁻¹ ``Faa``."""
        if self.Faa is not None or self._border_parts is None:
            return
        E, F, Pg = self._border_parts  # Pg (p, 3, na) by column
        Y = self.solve(E).reshape(self.m, 6, -1)
        self.Faa = np.linalg.inv(F - E.reshape(-1, self.na).T @ Y.reshape(-1, self.na))
        Gp = self.Vinv @ Pg + self._back(Y)
        self.Gc, self.Gp = Y, Gp[self.pcol]
        self._border_parts = None

    def precision(self) -> SimpleNamespace:
        """The bundle's precision of the base design from this factor
        (:func:`orientviz.bundle.precision.bundle_precision`: cofactor blocks of points and
        stations, redundancy numbers, ``redundancy_xy``, ``ray_gains``; a-priori σ0 = 1)."""
        st, rw, Je, Jp, ne = self._lin
        res = SimpleNamespace(residuals=0.0, sigma_obs=1.0, cofactor_groups={})
        bundle_precision(res, self.prob, st, rw, Je, Jp, (ne, self.fac, Je, Jp))
        self._lin = None  # the normal equations are not needed any more
        return res

    def solve(self, rhs: F64) -> F64:
        """S⁻¹ rhs (6m, k): with a banded factor and many columns by block products on
        views of the factor (:class:`orientviz.bundle.precision.BandSolver`, BLAS level
        3), else by the factor's solve."""
        fac = self.fac
        if fac.kind != "banded" or rhs.shape[1] < 4:
            return fac.solve(rhs)
        if self._band is None:
            self._band = BandSolver(fac.data)
        p = fac.structure.scalar_perm
        X = self._band.solve(rhs[p])
        out = np.empty_like(X)
        out[p] = X
        return out

    def _back(self, Cc: F64) -> F64:
        """−Σ_b T_bᵀ Cc[i_b] per point (columns of the problem), shape (p, 3, k)."""
        prob, T = self.prob, self.T
        S = prob.reduced
        vo = prob.obs.var_rays
        oi = prob.obs.image
        return -np.add.reduceat(T[vo].transpose(0, 2, 1) @ Cc[oi[vo]], S.pt_starts, axis=0)

    def columns(self, images: I64, points: I64, border: I64 | None = None) -> tuple[F64, F64, F64]:
        """Q0 at the coordinates of ``images`` (6 each), ``points`` (3 each) and the
        border's offsets ``border`` (1 each), in that order.

        Returns
        -------
        Cc : ndarray, shape (m, 6, k)
            Rows of the images (base order), k = 6·len(images) + 3·len(points) + len(border).
        Cp : ndarray, shape (p, 3, k)
            Rows of the points (base point index).
        Cg : ndarray, shape (na, k)
            Rows of the border's offsets (na = 0 without auxiliary data).
        """
        border = np.zeros(0, np.int64) if border is None else np.asarray(border, np.int64)
        keys = [("i", int(i)) for i in images] + [("p", int(j)) for j in points]
        keys += [("g", int(g)) for g in border]
        todo = [k for k in keys if k not in self._cache]
        if todo:
            self._compute(todo)
        parts = [self._cache[k] for k in keys]
        if not parts:
            return np.zeros((self.m, 6, 0)), np.zeros((self.p, 3, 0)), np.zeros((self.na, 0))
        out = tuple(np.concatenate([c[i] for c in parts], axis=-1) for i in range(3))
        if len(self._cache) > 400:  # bound the memory (each entry ~ (6m + 3p)·6 floats)
            self._cache.clear()
        return out

    def _compute(self, keys: list[tuple[str, int]]) -> None:
        prob, T, m = self.prob, self.T, self.m
        self._border()
        border = [j for kind, j in keys if kind == "g"]
        keys_x = [key for key in keys if key[0] != "g"]
        widths = [6 if kind == "i" else 3 for kind, _ in keys_x]
        starts = np.concatenate([[0], np.cumsum(widths)]).astype(int)
        k = int(starts[-1])
        rhs = np.zeros((m, 6, k))
        own = []  # (column of the problem, start) of the point columns
        for (kind, j), s in zip(keys_x, starts[:-1]):
            if kind == "i":
                rhs[j, :, s : s + 6] = np.eye(6)
            else:
                col = self.pcol[j]
                rays = np.flatnonzero(prob.obs.column == col)
                np.add.at(rhs[:, :, s : s + 3], prob.obs.image[rays], -T[rays])
                own.append((col, s))
        Cc = self.solve(rhs.reshape(6 * m, k)).reshape(m, 6, k)
        Cp = self._back(Cc)
        for col, s in own:
            Cp[col, :, s : s + 3] += self.Vinv[col]
        Cp = Cp[self.pcol]
        Cg = np.zeros((self.na, k))
        if self.na:  # the border: + G F̃⁻¹ G_Ωᵀ, and its own rows −F̃⁻¹ G_Ωᵀ
            GO = np.concatenate(
                [self.Gc[j] if kind == "i" else self.Gp[j] for kind, j in keys_x], axis=0
            ).reshape(k, self.na)
            B = self.Faa @ GO.T
            Cc += self.Gc @ B
            Cp += self.Gp @ B
            Cg = -B
        for key, s, w in zip(keys_x, starts[:-1], widths):
            self._cache[key] = (Cc[:, :, s : s + w], Cp[:, :, s : s + w], Cg[:, s : s + w])
        for g in border:  # an offset's column: −G F̃⁻¹ e_g, F̃⁻¹ e_g
            f = self.Faa[:, [g]]
            self._cache[("g", g)] = (-(self.Gc @ f), -(self.Gp @ f), f.copy())
