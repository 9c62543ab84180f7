"""A design that answers each change at once: low-rank updates of the design's cofactors.

Every change the studio makes to a design block is a change of the normal equations
N = Σ gᵀ d g by a few rows g with signed weights d:

* control of point j (weights P_j = diag(1/σ²), 1/m²) added, changed or removed: the
  three unit rows of the point with d = ΔP_j;
* images added: their rays (two rows P½J each, d = +1) and their GNSS prior; the new
  unknowns enter the base as separate slots with a provisional prior ω I (their cofactor
  block ω⁻¹ I, no coupling), which the same step takes away (d = −ω);
* images removed: their rays (d = −1) and a provisional prior ω I on their unknowns
  (d = +ω), which leaves them decoupled (cofactor ω⁻¹ I, masked from then on); the same
  for the points left with fewer than two rays (:func:`orientviz.design.remove_images`);
* with auxiliary data (statoscope, APR, GNSS with strip offsets g): the readings that
  come or go with the images, each a row √w·(unit on its coordinate + its offsets'
  coefficients); the offsets' border is part of the base columns and of every step.

With G the rows, D = diag(d) and Q the current cofactors, each step is one
Sherman-Morrison-Woodbury update

    Q' = Q − U M Uᵀ,   U = Q Gᵀ,   M = (I + D G U)⁻¹ D.

The current columns Q[:, Ω] at the step's coordinates Ω are the base design's
(:class:`orientviz.design._base.DesignBase`: one multi-column solve with its factor) less
the earlier steps' U_s M_s U_s[Ω]ᵀ. A step costs those columns and the update of the
shown quantities: the diagonal blocks of the point and station cofactors (Q_kk − U_k M
U_kᵀ) and per ray with h = P½ J U (2 × r) the 2 × 2 block P½ J Q Jᵀ P½ (loses h M hᵀ: the
redundancy numbers gain its diagonal) and the ray's gains K = Q Jᵀ P½ (lose U M hᵀ); a ray
added in the step starts from its own rows of G U and U. From these the reliability
(:func:`orientviz.bundle.ray_reliability`), ellipsoids, weak spots and summary follow
(:func:`orientviz.design._quality.quality_from_arrays`).

Every number equals a new :func:`orientviz.design.assess_block` of the changed design up
to rounding (``tests/design/test_live.py``, ``tests/design/test_live_structure.py``).
Changes of the plan (image σ, flight, overlaps) change all of N: :meth:`LiveDesign.rebuild`
forms and factors it again, as does a structural change whose step would need more than
``max_columns`` (:data:`MAX_COLUMNS`) columns, or that adds offsets (a new strip of a
design with auxiliary data). The algebra of the columns and the step is
:class:`orientviz.design._steps.WoodburySteps`.
"""

from __future__ import annotations

import copy
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..block import CONTROL, TIE, Block
from ..bundle import RayGains, ray_reliability
from ..bundle.model import collinearity_block
from ..bundle.problem import auxiliary_rows
from ..errors import InputError
from ._base import DesignBase
from ._extend import add_images, kept_after_removal
from ._extend import remove_images as _remove_images
from ._live_parts import (
    Change,
    _aux_rows,
    _capped,
    _check_connected,
    _check_rays,
    _Current,
    _weights,
    _with_aux_rows,
)
from ._quality import DesignQuality, quality_from_arrays
from ._steps import _NONE, WoodburySteps

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: After this many update steps the design is formed and factored again.
MAX_STEPS: int = 40
#: A structural change whose step needs more columns of Q than this is assessed anew.
MAX_COLUMNS: int = 400


class LiveDesign(WoodburySteps):
    """A design block whose quality follows each change at once.

    Parameters
    ----------
    block : Block
        A design block (:func:`orientviz.design.design_block`): planned geometry,
        error-free observations, weighted control.
    spec : dict
        Its geometry (needs ``base_m``).
    level, alpha0, beta0 : float
        Ellipsoid probability; test level and power of the reliability.
    auxiliary : list of Auxiliary, optional
        Statoscope / APR / GNSS rows with strip offsets (:func:`orientviz.design.design_auxiliary`).
    blas_threads : int or None
        BLAS threads while the design forms, factors and updates (:func:`orientviz.blas.blas_threads`;
        None: as the process runs them).

    Attributes
    ----------
    block : Block
        The current design (control as changed).
    changes : list of Change
        The control changes since the last :meth:`rebuild` or structural change, in
        order (:meth:`undo` takes the last back).
    history : list of str
        Every change in words, including those before a rebuild.
    """

    def __init__(
        self, block: Block, spec: dict[str, Any], *, level: float = 0.95,
        alpha0: float = 0.001, beta0: float = 0.80, auxiliary: list | None = None,
        blas_threads: int | None = 1,
    ) -> None:  # fmt: skip
        self.spec = spec
        self.blas_threads = blas_threads
        self.auxiliary = list(auxiliary or [])
        self.level, self.alpha0, self.beta0 = level, alpha0, beta0
        #: a structural step needing more columns of Q than this is assessed anew
        self.max_columns = MAX_COLUMNS
        self.history: list[str] = []
        self.rebuild(block.copy())

    # ------------------------------------------------------------------ the base design
    @_capped
    def rebuild(self, block: Block | None = None) -> DesignQuality:
        """Form and factor the normal equations of the current (or given) design again."""
        if block is not None:
            self.block = block
        b = self.block
        _check_connected(b)
        _check_rays(b)
        self._base = DesignBase(b, self.auxiliary)
        self.result = res = self._base.precision()
        m, p, n = b.n_images, b.n_points, b.n_observations
        self._img = np.arange(m)  # slot of each current image, point, ray
        self._pt = np.arange(p)
        self._obs = np.arange(n)
        self._omega = np.zeros((m, 6))  # provisional prior of the image slots
        self._ray_img = np.asarray(b.observations.image, np.int64).copy()
        self._ray_pt = np.asarray(b.observations.point, np.int64).copy()
        self._Jw = self._base.Jw
        self._cur = _Current(
            Qp=np.asarray(res.cofactor_groups["points"], float).copy(),
            Qe=np.asarray(res.cofactor_groups["exterior"], float).copy(),
            r=np.asarray(res.redundancy_numbers[: 2 * n]).reshape(n, 2).copy(),
            rxy=np.asarray(res.redundancy_xy, float).copy(),
            Ke=np.asarray(res.ray_gains.exterior, float).copy(),
            Kp=np.asarray(res.ray_gains.points, float).copy(),
        )
        self._w = _weights(b.points.sigma)  # by base point: the weights of the terms
        rows = self._base.prob.aux.rows if self.auxiliary else None
        self._aux_names = list(rows.names) if rows is not None else []
        #: the auxiliary rows by label (slots), or the base's rows until first asked for
        self._aux: dict | object = rows if rows is not None else {}
        #: the steps (U images by slot, U points by base point, U offsets, M)
        self._steps: list[tuple[F64, F64, F64, F64]] = []
        #: per control change: (weights, terms, quality, number of steps) before it
        self._saved: list[tuple[F64, _Current, DesignQuality, int]] = []
        self.changes: list[Change] = []
        q = self._assemble()
        self.base_quality = self._quality = q
        return q

    def columns(self, point: int) -> tuple[F64, F64]:
        """Q0 (the base design's cofactors) at the three columns of a base point:
        orientations (m, 6, 3), points (p, 3, 3) in the base block's order."""
        return self._base.columns(np.zeros(0, np.int64), np.array([point]))[:2]

    @_capped
    def current_columns(self, point: int) -> tuple[F64, F64]:
        """The current design's cofactors at the three columns of ``point`` (current
        index): orientations (m, 6, 3) and points (p, 3, 3) in the current order."""
        Cc, Cp, _ = self._columns(_NONE, self._pt[[point]])
        return Cc[self._img], Cp[self._pt]

    # ------------------------------------------------------------------ control changes
    @_capped
    def set_control(self, point: int, sigma_xyz: ArrayLike) -> DesignQuality:
        """Make ``point`` control with σ (m; NaN = coordinate not given, all NaN = tie).

        Returns the updated :class:`DesignQuality`.
        """
        s = np.asarray(sigma_xyz, float).reshape(3)
        if np.any(s[np.isfinite(s)] <= 0):
            raise InputError(f"sigma_xyz: a design weights its control, expected σ > 0, got {s}")
        before = tuple(float(v) for v in self.block.points.sigma[point])
        ch = Change(int(point), tuple(float(v) for v in s), before)
        self._saved.append((self._w, self._cur, self._quality, len(self._steps)))
        self._apply_roles(ch.point, s)
        self.changes.append(ch)
        self.history.append(ch.describe(self.block.points.ids))
        if len(self._steps) >= MAX_STEPS:
            self.history.append("(normal equations formed and factored again)")
            return self.rebuild()
        w = self._w.copy()
        j = int(self._pt[point])
        w[j] = _weights(s)
        if np.any(w[j] != self._w[j]):
            d = (w[j] - self._w[j]).astype(float)
            self._step(_NONE, np.array([j]), np.eye(3), d)
            self._w = w
            self._quality = self._assemble()
        return self._quality

    def add_control(self, point: int, sigma: float = 0.02) -> DesignQuality:
        """Make ``point`` XYZ control with σ ``sigma`` (m) in each coordinate."""
        return self.set_control(point, (sigma, sigma, sigma))

    def remove_control(self, point: int) -> DesignQuality:
        """Make ``point`` a tie point."""
        return self.set_control(point, (np.nan, np.nan, np.nan))

    def undo(self) -> DesignQuality:
        """Take the last control change since the last :meth:`rebuild` back."""
        if not self.changes:
            raise InputError("nothing to undo since the last rebuild")
        ch = self.changes.pop()
        self._apply_roles(ch.point, np.asarray(ch.before))
        self.history.append(f"undo: {ch.describe(self.block.points.ids)}")
        self._w, self._cur, self._quality, n = self._saved.pop()
        del self._steps[n:]
        return self._quality

    def _apply_roles(self, point: int, s: F64) -> None:
        P = self.block.points
        given = np.isfinite(s)
        P.sigma[point] = np.where(given, s, np.nan)
        P.xyz_known[point] = np.where(given, P.xyz[point], np.nan)
        P.role[point] = CONTROL if given.any() else TIE

    # ------------------------------------------------------------------ structural changes
    def _aux_change(self, b: Block, auxiliary, img_slot, pt_slot):
        """The auxiliary rows of the changed design ``b``: (its data, its rows by label,
        rows removed, rows added), or its data and None when its offsets differ (then the
        design is assessed anew). ``auxiliary``: the new design's data or a function of
        the new block giving them (:func:`orientviz.design.design_auxiliary`)."""
        if not self.auxiliary:
            return [], {}, [], []
        if auxiliary is None:
            raise InputError(
                "images of a design with auxiliary data: their rows follow the images — "
                "pass auxiliary= (the new design's data, or a function of the new block)"
            )
        new_aux = list(auxiliary(b) if callable(auxiliary) else auxiliary)
        rows = auxiliary_rows(new_aux, b)
        if list(rows.names) != self._aux_names:
            return new_aux, None, [], []
        now = _aux_rows(rows, img_slot, pt_slot)
        if not isinstance(self._aux, dict):  # the base's rows: slots are indices
            self._aux = _aux_rows(self._aux, lambda i: i, lambda j: j)
        removed = [v for key, v in self._aux.items() if now.get(key) != v]
        added = [v for key, v in now.items() if self._aux.get(key) != v]
        return new_aux, now, removed, added

    def _fresh(self, block: Block, label: str, auxiliary=None) -> LiveDesign:
        """A new live design of ``block`` (a new block of the structural edit, not shared
        with this design's: formed and factored anew, no copy)."""
        new = copy.copy(self)
        if auxiliary is not None:
            new.auxiliary = auxiliary
        new.history = self.history + [label, "(normal equations formed and factored again)"]
        new.rebuild(block)
        return new

    def _derived(self, block: Block, label: str, aux: list, rows: dict) -> LiveDesign:
        """A copy for ``block`` sharing the base and the steps so far (the bundle's rule
        for a block in pieces applies first: the update would give each piece its own
        numbers, the bundle refuses it)."""
        _check_connected(block)
        new = copy.copy(self)
        new.block = block  # new arrays from the structural edit: not shared
        new._steps = list(self._steps)
        new._saved, new.changes = [], []
        new.history = self.history + [label]
        new.auxiliary, new._aux = aux, rows
        return new

    @_capped
    def add_images(
        self, X0: ArrayLike, angles: ArrayLike, *, strip: ArrayLike | int | None = None,
        ids: list[str] | None = None, auxiliary=None,
    ) -> LiveDesign:  # fmt: skip
        """A new live design with images added (:func:`orientviz.design.add_images`).

        The current design stays as it is (undo: keep using it). Updated by one step
        (rank 2·rays + 6·images) when the step needs at most :data:`MAX_COLUMNS` columns
        of Q and the auxiliary data keep their offsets; otherwise assessed anew.
        ``auxiliary``: for a design with auxiliary data, the new design's data or a
        function of the new block giving them (their rows follow the images:
        :func:`orientviz.design.design_auxiliary`); the rows that change are rows of the
        step.

        Raises
        ------
        InputError
            For a design with auxiliary data without ``auxiliary``.
        NotDeterminableError
            If the changed design is not determinable.
        """
        b = add_images(self.block, X0, angles, strip=strip, ids=ids)
        m, n = self.block.n_images, self.block.n_observations
        k = b.n_images - m
        label = f"{k} image(s) added"
        O = b.observations
        new_obs = np.arange(n, b.n_observations)
        pts_new = np.unique(O.point[new_obs])
        M0, R0 = self._omega.shape[0], self._Jw.shape[0]
        slots = M0 + np.arange(k)
        img_slot = np.r_[self._img, slots]
        aux, now, gone_a, new_a = self._aux_change(b, auxiliary, img_slot.__getitem__,
                                                   self._pt.__getitem__)  # fmt: skip
        wide = 6 * k + 3 * pts_new.size + 3 * (len(gone_a) + len(new_a))
        if now is None or wide > self.max_columns or len(self._steps) >= MAX_STEPS:
            return self._fresh(b, label, aux)
        new = self._derived(b, label, aux, now)
        rays = R0 + np.arange(new_obs.size)
        # the new rays' weighted Jacobians
        cam = b.cameras
        I = b.images
        _, Je, Jp = collinearity_block(
            I.X0, I.angles, cam.c[I.camera], cam.x0[I.camera], cam.y0[I.camera],
            O.image[new_obs], b.points.xyz[O.point[new_obs]], b.sequence,
        )  # fmt: skip
        sw = 1.0 / np.asarray(O.sigma[new_obs], float)[:, :, None]
        Jn = np.concatenate([Je * sw, Jp * sw], axis=2)  # (nn, 2, 9)
        ray_img = slots[O.image[new_obs] - m]
        ray_pt = self._pt[O.point[new_obs]]
        # provisional prior ω (the new rays' diagonal + GNSS) and the GNSS weights
        gw = np.zeros((k, 6))
        xs = np.asarray(I.X0_sigma[m:], float)
        gw[:, :3] = np.where(np.isfinite(xs) & (xs > 0), 1.0 / np.where(xs > 0, xs, 1.0) ** 2, 0.0)
        omega = gw.copy()
        np.add.at(omega, O.image[new_obs] - m, np.einsum("nki,nki->ni", Jn[:, :, :6], Jn[:, :, :6]))
        new._omega = np.vstack([self._omega, omega])
        new._Jw = np.concatenate([self._Jw, Jn])
        new._ray_img = np.r_[self._ray_img, ray_img]
        new._ray_pt = np.r_[self._ray_pt, ray_pt]
        c = self._cur
        nn = rays.size
        new._cur = _Current(
            Qp=c.Qp, Qe=np.concatenate([c.Qe, np.stack([np.diag(1.0 / o) for o in omega])]),
            r=np.vstack([c.r, np.zeros((nn, 2))]), rxy=np.r_[c.rxy, np.zeros(nn)],
            Ke=np.concatenate([c.Ke, np.zeros((nn, 6, 2))]),
            Kp=np.concatenate([c.Kp, np.zeros((nn, 3, 2))]),
        )  # fmt: skip
        new._img = np.r_[self._img, slots]
        new._obs = np.r_[self._obs, rays]
        # the rows: new rays (d = +1), then the priors of the new images (d = GNSS − ω)
        pos_i = {int(s): t for t, s in enumerate(slots)}
        pts_s = self._pt[pts_new]
        pos_p = {int(j): t for t, j in enumerate(pts_s)}
        kc = 6 * k + 3 * pts_new.size
        G = np.zeros((2 * nn + 6 * k, kc))
        for a in range(nn):
            ci0 = 6 * pos_i[int(ray_img[a])]
            cp0 = 6 * k + 3 * pos_p[int(ray_pt[a])]
            G[2 * a : 2 * a + 2, ci0 : ci0 + 6] = Jn[a, :, :6]
            G[2 * a : 2 * a + 2, cp0 : cp0 + 3] = Jn[a, :, 6:]
        G[2 * nn :, : 6 * k] = np.eye(6 * k)
        d = np.r_[np.ones(2 * nn), (gw - omega).reshape(-1)]
        alive = np.zeros(new._Jw.shape[0], bool)
        alive[new._obs] = True
        imgs, pts, gs, G, d = _with_aux_rows(slots, pts_s, G, d, gone_a, new_a)
        new._step(imgs, pts, G, d, new_rays=rays, alive=alive, gs=gs)
        new._quality = new.base_quality = new._assemble()
        return new

    @_capped
    def remove_images(
        self, images: ArrayLike, label: str | None = None, *, auxiliary=None
    ) -> LiveDesign:
        """A new live design without some images (:func:`orientviz.design.remove_images`:
        points left with fewer than 2 rays go too). The current design stays as it is.
        Updated by one step when possible (see :meth:`add_images`, also for
        ``auxiliary``), else assessed anew.
        """
        drop_i = np.asarray(images, np.int64).reshape(-1)
        b = _remove_images(self.block, drop_i)
        label = label or f"{drop_i.size} image(s) removed"
        keep_o, keep_p = kept_after_removal(self.block, drop_i)
        O = self.block.observations
        gone = np.flatnonzero(~keep_o)
        gone_p = np.flatnonzero(~keep_p)
        touched = np.unique(O.point[gone])
        other_imgs = np.setdiff1d(np.unique(O.image[gone]), drop_i)
        imgs_cur = np.r_[drop_i, other_imgs]
        kc = 6 * imgs_cur.size + 3 * touched.size
        keep_i = np.ones(self.block.n_images, bool)
        keep_i[drop_i] = False
        aux, now, gone_a, new_a = self._aux_change(
            b, auxiliary, self._img[keep_i].__getitem__, self._pt[keep_p].__getitem__
        )
        wide = kc + 3 * (len(gone_a) + len(new_a))
        if now is None or wide > self.max_columns or len(self._steps) >= MAX_STEPS:
            return self._fresh(b, label, aux)
        new = self._derived(b, label, aux, now)
        imgs = self._img[imgs_cur]
        pts = self._pt[touched]
        rays = self._obs[gone]
        pos_i = {int(s): t for t, s in enumerate(imgs)}
        pos_p = {int(j): t for t, j in enumerate(pts)}
        Jg = self._Jw[rays]
        # provisional priors ω: the diagonal of the normal block of the removed images
        # (their rays) and of the dropped points (their rays and control weight)
        om_i = np.zeros((drop_i.size, 6))
        for t, i in enumerate(drop_i):
            Jr = self._Jw[self._obs[O.image == i]][:, :, :6]
            om_i[t] = np.einsum("nki,nki->i", Jr, Jr)
        om_p = np.zeros((gone_p.size, 3))
        for t, j in enumerate(gone_p):
            Jr = self._Jw[self._obs[O.point == j]][:, :, 6:]
            om_p[t] = np.einsum("nki,nki->i", Jr, Jr) + self._w[self._pt[j]]
        nr = rays.size
        G = np.zeros((6 * drop_i.size + 3 * gone_p.size + 2 * nr, kc))
        G[: 6 * drop_i.size, : 6 * drop_i.size] = np.eye(6 * drop_i.size)
        r0 = 6 * drop_i.size
        for t, j in enumerate(gone_p):
            c0 = 6 * imgs.size + 3 * pos_p[int(self._pt[j])]
            G[r0 + 3 * t : r0 + 3 * t + 3, c0 : c0 + 3] = np.eye(3)
        r0 += 3 * gone_p.size
        for a in range(nr):
            ci0 = 6 * pos_i[int(self._ray_img[rays[a]])]
            cp0 = 6 * imgs.size + 3 * pos_p[int(self._ray_pt[rays[a]])]
            G[r0 + 2 * a : r0 + 2 * a + 2, ci0 : ci0 + 6] = Jg[a, :, :6]
            G[r0 + 2 * a : r0 + 2 * a + 2, cp0 : cp0 + 3] = Jg[a, :, 6:]
        d = np.r_[om_i.reshape(-1), om_p.reshape(-1), -np.ones(2 * nr)]
        new._img = self._img[keep_i]
        new._pt = self._pt[keep_p]
        new._obs = self._obs[keep_o]
        alive = np.zeros(self._Jw.shape[0], bool)
        alive[new._obs] = True
        imgs, pts, gs, G, d = _with_aux_rows(imgs, pts, G, d, gone_a, new_a)
        new._step(imgs, pts, G, d, alive=alive, gs=gs)
        new._quality = new.base_quality = new._assemble()
        return new

    # ------------------------------------------------------------------ the quality
    def quality(self) -> DesignQuality:
        """The quality of the current design."""
        return self._quality

    def _assemble(self) -> DesignQuality:
        """Reliability, ellipsoids, weak spots and summary from the current terms."""
        b, cur = self.block, self._cur
        o = self._obs
        adj = SimpleNamespace(
            redundancy_numbers=cur.r[o].reshape(-1), redundancy_xy=cur.rxy[o],
            ray_gains=RayGains(cur.Ke[o], cur.Kp[o]),
        )  # fmt: skip
        rel = ray_reliability(adj, b, alpha0=self.alpha0, beta0=self.beta0)
        return quality_from_arrays(
            b, cur.Qp[self._pt], cur.Qe[self._img], cur.r[o], rel, float(self.spec["base_m"]),
            self.level,
        )  # fmt: skip
