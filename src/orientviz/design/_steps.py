"""One low-rank step of a live design's cofactors (the algebra of
:mod:`orientviz.design._live`).

:class:`WoodburySteps` holds the two operations a :class:`~orientviz.design.LiveDesign`
is made of: the current columns of Q at chosen coordinates (the base design's, less the
earlier steps' U M U[Ω]ᵀ) and one step Q' = Q − U M Uᵀ with the update of every shown
quantity (point and station cofactor blocks, the rays' redundancy numbers and gains).
The attributes it reads are the live design's (``_base``, ``_steps``, ``_cur``,
``_omega``, ``_Jw``, ``_ray_img``, ``_ray_pt``, ``_obs``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import NotDeterminableError
from ._live_parts import _Current

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

_NONE = np.zeros(0, np.int64)
#: The scaled Woodbury matrix of a step is taken as singular beyond this condition.
COND_LIMIT: float = 1e14


class WoodburySteps:
    """The columns and the step of a live design (see the module's docstring)."""

    # ------------------------------------------------------------------ columns
    def _columns(self, imgs: I64, pts: I64, gs: I64 = _NONE) -> tuple[F64, F64, F64]:
        """The current cofactors at the coordinates of image slots ``imgs`` (6 each), base
        points ``pts`` (3 each) and offsets ``gs`` (1 each): rows of the images by slot
        (M, 6, k), of the points (p0, 3, k) and of the offsets (na, k)."""
        base = self._base
        M = self._omega.shape[0]
        old = imgs[imgs < base.m]
        Cc0, Cp, Cg = base.columns(old, pts, gs)
        k = 6 * imgs.size + 3 * pts.size + gs.size
        Cc = np.zeros((M, 6, k))
        pos = np.flatnonzero(imgs < base.m)  # where the base images' columns go
        cols = np.r_[
            (6 * pos[:, None] + np.arange(6)).reshape(-1),
            6 * imgs.size + np.arange(3 * pts.size + gs.size),
        ]
        Cc[: base.m, :, cols] = Cc0
        Cpk = np.zeros((Cp.shape[0], 3, k))
        Cpk[:, :, cols] = Cp
        Cgk = np.zeros((Cg.shape[0], k))
        Cgk[:, cols] = Cg
        for s, i in enumerate(imgs):  # added slots: ω⁻¹ I in the base
            if i >= base.m:
                Cc[i, :, 6 * s : 6 * s + 6] = np.diag(1.0 / self._omega[i])
        for Uc, Up, Ug, Ms in self._steps:  # less the earlier steps' U M U[Ω]ᵀ
            r = Uc.shape[2]
            X = np.concatenate(
                [Uc[i] if i < Uc.shape[0] else np.zeros((6, r)) for i in imgs]
                + [Up[j] for j in pts]
                + [Ug[gs]],
                axis=0,
            )  # (k, r)
            B = Ms @ X.T
            Cc[: Uc.shape[0]] -= Uc @ B
            Cpk -= Up @ B
            Cgk -= Ug @ B
        return Cc, Cpk, Cgk

    # ------------------------------------------------------------------ the step
    def _step(
        self, imgs: I64, pts: I64, G: F64, d: F64, new_rays: I64 | None = None,
        alive: NDArray[np.bool_] | None = None, gs: I64 = _NONE,
    ) -> None:  # fmt: skip
        """One update by rows ``G`` (r, k) over the coordinates of ``imgs``, ``pts`` and
        offsets ``gs`` with signed weights ``d`` (r,); ``new_rays``: ray slots added in
        this step, their rows at 2i, 2i + 1 of G in order; ``alive``: the ray slots
        present after the step."""
        Cc, Cp, Cg = self._columns(imgs, pts, gs)
        k = G.shape[1]
        QO = np.concatenate(
            [Cc[imgs].reshape(-1, k), Cp[pts].reshape(-1, k), Cg[gs].reshape(-1, k)], axis=0
        )
        GU = G @ QO @ G.T
        GU = 0.5 * (GU + GU.T)
        # M = (I + D G U)⁻¹ D = S B⁻¹ Σ S with D = S Σ S (S = √|d|, Σ = sign d) and
        # B = I + Σ S G U S: B is scaled (unit rows for rays and priors alike), so its
        # condition tells whether the changed design is still determinable
        sq, sg = np.sqrt(np.abs(d)), np.sign(d)
        B = np.eye(d.size) + sg[:, None] * (sq[:, None] * GU * sq[None, :])
        if not np.isfinite(B).all() or np.linalg.cond(B) > COND_LIMIT:
            raise NotDeterminableError(
                "the changed design is not determinable (the change leaves unknowns "
                "without enough observations)",
                parameters=[],
            )
        Mx = sq[:, None] * np.linalg.solve(B, np.diag(sg)) * sq[None, :]
        Mx = 0.5 * (Mx + Mx.T)
        Uc, Up, Ug = Cc @ G.T, Cp @ G.T, Cg @ G.T  # (M, 6, r), (p0, 3, r), (na, r)
        c0 = self._cur
        r, rxy, Ke, Kp = c0.r.copy(), c0.rxy.copy(), c0.Ke.copy(), c0.Kp.copy()
        if new_rays is not None and new_rays.size:  # their terms before: rows of G U, U
            nn = new_rays.size
            a = np.arange(nn)
            H = GU[: 2 * nn, : 2 * nn].reshape(nn, 2, nn, 2)[a, :, a, :]  # (nn, 2, 2)
            r[new_rays] = 1.0 - np.stack([H[:, 0, 0], H[:, 1, 1]], 1)
            rxy[new_rays] = -0.5 * (H[:, 0, 1] + H[:, 1, 0])
            Ue = Uc[self._ray_img[new_rays]][:, :, : 2 * nn].reshape(nn, 6, nn, 2)
            Upn = Up[self._ray_pt[new_rays]][:, :, : 2 * nn].reshape(nn, 3, nn, 2)
            Ke[new_rays], Kp[new_rays] = Ue[a, :, a, :], Upn[a, :, a, :]
        live = np.flatnonzero(alive) if alive is not None else self._obs
        oi, op = self._ray_img[live], self._ray_pt[live]
        Jw = self._Jw[live]
        rr = Mx.shape[0]
        UcM = (Uc.reshape(-1, rr) @ Mx).reshape(Uc.shape)
        UpM = (Up.reshape(-1, rr) @ Mx).reshape(Up.shape)
        h = Jw[:, :, :6] @ Uc[oi] + Jw[:, :, 6:] @ Up[op]  # (n, 2, r)
        ht = h.transpose(0, 2, 1)
        UcMo, UpMo = UcM[oi], UpM[op]
        hM = Jw[:, :, :6] @ UcMo + Jw[:, :, 6:] @ UpMo
        dH = hM @ ht
        r[live] = np.clip(r[live] + np.stack([dH[:, 0, 0], dH[:, 1, 1]], 1), 0.0, 1.0)
        rxy[live] += 0.5 * (dH[:, 0, 1] + dH[:, 1, 0])
        Ke[live] -= UcMo @ ht
        Kp[live] -= UpMo @ ht
        self._cur = _Current(
            Qp=c0.Qp - UpM @ Up.transpose(0, 2, 1),
            Qe=c0.Qe - UcM @ Uc.transpose(0, 2, 1),
            r=r, rxy=rxy, Ke=Ke, Kp=Kp,
        )  # fmt: skip
        self._steps.append((Uc, Up, Ug, Mx))
