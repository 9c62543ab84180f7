"""Per-image cameras inside the images' blocks of the reduced system.

When every image has a camera of its own whose parameters are estimated (BAL's f, k1, k2
per image; a COLMAP model with one camera per image), the border of the additional
parameters (:mod:`._ap_normal`) couples image i's exterior orientation with camera l's
parameters exactly where S couples images i and l: E and F have S's pattern. So the k
camera parameters join the image's 6 exterior unknowns, one block of d = 6 + k unknowns
per image::

    S_d = U_d − Σ_j W_j V_j⁻¹ W_jᵀ,   W = [J_e | A]ᵀ P J_p per ray (d × 3),
    r_d = Σ [J_e | A]ᵀ P (r − J_p V⁻¹ b_p),

formed by pairs of rays of a point as S is (:func:`orientviz.bundle.reduced._tracks.schur_blocks`
with d × d blocks) and factored densely: no per-point border terms, no elimination of a
border. It is the bordered system [S E; Eᵀ F] with its unknowns ordered by image, so the
step is the bordered solve's up to rounding: S is S_d's exterior part, E and F its camera
parts, and the cameras are damped as the border damps them (the diagonal of F, points
eliminated, × (1 + λ)). :class:`CameraBorder` gives E, F, H of the border form from S_d
(the precision reads them).

The bundle (:class:`~orientviz.bundle.problem.BundleProblem`) takes this path when
:func:`camera_blocks_apply` holds; every other problem keeps the border.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..reduced import (
    Factor,
    NormalEquations,
    back_substitute,
    factor_reduced,
    schur_blocks,
    schur_buffer_size,
)
from ._border import _not_determinable
from ._eliminate import eliminate_points, image_blocks, work_array

F64 = NDArray[np.float64]


def camera_blocks_apply(prob) -> bool:
    """Whether ``prob``'s camera parameters go inside the images' blocks: a camera model
    (:class:`~orientviz.bundle.LensModel`) with parameters to estimate, a camera of its
    own for every image, no auxiliary data, and S formed by pairs of rays and factored
    densely (a small network: the dense factor of S_d costs (d/6)³ that of S)."""
    ap, red = prob.ap, prob.reduced
    if ap.lens is None or not ap.q or prob.aux is not None or ap.G != prob.m:
        return False
    if not np.array_equal(np.sort(ap.group), np.arange(prob.m)):
        return False
    return (
        red.solver == "dense" and red.formation == "pairs" and bool(red.cam_present.size == prob.m)
    )


@dataclass
class CameraBlocks:
    """The reduced system in blocks of d = 6 + k unknowns per image (exterior, camera).

    Attributes
    ----------
    blocks : ndarray, shape (n_blocks, d, d)
        S_d's blocks (i ≤ l) in the structure's order; the cameras' diagonals damped.
    rhs : ndarray, shape (m, d)
        The reduced right-hand side per image.
    W, T : ndarray, shape (n_var, d, 3)
        [J_e | A]ᵀ P J_p and W V⁻¹ per ray (the track order of ``reduced.tracks``).
    F_diag : ndarray, shape (m, k)
        Undamped diagonal of each image's camera block (points eliminated).
    lam : float
        The damping λ of this system.
    Jc, Jp : ndarray, shapes (n, 2, d), (n, 2, 3), optional
        The rays' weighted designs [P½J_e | P½A] and P½J_p it was formed from (views of
        work arrays, like ``W`` and ``T``).
    """

    blocks: F64
    rhs: F64
    W: F64
    T: F64
    F_diag: F64
    lam: float
    Jc: F64 | None = None
    Jp: F64 | None = None

    @property
    def d(self) -> int:
        """Unknowns per image."""
        return self.blocks.shape[1]


def camera_normal(
    prob, st, rw: F64, Je: F64, Jp: F64, lam: float, hold: bool = False
) -> NormalEquations:
    """The normal equations with the cameras inside the images' blocks (see the module
    docstring); the same arguments as :meth:`BundleProblem.normal`. ``ne.ext`` holds
    the :class:`CameraBlocks`; ``ne.blocks``, ``ne.rhs``, ``ne.Wr``, ``ne.Tr`` are their
    exterior parts and ``ne.ap`` a :class:`CameraBorder` (``hold``: as
    :meth:`BundleProblem.normal`).

    W, T and the weighted designs are work arrays kept between iterations
    (``reduced.tracks.work``, released with the Schur formation's maps after the
    iterations): they hold this system's until the next call, which overwrites them (the
    loop solves each system before forming the next)."""
    S, ap = prob.reduced, prob.ap
    tg = S.tracks
    k = ap.k
    d = 6 + k
    grp = ap.group
    n = Je.shape[0]
    sw = prob.obs.weight[:, :, None]
    ws = tg.work
    # [P½J_e | P½A | r'] per ray (r': ._eliminate) and a zero row: the Gram matrices
    Jz = work_array(ws, "Jz", (n + 1, 2, d + 1))
    Jz[n] = 0.0
    np.multiply(Je, sw, out=Jz[:n, :, :6])
    Jz[:n, :, 6:d] = ap.Aw
    Jpw = np.multiply(Jp, sw, out=work_array(ws, "Jpw", (n, 2, 3)))
    Wr, V, Vinv, Tr, bp, diagV, G, held = eliminate_points(
        prob, st, Jz, Jpw, rw, lam, ws, hold=hold
    )
    U, red, diagU = image_blocks(prob, st, G, lam)
    buf = work_array(ws, "products", (schur_buffer_size(tg, d),))
    blocks = schur_blocks(S, U, Tr, Wr, buf)
    ik = 6 + np.arange(k)
    dg = blocks[S.diag_block]
    Fd = dg[:, ik, ik]  # (m, k): the diagonal blocks are in image order
    if lam > 0:
        dg[:, ik, ik] = Fd * (1.0 + lam)
        blocks[S.diag_block] = dg
    diagF = np.empty((ap.G, k))
    diagF[grp] = Fd
    cb = CameraBlocks(blocks, red, Wr, Tr, Fd, lam, Jz[:n, :, :d], Jpw)
    out = NormalEquations(
        blocks=blocks[:, :6, :6],
        rhs=red[:, :6].reshape(-1),
        Vinv=Vinv,
        Wr=Wr[:, :6],
        Tr=Tr[:, :6],
        rays=tg.rays,
        n_obs=n,
        bp=bp,
        diagU=diagU,
        diagV=diagV,
        diagF=diagF.reshape(-1),
    )
    out.ext, out.held = cb, held
    out.ap = CameraBorder(prob, cb)
    return out


def dense_blocks(st, blocks: F64) -> F64:
    """The dense (dm, dm) matrix (lower triangle and diagonal blocks filled, Fortran
    order) of d × d blocks (i ≤ l) in the structure ``st``'s order."""
    m, d = st.n_cam, blocks.shape[1]
    N = np.zeros((d * m, d * m), order="F")
    N4 = N.T.reshape(m, d, m, d)  # N4[i, r, l, c] = N[dl + c, di + r]
    N4[st.block_i, :, st.block_k, :] = blocks
    return N


def camera_solve(prob, ne: NormalEquations, names: list[str]):
    """The step (dc (m, 6), dp (p_var, 3), da (q,), factor) of :func:`camera_normal`'s
    system by the dense Cholesky of S_d. A singular S_d raises
    :class:`~orientviz.errors.NotDeterminableError`: naming the images' parameters when
    S is singular, else the cameras'."""
    cb: CameraBlocks = ne.ext
    S, ap = prob.reduced, prob.ap
    m, d, k = prob.m, cb.d, prob.ap.k
    N = dense_blocks(S, cb.blocks)
    nd = N.shape[0]
    try:
        if not np.isfinite(N[:: nd + 1]).all():
            raise np.linalg.LinAlgError("non-finite diagonal")
        c, _ = scipy.linalg.cho_factor(N, lower=True, overwrite_a=True, check_finite=False)
        if not np.isfinite(c[:: nd + 1]).all():
            raise np.linalg.LinAlgError("non-finite pivot")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        factor_reduced(S, np.ascontiguousarray(ne.blocks), names)  # names a singular S
        raise _not_determinable(ap.names) from None
    prob.run.border.log.append("camera blocks")
    x = scipy.linalg.cho_solve((c, True), cb.rhs.reshape(-1), check_finite=False).reshape(m, d)
    da = np.empty((ap.G, k))
    da[ap.group] = x[:, 6:]
    dp = back_substitute(S.tracks, ne.Vinv, cb.W, ne.bp, x)
    return np.ascontiguousarray(x[:, :6]), dp, da.reshape(-1), Factor(S, "camera blocks", c)


class CameraBorder:
    """The border form (E, F0, F, ba, H of :class:`~orientviz.bundle.reduced.APBorder`) of
    a :class:`CameraBlocks` system, each formed on first access (the precision reads
    them)."""

    reused = False

    def __init__(self, prob, cb: CameraBlocks) -> None:
        self._prob, self._cb = prob, cb
        self._E: F64 | None = None
        self._F: tuple[F64, F64] | None = None
        self._H: F64 | None = None

    def _parts(self) -> None:
        prob, cb = self._prob, self._cb
        S, ap = prob.reduced, prob.ap
        k, m, G = ap.k, prob.m, ap.G
        g = ap.group
        bi, bl = S.block_i, S.block_k
        B = cb.blocks
        E4 = np.zeros((m, 6, G, k))  # E[6i + r, k·g(l) + c]
        E4[bi, :, g[bl]] = B[:, :6, 6:]
        off = bi != bl
        E4[bl[off], :, g[bi[off]]] = B[off, 6:, :6].transpose(0, 2, 1)
        F4 = np.zeros((G, k, G, k))
        F4[g[bi], :, g[bl]] = B[:, 6:, 6:]
        F4[g[bl[off]], :, g[bi[off]]] = B[off, 6:, 6:].transpose(0, 2, 1)
        F = F4.reshape(G * k, G * k)
        F0 = F.copy()
        if cb.lam > 0:  # the undamped diagonal
            Fd = np.empty((G, k))
            Fd[g] = cb.F_diag
            F0[np.diag_indices(G * k)] = Fd.reshape(-1)
        self._E = E4.reshape(6 * m, G * k)
        self._F = (F0, F)

    @property
    def E_border(self) -> F64:
        """E (6m, q) as an array."""
        if self._E is None:
            self._parts()
        return self._E

    E = E_border

    @property
    def F0(self) -> F64:
        """F (q, q), undamped."""
        if self._F is None:
            self._parts()
        return self._F[0]

    @property
    def F(self) -> F64:
        """F (q, q), its diagonal damped × (1 + λ)."""
        if self._F is None:
            self._parts()
        return self._F[1]

    @property
    def ba(self) -> F64:
        """The cameras' right-hand side (q,)."""
        ap = self._prob.ap
        out = np.empty((ap.G, ap.k))
        out[ap.group] = self._cb.rhs[:, 6:]
        return out.reshape(-1)

    @property
    def H(self) -> F64:
        """Σ Aᵀ P J_p per (point, group) pair (pairs, k, 3) in the order of
        :class:`~orientviz.bundle.problem._ap_structure.APStructure`."""
        if self._H is None:
            prob = self._prob
            A = prob.ap.structure
            tg = prob.reduced.tracks
            npg = A.pg_pt.size
            H = np.zeros((npg, prob.ap.k, 3))
            np.add.at(H, A.own_pg[tg.rays], self._cb.W[:, 6:, :])
            self._H = H
        return self._H
