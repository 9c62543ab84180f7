"""Vectorised collinearity kernel of the bundle adjustment.

The same equations as :func:`orientviz.camera.collinearity_jacobian` (image plane at
z = −c, R image → object, ``x = x0 − c·u/w``, ``y = y0 − c·v/w`` with
(u, v, w) = Rᵀ (X − X0)) and the same derivative chain
(:func:`orientviz.camera.collinearity_partials`), arranged for a block of many rays and
few images: everything that depends only on the image — R, and for each angle θ the
axial vector ω_θ of the skew-symmetric (∂R/∂θ)ᵀ R, so that ∂(u, v, w)/∂θ =
(∂R/∂θ)ᵀ (X − X0) = ω_θ × (u, v, w) — is computed once per *image* and gathered per ray
by a take of a per-image table; the per-ray work is then a few dozen products of (n,) arrays instead of
stacked 3 × 3 products. Rotation sequence ``"opk"`` (R = R_ω R_φ R_κ) or ``"pok"``
(R = R_φ R_ω R_κ), see :mod:`orientviz.rotation`. A :class:`RayProjection` keeps what
the Jacobians reuse, so that they can follow a projection (:func:`ray_jacobians`: the
bundle's start decides from the projection's misclosures which Jacobian it forms).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...rotation import matrix_from_opk
from ._local_rotation import frame_axials

F64 = NDArray[np.float64]


def _image_table(X0: F64, angles: F64, c: F64, x0: F64, y0: F64, sequence: str) -> F64:
    """Per-image rows to gather per ray, shape (15, m): R (9, row-major), X0, c, x0, y0."""
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)
    m = R.shape[0]
    cols = [R.reshape(m, 9), X0, c[:, None], x0[:, None], y0[:, None]]
    return np.ascontiguousarray(np.concatenate(cols, axis=1).T)


def _axial_table(angles: F64, sequence: str, local: bool) -> F64:
    """Per-image axial vectors ω_θ of (∂R/∂θ)ᵀ R, shape (9, m): ω, φ, κ (or with ``local``
    the rotations δ of the image frame), 3 each (:func:`~._local_rotation.frame_axials`)."""
    omega = frame_axials(angles, sequence, local)
    return np.ascontiguousarray(omega.reshape(omega.shape[0], 9).T)


#: Rays per chunk of the kernel's per-ray work: its temporaries stay small (in the cache,
#: no fresh pages of a large array per call); every operation is per ray, so the numbers
#: do not depend on the chunks.
KERNEL_CHUNK: int = 8192


def _chunks(n: int) -> list[tuple[int, int]]:
    """Bounds of the kernel's chunks of ``n`` rays; none of a single ray unless n = 1 (a
    stacked product of one 2 × 2 matrix reaches BLAS by another path than of two or
    more: its rounding could differ)."""
    b = list(range(0, n, KERNEL_CHUNK)) + [n]
    if len(b) > 2 and b[-1] - b[-2] == 1:
        del b[-2]
    return list(zip(b[:-1], b[1:]))


def _image_vectors(G: F64, xyz: F64, u: F64, v: F64, w: F64) -> None:
    """(u, v, w) = Rᵀ (X − X0) per ray from the gathered table ``G`` (k, n), written to
    ``u``, ``v``, ``w`` (n,)."""
    dx = xyz[:, 0] - G[9]
    dy = xyz[:, 1] - G[10]
    dz = xyz[:, 2] - G[11]
    np.multiply(G[0], dx, out=u)
    u += G[3] * dy
    u += G[6] * dz
    np.multiply(G[1], dx, out=v)
    v += G[4] * dy
    v += G[7] * dz
    np.multiply(G[2], dx, out=w)
    w += G[5] * dy
    w += G[8] * dz


class RayProjection:
    """Image coordinates of rays and what their Jacobians reuse (:func:`ray_jacobians`).

    Attributes
    ----------
    xy : ndarray, shape (n, 2)
        Image coordinates in mm.
    table : ndarray, shape (15, m)
        Per image R (row-major), X0, c, x0, y0 (each ray's rows are gathered by chunk).
    G : ndarray, shape (15, n) or None
        The table's rows of every ray, kept when the rays are one chunk.
    u, v, w : ndarray, shape (n,)
        Rᵀ (X − X0) per ray in m.
    a : ndarray, shape (n,)
        −c/w per ray in mm/m.
    obs_image : ndarray of int, shape (n,)
        Image of each ray.

    ``table``: the per-image table of these X0, angles, c, x0, y0 when it is known (the
    values :func:`_image_table` forms).
    """

    def __init__(
        self, X0, angles, c, x0, y0, obs_image, xyz, sequence: str, table: F64 | None = None
    ) -> None:
        T = _image_table(X0, angles, c, x0, y0, sequence) if table is None else table
        n = obs_image.shape[0]
        u, v, w, a = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        xy = np.empty((n, 2))
        chunks = _chunks(n)
        G = None
        for s, e in chunks:
            G = T.take(obs_image[s:e], axis=1)
            _image_vectors(G, xyz[s:e], u[s:e], v[s:e], w[s:e])
            np.divide(-G[12], w[s:e], out=a[s:e])
            np.multiply(a[s:e], u[s:e], out=xy[s:e, 0])
            xy[s:e, 0] += G[13]
            np.multiply(a[s:e], v[s:e], out=xy[s:e, 1])
            xy[s:e, 1] += G[14]
        self.xy, self.table, self.u, self.v, self.w, self.a = xy, T, u, v, w, a
        self.obs_image = obs_image
        #: the rows gathered per ray when the rays are one chunk (the Jacobians reuse them)
        self.G = G if len(chunks) == 1 else None


def project_block(
    X0: F64,
    angles: F64,
    c: F64,
    x0: F64,
    y0: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
) -> F64:
    """Image coordinates (n, 2) in mm of observation rays.

    Parameters
    ----------
    X0 : ndarray, shape (m, 3)
        Projection centres in m.
    angles : ndarray, shape (m, 3)
        ω, φ, κ in rad (sequence ``sequence``).
    c, x0, y0 : ndarray, shape (m,)
        Interior orientation per image in mm.
    obs_image : ndarray of int, shape (n,)
        Image of each observation.
    xyz : ndarray, shape (n, 3)
        Object point of each observation in m.
    sequence : {"opk", "pok"}
    """
    return RayProjection(X0, angles, c, x0, y0, obs_image, xyz, sequence).xy


def collinearity_block(
    X0: F64,
    angles: F64,
    c: F64,
    x0: F64,
    y0: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
    local: bool = False,
) -> tuple[F64, F64, F64]:
    """Image coordinates and Jacobians of all observations of a block.

    Parameters are those of :func:`project_block`; ``local``: the last three columns of
    J_exterior are derivatives by a small rotation δ of the image frame,
    R(δ) = R·exp([δ]×), instead of by ω, φ, κ (no gimbal lock; see
    :mod:`orientviz.bundle.model._local_rotation`).

    Returns
    -------
    xy : ndarray, shape (n, 2)
        Image coordinates in mm.
    J_exterior : ndarray, shape (n, 2, 6)
        ∂(x, y)/∂(X0, Y0, Z0, ω, φ, κ) in mm/m and mm/rad.
    J_point : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(X, Y, Z) in mm/m.
    """
    p = RayProjection(X0, angles, c, x0, y0, obs_image, xyz, sequence)
    return (p.xy, *ray_jacobians(p, angles, sequence, local))


def ray_jacobians(
    p: RayProjection, angles: F64, sequence: str, local: bool = False, M: F64 | None = None
):
    """J_exterior (n, 2, 6) and J_point (n, 2, 3) of the rays of a :class:`RayProjection`
    (see :func:`collinearity_block`; ``angles`` those of the projection); with ``M`` (n,
    2, 2) mapped through it, M·J (e.g. a camera model's Jacobian by the normalised image
    point), chunk by chunk without the unmapped ones.

    Notes
    -----
    With a = −c/w, b = c·(u, v)/w²: ∂(x, y)/∂(u, v, w) = [[a, 0, b_u], [0, a, b_v]],
    ∂(u, v, w)/∂X = Rᵀ (rows of Rᵀ: columns of R) and ∂(u, v, w)/∂θ = ω_θ × (u, v, w).
    Formed in chunks of :data:`KERNEL_CHUNK` rays.
    """
    Om_table = _axial_table(angles, sequence, local)
    n = p.u.shape[0]
    chunks = _chunks(n)
    if len(chunks) == 1:  # the products are the results (no copies)
        J = _jacobian_rows(p, Om_table, 0, n).transpose(2, 0, 1)
        if M is None:
            return np.ascontiguousarray(J[:, :, :6]), np.ascontiguousarray(J[:, :, 6:])
        return M @ J[:, :, :6], M @ J[:, :, 6:]
    Je, Jp = np.empty((n, 2, 6)), np.empty((n, 2, 3))
    for s, e in chunks:
        E = _jacobian_rows(p, Om_table, s, e)
        J = E.transpose(2, 0, 1)  # (rays, x/y, 9)
        if M is None:
            Je[s:e], Jp[s:e] = J[:, :, :6], J[:, :, 6:]
        else:  # (a product into ``out`` takes a slower path here: copied instead)
            Je[s:e] = M[s:e] @ J[:, :, :6]
            Jp[s:e] = M[s:e] @ J[:, :, 6:]
    return Je, Jp


def _jacobian_rows(p: RayProjection, Om_table: F64, s: int, e: int) -> F64:
    """Rows x, y of both Jacobians of rays s:e as (e − s,) columns of one (2, 9, e − s)
    array: X0, Y0, Z0, the three angles, then X, Y, Z (:func:`ray_jacobians`)."""
    G = p.G if p.G is not None else p.table.take(p.obs_image[s:e], axis=1)
    Om = Om_table.take(p.obs_image[s:e], axis=1)
    u, v, w, a = p.u[s:e], p.v[s:e], p.w[s:e], p.a[s:e]
    bu = a * u
    bu /= w
    bu *= -1.0  # c u / w²
    bv = a * v
    bv /= w
    bv *= -1.0
    E = np.empty((2, 9, e - s))
    for j in range(3):  # ∂/∂X_j: a·R[j, 0 or 1] + b·R[j, 2]
        r2 = G[3 * j + 2]
        np.multiply(a, G[3 * j], out=E[0, 6 + j])
        E[0, 6 + j] += bu * r2
        np.multiply(a, G[3 * j + 1], out=E[1, 6 + j])
        E[1, 6 + j] += bv * r2
    for k in range(3):  # ∂/∂θ_k: (du, dv, dw) = ω_k × (u, v, w)
        ox, oy, oz = Om[3 * k], Om[3 * k + 1], Om[3 * k + 2]
        dw = ox * v
        dw -= oy * u
        du = oy * w
        du -= oz * v
        dv = oz * u
        dv -= ox * w
        np.multiply(a, du, out=E[0, 3 + k])
        E[0, 3 + k] += bu * dw
        np.multiply(a, dv, out=E[1, 3 + k])
        E[1, 3 + k] += bv * dw
    np.negative(E[:, 6:], out=E[:, :3])
    return E


def normalised_block(
    X0: F64,
    angles: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
    jac: bool = True,
) -> tuple[F64, F64 | None, F64 | None]:
    """Normalised image points n = −(u, v)/w of rays and their Jacobians.

    The pinhole part of a camera model that applies c, the principal point and the lens
    itself (:mod:`orientviz.bundle.model._lens`): ``project_block`` with c = 1, x0 = y0 = 0.

    Returns
    -------
    n : ndarray, shape (n, 2)
        Normalised image points (unitless).
    J_exterior : ndarray, shape (n, 2, 6) or None
        ∂n/∂(X0, Y0, Z0, ω, φ, κ) in 1/m and 1/rad (None without ``jac``).
    J_point : ndarray, shape (n, 2, 3) or None
        ∂n/∂(X, Y, Z) in 1/m.
    """
    one = np.ones(X0.shape[0])
    zero = np.zeros(X0.shape[0])
    if not jac:
        return project_block(X0, angles, one, zero, zero, obs_image, xyz, sequence), None, None
    return collinearity_block(X0, angles, one, zero, zero, obs_image, xyz, sequence)
