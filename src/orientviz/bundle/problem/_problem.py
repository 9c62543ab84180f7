"""The bundle problem: its parts, its linearisation and its step.

:class:`BundleProblem` holds what is constant during a bundle adjustment, composed of
the parts in :mod:`orientviz.bundle.problem._parts`. For an iterate
(:class:`~orientviz.bundle.problem._state.BundleState`) it computes the weighted misclosures and
Jacobians (:meth:`BundleProblem.residuals`), vᵀPv (:meth:`~BundleProblem.cost`), the
normal equations with the points eliminated by the Schur complement
(:meth:`~BundleProblem.normal` → :class:`~orientviz.bundle.reduced._normal.NormalEquations`),
the step (:meth:`~BundleProblem.solve`, bordered by additional parameters and auxiliary
offsets) and the next iterate (:meth:`~BundleProblem.apply`). The iteration itself is
the engine's (:func:`orientviz.adjust.engine.iterate`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ...block import Block
from .._options import BundleOptions
from ..model._kernel import RayProjection, ray_jacobians
from ..model._local_rotation import apply_local
from ..reduced import (
    ImageGram,
    NormalEquations,
    ReducedStructure,
    back_substitute,
    dense_schur,
    factor_reduced,
    schur_blocks,
    schur_buffer_size,
)
from ._ap_normal import ap_normal, point_ap_term
from ._border import solve_border
from ._camera_blocks import camera_blocks_apply, camera_normal, camera_solve
from ._checks import PointSetup
from ._damping import scene_centres
from ._eliminate import eliminate_points, image_blocks, work_array
from ._names import ParameterNames
from ._parts import (
    AdditionalBlock,
    additional_block,
    exterior_block,
    image_observations,
    interior_orientation,
    point_block,
    with_var_rays,
)
from ._run import BundleRun
from ._state import BundleState, wrap

if TYPE_CHECKING:  # annotations only
    from ._auxiliary import BundleAuxiliary

F64 = NDArray[np.float64]


class BundleProblem:
    """One bundle adjustment, composed of small parts (constant over the iterations).

    What a run writes lives in :attr:`run` (a :class:`~orientviz.bundle.problem._run.BundleRun`),
    never in the problem's other attributes.

    Attributes
    ----------
    block : Block
        The block (approximate values, observations).
    setup : PointSetup
        How each point enters (fixed, unknown, weighted).
    obs : ImageObservations
        The rays that enter, in point order.
    interior : InteriorOrientation
        c, x0, y0 per image (mm).
    exterior : ExteriorBlock
        Observed projection centres/attitudes (weights, values).
    points : PointBlock
        Point unknowns and their coordinate pseudo-observations.
    ap0 : AdditionalBlock
        Self-calibration parameters (empty: ``q == 0``), design at the approximations;
        :attr:`ap` is the run's (a lens model's design moves with the iterate).
    aux : BundleAuxiliary or None
        GNSS / statoscope / APR rows and their offsets/drifts.
    reduced : ReducedStructure
        Structure, ordering and solver of the reduced camera system.
    run : BundleRun
        The state of the current run (the border's memory, the kept projection, the
        additional parameters' current design).
    options : BundleOptions
        The solver's knobs (the reduced system's solver, tolerances of the border's
        solve, the precision's limits).
    n_eq, n_unknowns, redundancy : int
        Counts of equations (observations and pseudo-observations) and unknowns.

    The iterate is a :class:`~orientviz.bundle.problem._state.BundleState`; the methods take it
    as an argument: :meth:`residuals`, :meth:`cost`, :meth:`normal` (→
    :class:`NormalEquations`), :meth:`solve`, :meth:`apply`.
    """

    def __init__(
        self,
        block: Block,
        setup: PointSetup,
        *,
        additional=None,
        ap_group=None,
        ap_sigma=None,
        auxiliary: list | None = None,
        options: BundleOptions | None = None,
    ) -> None:
        self.block = block
        self.setup = setup
        self.options = BundleOptions() if options is None else options
        self.points = point_block(block, setup)
        obs = image_observations(block, setup, self.points.column)
        self.reduced = ReducedStructure(
            obs.image,
            obs.column,
            block.n_images,
            self.points.n,
            solver=self.options.solver,
            positions=block.images.X0,
            options=self.options.reduced,
        )
        self.obs = with_var_rays(obs, self.reduced)
        #: "trust" damping: the images' blocks are damped in the frame of their scene (._damping)
        self.scene_centres = (
            scene_centres(
                obs.image, obs.point, block.points.xyz, block.images.X0, self.reduced.cam_order
            )
            if self.options.damping == "trust"
            else None
        )
        r = self.reduced
        #: the images' Gram matrices (U and the reduced rhs in normal())
        self.image_gram = ImageGram(
            r.cam_order,
            r.cam_starts,
            r.cam_present,
            r.n_cam,
            obs.n,
            self.options.reduced.gram_pad_max,
        )
        self.interior = interior_orientation(block)
        self.exterior = exterior_block(block)
        #: the additional parameters with their design at the approximations
        self.ap0 = additional_block(
            block, self.obs, self.points, self.reduced, additional, ap_group, ap_sigma
        )
        self.run = BundleRun(self.ap0)
        self.aux: BundleAuxiliary | None = None
        if auxiliary:
            from ._auxiliary import BundleAuxiliary, auxiliary_rows  # only with auxiliary data

            self.aux = BundleAuxiliary(auxiliary_rows(auxiliary, block), self.points.column)
        n_pseudo = int(
            (self.points.prior_w > 0).sum()
            + (self.exterior.X0_w > 0).sum()
            + (self.exterior.angles_w > 0).sum()
        )
        n_pseudo += int((self.ap.w > 0).sum()) if self.q else 0
        self.n_eq = 2 * self.obs.n + n_pseudo + (self.aux.rows.n if self.aux else 0)
        self.n_unknowns = 6 * self.m + 3 * self.points.n + self.q + self.na
        self.redundancy = self.n_eq - self.n_unknowns
        #: per-image cameras inside the images' blocks of the reduced system (._camera_blocks)
        self.camera_blocks = camera_blocks_apply(self)

    def new_run(self) -> BundleRun:
        """Start a fresh :class:`BundleRun` (the problem may be adjusted again)."""
        self.run = BundleRun(self.ap0)
        return self.run

    @property
    def ap(self) -> AdditionalBlock:
        """The additional parameters, their design at the last evaluation (``run.ap``)."""
        return self.run.ap

    @property
    def m(self) -> int:
        """Number of images."""
        return self.block.n_images

    @property
    def q(self) -> int:
        """Number of additional parameters."""
        return self.ap.q

    @property
    def na(self) -> int:
        """Number of auxiliary offsets/drifts."""
        return self.aux.n_global if self.aux is not None else 0

    # ----------------------------------------------------------------- model
    def residuals(self, st: BundleState, jac: bool, local: bool = False, keep: bool = False):
        """Weighted misclosures l − f (n, 2)·(1/σ), with Jacobians if ``jac``; ``local``:
        by rotations of the image frame (:mod:`orientviz.bundle.model._local_rotation`).

        ``keep`` (without ``jac``): the projection is kept until the next call, which
        forms the Jacobians at the same ``st`` from it instead of projecting again.
        """
        if self.ap.lens is not None:
            return self._lens_residuals(st, jac)
        run = self.run
        kept, run.projection = run.projection, None
        seq = self.block.sequence
        if kept is not None and kept[0] is st:
            proj = kept[1]
        else:
            io = self.interior
            xyz = np.take(st.xyz, self.obs.point, axis=0)
            tab, run.image_table = run.image_table, None
            table = tab[2] if tab is not None and tab[0] is st.X0 and tab[1] is st.angles else None
            proj = RayProjection(
                st.X0, st.angles, io.c, io.x0, io.y0, self.obs.image, xyz, seq, table
            )
        f = proj.xy
        run.projected = (st, f)
        if jac:
            Je, Jp = ray_jacobians(proj, st.angles, seq, local)
        else:
            Je = Jp = None
            if keep:
                run.projection = (st, proj)
        if self.q:
            f = f + (self.ap.A_csr @ st.ap).reshape(-1, 2)
        return (self.obs.xy - f) * self.obs.weight, Je, Jp

    def reweighted(self, st: BundleState) -> F64:
        """The misclosures at ``st`` weighted by the current ray weights, as
        :meth:`residuals` without ``jac`` forms them — from the last evaluation's projection
        when it was of ``st`` (a pinhole; the same numbers: no second projection)."""
        done = self.run.projected
        if self.ap.lens is not None or done is None or done[0] is not st:
            return self.residuals(st, jac=False)[0]
        f = done[1]
        if self.q:
            f = f + (self.ap.A_csr @ st.ap).reshape(-1, 2)
        return (self.obs.xy - f) * self.obs.weight

    def _lens_residuals(self, st: BundleState, jac: bool):
        """Misclosures and Jacobians through the camera model (:mod:`._lens`); with
        ``jac`` the design of its parameters at ``st`` becomes the problem's.

        The normalised projection of a call without ``jac`` is kept until the next call:
        the Jacobians at the same ``st`` (a trial point accepted) are formed from it, the
        rays are not projected again (the same values as :func:`normalised_block`)."""
        obs, lens, run = self.obs, self.ap.lens, self.run
        kept, run.projection = run.projection, None
        seq = self.block.sequence
        if kept is not None and kept[0] is st:
            proj = kept[1]
        else:
            one, zero = np.ones(self.m), np.zeros(self.m)
            xyz = st.xyz[obs.point]
            proj = RayProjection(st.X0, st.angles, one, zero, zero, obs.image, xyz, seq)
        nrm = proj.xy
        if not jac:
            run.projection = (st, proj)
        f, M, A = lens.evaluate(st.ap, self.ap.group[obs.image], nrm, obs.xy, jac)
        Je = Jp = None
        if jac:  # the pinhole's Jacobians mapped through the camera model's
            Je, Jp = ray_jacobians(proj, st.angles, seq, M=M)
            if self.q:
                self.run.ap = self.ap.with_design(A, obs.weight)
                self.run.design_at = st
        return (obs.xy - f) * obs.weight, Je, Jp

    def residuals_of_rays(self, st: BundleState, rays, rw: F64, Je: F64, Jp: F64):
        """:meth:`residuals` ``(st, jac=True)`` where ``rw, Je, Jp`` are that evaluation at a
        state that differs from ``st`` only in points seen by ``rays`` alone: those rays are
        evaluated again, the others' rows taken over (new arrays); with a camera model its
        design becomes the one at ``st`` too. Each ray's numbers are its own arithmetic, so
        they are a full evaluation's at ``st``."""
        obs, seq, run = self.obs, self.block.sequence, self.run
        run.projection = None
        img, xyz, xy = obs.image[rays], st.xyz[obs.point[rays]], obs.xy[rays]
        if self.ap.lens is not None:
            one, zero = np.ones(self.m), np.zeros(self.m)
            proj = RayProjection(st.X0, st.angles, one, zero, zero, img, xyz, seq)
            f, M, A = self.ap.lens.evaluate(st.ap, self.ap.group[img], proj.xy, xy, True)
            je, jp = ray_jacobians(proj, st.angles, seq, M=M)
            if self.q:
                design = self.ap.A.copy()
                design[rays] = A
                run.ap = self.ap.with_design(design, obs.weight)
                run.design_at = st
        else:
            io = self.interior
            proj = RayProjection(st.X0, st.angles, io.c, io.x0, io.y0, img, xyz, seq)
            je, jp = ray_jacobians(proj, st.angles, seq)
            f = proj.xy
            if self.q:
                f = f + (self.ap.A_csr @ st.ap).reshape(-1, 2)[rays]
        rw, Je, Jp = rw.copy(), Je.copy(), Jp.copy()
        rw[rays], Je[rays], Jp[rays] = (xy - f) * obs.weight[rays], je, jp
        return rw, Je, Jp

    def design_at(self, st: BundleState) -> None:
        """Make the camera model's design the one at ``st`` (no-op for linear sets)."""
        if self.ap.lens is not None and self.q and self.run.design_at is not st:
            self._lens_residuals(st, True)

    def cost(self, st: BundleState, rw: F64) -> float:
        c = float(np.sum(rw**2))
        d = self.points.prior_obs - np.take(st.xyz, self.points.unknown, axis=0)
        c += float(np.sum(self.points.prior_w * d**2))
        c += float(np.sum(self.exterior.X0_w * (self.exterior.X0_obs - st.X0) ** 2))
        c += float(np.sum(self.exterior.angles_w * wrap(self.exterior.angles_obs - st.angles) ** 2))
        if self.q:
            c += float(np.sum(self.ap.w * st.ap**2))
        if self.aux:
            c += self.aux.cost(st.X0, st.xyz, st.g)
        return c

    # ----------------------------------------------------------------- normal equations
    def normal(
        self, st: BundleState, rw: F64, Je: F64, Jp: F64, lam: float = 0.0, hold: bool = False
    ) -> NormalEquations:
        """Blocks of the normal equations and the Schur complement (see bundle.reduced).

        ``hold``: a step's system — a point whose block V is numerically singular is held
        along its weak directions (``ne.held``; :func:`~orientviz.bundle.reduced.inv3_held`)."""
        S = self.reduced
        self.design_at(st)
        if self.camera_blocks and not self.run.border.hold:
            return camera_normal(self, st, rw, Je, Jp, lam, hold)
        sw = self.obs.weight[:, :, None]
        bd = self.run.border
        # with a border, the work arrays are kept between iterations (the loop keeps no
        # normal equations of such a bundle past the next formation: no chord steps, no
        # linearisation kept for the precision, ..loop._steps): arrays of a few MB formed
        # anew in every iteration cost their page faults again
        ws = S.tracks.work if self.q and not bd.hold else None
        # [P½J_e | r'] per ray (r': ._eliminate) and a zero row: the images' Gram matrices
        n = Je.shape[0]
        Jz = np.empty((n + 1, 2, 7))
        Jz[n] = 0.0
        Jew = np.multiply(Je, sw, out=Jz[:n, :, :6])
        Jpw = Jp * sw
        # E formed here (not held, not reused): its own-group blocks read the rays sorted
        # by image (._ap_normal)
        border_e = self.q and not bd.hold and not (bd.reuse and bd.border is not None)
        rays = [] if border_e and not self.ap.structure.batched else None
        Wr, V, Vinv, Tr, bp, diagV, G, held = eliminate_points(
            self, st, Jz, Jpw, rw, lam, ws, rays, hold
        )
        del Jz
        if rays:  # ... as the images' Gram matrices had them: not J_e again
            rays, Jew = rays[0], None
        if not (self.q and not self.run.border.hold):  # the weighted Jacobians: border only
            del Jew, Jpw  # (frees them before S is formed: the peak of a large block)
        U, red, diagU = image_blocks(self, st, G, lam)
        tg = S.tracks
        r = tg.rays
        out = NormalEquations(
            blocks=None,
            rhs=red.reshape(-1),
            Vinv=Vinv,
            Wr=Wr,
            Tr=Tr,
            rays=r,
            n_obs=Je.shape[0],
            bp=bp,
            diagU=diagU,
            diagV=diagV,
            held=held,
        )
        if self.q:  # (before S: the rays sorted by image are freed first)
            if self.run.border.hold:
                out.diagF = np.ones(self.q)
            else:
                border = self.run.border.border if self.run.border.reuse else None
                out.ap = ap_normal(self, st, rw, Jew, Jpw, out.T, Vinv, bp, lam, border, rays)
                out.ap.reused = border is not None
                out.diagF = np.diag(out.ap.F0).copy()
                self.run.border.border = (out.ap.E_border, out.ap.F0)
                del Jew, Jpw, rays
        if S.formation == "dense":
            out.blocks, out.S = dense_schur(S, U, Wr, V, held)
        else:
            buf = work_array(ws, "products", (schur_buffer_size(tg),))
            out.blocks = schur_blocks(S, U, Tr, Wr, buf)
        if self.aux:
            self.aux.normal(self, st, out, lam)
        return out

    def chord_normal(
        self,
        st: BundleState,
        rw: F64,
        Je: F64,
        Jp: F64,
        ne: NormalEquations,
        rot: F64 | None = None,
    ) -> NormalEquations:
        """The right-hand sides at ``st`` with the matrix of an earlier linearisation.

        For a *chord* step dx = N(x_old)⁻¹ g(x): the gradient g = Jᵀ P (l − f) at
        ``st`` (its image and point parts, the points eliminated with ``ne``'s T), and
        ``ne``'s point blocks, couplings and diagonals for the back-substitution and the
        stopping rule. Plain bundles only (no border, no auxiliary rows); undamped.

        ``rot`` (m, 3, 3): ``ne`` is of rotations δ of the image frames, the Jacobian of
        ω, φ, κ with J_θ = J_δ·rot (:func:`~orientviz.bundle.model._local_rotation.angle_map`):
        the angle rows of the images' gradient become rot⁻ᵀ g_θ (the system is then in δ,
        its solution δ = rot·dθ), the angle part of ``diagU`` the diagonal in ω, φ, κ at
        ``st``.
        """
        S = self.reduced
        tg = S.tracks
        rp = rw * self.obs.weight  # P (l − f) = P½ · P½ (l − f)
        gc = np.einsum("nki,nk->ni", Je, rp)
        bc = np.zeros((self.m, 6))
        bc[S.cam_present] = np.add.reduceat(np.take(gc, S.cam_order, axis=0), S.cam_starts)
        bc[:, :3] += self.exterior.X0_w * (self.exterior.X0_obs - st.X0)
        bc[:, 3:] += self.exterior.angles_w * wrap(self.exterior.angles_obs - st.angles)
        diagU = ne.diagU
        if rot is not None:
            Ja = np.take(Je[:, :, 3:] * self.obs.weight[:, :, None], S.cam_order, axis=0)
            diagU = diagU.copy()
            diagU[:, 3:] = self.exterior.angles_w
            diagU[S.cam_present, 3:] += np.add.reduceat(np.sum(Ja * Ja, axis=1), S.cam_starts)
            bc[:, 3:] = np.linalg.solve(rot.transpose(0, 2, 1), bc[:, 3:, None])[:, :, 0]
        gp = np.einsum("nki,nk->ni", Jp, rp)
        bp = tg.by_point @ tg.take(gp)
        bp += self.points.prior_w * (
            self.points.prior_obs - np.take(st.xyz, self.points.unknown, 0)
        )
        Tb = (ne.Tr @ np.take(bp, tg.ray_point, axis=0)[:, :, None])[:, :, 0]
        red = bc - tg.by_image @ Tb
        return NormalEquations(
            blocks=None,
            rhs=red.reshape(-1),
            Vinv=ne.Vinv,
            Wr=ne.Wr,
            Tr=ne.Tr,
            rays=ne.rays,
            n_obs=ne.n_obs,
            bp=bp,
            diagU=diagU,
            diagV=ne.diagV,
            held=ne.held,
        )

    def solve(self, ne: NormalEquations, names: list[str], fac=None):
        """Corrections (dc (m, 6), dp (p_var, 3), da (q,)) and the factor of S.

        ``fac``: a factor of S from an earlier linearisation, used instead of factoring
        ``ne``'s S (a *chord* step, ``ne`` from :meth:`chord_normal`; plain bundles only:
        no border).
        """
        if ne.ext is not None:
            return camera_solve(self, ne, names)
        if fac is not None:
            if self.aux or self.q:
                raise ValueError("a chord step needs a bundle without border unknowns")
            return self.back_substitute(ne, fac.solve(ne.rhs), np.zeros(0), fac)
        fac = factor_reduced(self.reduced, ne.blocks, names, dense=ne.S)
        ne.S = None  # overwritten by the factor
        if self.aux:
            return self.aux.solve(self, fac, ne)
        if self.q:
            dc, da = solve_border(self, ne, fac)
        else:
            dc = fac.solve(ne.rhs)
            da = np.zeros(0)
        return self.back_substitute(ne, dc, da, fac)

    def back_substitute(self, ne: NormalEquations, dc: F64, da: F64, fac):
        """Back-substitution of the points; returns (dc, dp, da, fac)."""
        dc = dc.reshape(self.m, 6)
        tg = self.reduced.tracks  # ne.Wr is in its ray order
        ap = point_ap_term(self, ne.ap.H, da) if self.q and not self.run.border.hold else None
        dp = back_substitute(tg, ne.Vinv, ne.Wr, ne.bp, dc, ap)
        return dc, dp, da, fac

    @property
    def local_rotations_allowed(self) -> bool:
        """Whether steps may rotate the image frames (nothing else refers to the angles)."""
        return not (self.q or self.aux or self.ap.lens is not None) and not np.any(
            self.exterior.angles_w > 0
        )

    def apply(
        self,
        st: BundleState,
        dc: F64,
        dp: F64,
        da: F64,
        local: bool = False,
        images: tuple[F64, F64] | None = None,
    ) -> BundleState:
        """The next iterate; ``local``: dc[:, 3:] are rotations δ of the image frames;
        ``images``: (X0, angles) of the next iterate, formed already as st.X0 + dc[:, :3],
        st.angles + dc[:, 3:] (a plain step: not ``local``, no auxiliary data)."""
        xyz = st.xyz.copy()
        xyz[self.points.unknown] = np.take(xyz, self.points.unknown, axis=0) + dp
        if images is not None and not (local or self.aux):
            return BundleState(images[0], images[1], xyz, st.ap + da, st.g)
        if local:
            angles = apply_local(st.angles, dc[:, 3:], self.block.sequence)
            return BundleState(st.X0 + dc[:, :3], angles, xyz, st.ap + da, st.g)
        if self.aux:  # da: the additional parameters, then the auxiliary offsets/drifts
            q = self.q
            return BundleState(
                st.X0 + dc[:, :3], st.angles + dc[:, 3:], xyz, st.ap + da[:q], st.g + da[q:]
            )
        return BundleState(st.X0 + dc[:, :3], st.angles + dc[:, 3:], xyz, st.ap + da, st.g)

    def names(self, exterior_only: bool = False) -> ParameterNames:
        """The parameters' names in the order of ``x`` (``"<image id>.omega"``,
        ``"<point id>.X"``, the additional parameters'); ``exterior_only``: the first
        6m (the reduced system's). Formed when first read (messages, results)."""
        b = self.block
        if exterior_only:
            return ParameterNames(b.images.ids, (), ())
        return ParameterNames(b.images.ids, b.points.ids, self.ap.names if self.q else ())

    def flat(self, st: BundleState) -> F64:
        """The parameter vector of ``st`` (exterior, points, additional parameters)."""
        return st.flat()
