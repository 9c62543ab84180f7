"""The points eliminated from the bundle's normal equations, and the images' damped blocks.

The two steps that :meth:`~orientviz.bundle.problem.BundleProblem.normal` (6 unknowns per
image) and :func:`~orientviz.bundle.problem._camera_blocks.camera_normal` (6 + k: the
image's own camera too) share, for d unknowns per image:

* :func:`eliminate_points` — per ray W = J_cᵀ P J_p (d × 3), per point V and b_p (with the
  points' pseudo-observations and auxiliary rows, V damped × (1 + λ)), V⁻¹, T = W V⁻¹, and
  the images' Gram matrices of [P½J_c | r'] with r' = P½(l − f) − P½J_p V⁻¹ b_p per ray: U
  and, in the last column, the reduced right-hand side;
* :func:`image_blocks` — U with the exterior orientations' pseudo-observations (and the
  cameras', d > 6), its exterior part damped: "trust" in the frame of the image's scene
  (:mod:`._damping`), else Marquardt's × (1 + λ).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..reduced import inv3, inv3_held, point_products, ray_couplings
from ._damping import image_damping
from ._state import wrap

F64 = NDArray[np.float64]

_I3 = np.arange(3)
_I6 = np.arange(6)


def work_array(work: dict | None, name: str, shape: tuple) -> F64 | None:
    """The array ``name`` of ``shape`` kept in ``work`` (formed on first use); None
    without ``work`` (the callee then forms its own)."""
    if work is None:
        return None
    a = work.get(name)
    if a is None or a.shape != shape:
        a = work[name] = np.empty(shape)
    return a


def eliminate_points(
    prob,
    st,
    Jz: F64,
    Jpw: F64,
    rw: F64,
    lam: float,
    work: dict | None = None,
    rays: list | None = None,
    hold: bool = False,
):
    """The point elimination of one linearisation (see the module docstring).

    Parameters
    ----------
    prob : BundleProblem
    st : BundleState
        The iterate.
    Jz : ndarray, shape (n + 1, 2, d + 1)
        P½J_c of every ray in ``[:n, :, :d]`` and a zero row ``n``; its last column is
        written here (r' per ray).
    Jpw : ndarray, shape (n, 2, 3)
        P½J_p.
    rw : ndarray, shape (n, 2)
        Weighted misclosures P½(l − f).
    lam : float
        Damping of the point blocks.
    work : dict, optional
        Where W and T are kept between calls.
    rays : list, optional
        A list to which the rays of ``Jz`` sorted by image are appended
        (:class:`~orientviz.bundle.reduced.ImageRays`: the images' Gram matrices' operand).
    hold : bool
        A step's system: a point whose block V is numerically singular is held along its
        weak directions (:func:`~orientviz.bundle.reduced.inv3_held`: V⁺ for V⁻¹);
        False: every V inverted (the precision places such points first).

    Returns
    -------
    Wr, V, Vinv, Tr, bp, diagV, G, held
        W (n_var, d, 3), the damped V (p, 3, 3), V⁻¹, T (n_var, d, 3) in the track order,
        b_p (p, 3), V's undamped diagonal (p, 3), the images' Gram matrices (m, d + 1,
        d + 1), the held points (:class:`~orientviz.bundle.reduced.HeldDepths`, or None).
    """
    S = prob.reduced
    tg = S.tracks
    n, d = Jz.shape[0] - 1, Jz.shape[2] - 1
    nv = tg.rays.size
    # point rays in the order of their track lengths (._tracks); sums per point and per
    # image by products with constant sparse incidences
    W_out = work_array(work, "W", (nv, d, 3))
    Wr, V, bp = point_products(tg, Jz[:n, :, :d], Jpw, rw, S.n_pt, W_out)
    pts = prob.points
    Vd = V.reshape(-1, 9)[:, ::4]  # the diagonals (a view)
    Vd += pts.prior_w
    xyz = np.take(st.xyz, pts.unknown, axis=0)
    bp += pts.prior_w * (pts.prior_obs - xyz)
    if prob.aux:
        prob.aux.add_points(V, bp, st.X0, st.xyz, st.g)
    diagV = Vd.copy()
    if lam > 0:
        Vd *= 1.0 + lam
    held = None
    if hold:
        Vinv, held = inv3_held(V)
    else:
        Vinv = inv3(V)
    Tr = ray_couplings(tg, Wr, Vinv, work_array(work, "T", (nv, d, 3)))
    # the reduced right-hand side b_c − Σ T b_p = Σ P½J_cᵀ r' per ray: the last column
    y = np.take(np.einsum("nij,nj->ni", Vinv, bp), tg.ray_point, axis=0)
    Jpr = tg.take(Jpw)
    Jy = Jpr[:, :, 0] * y[:, 0, None]  # P½J_p y per ray by columns (no tiny products)
    Jy += Jpr[:, :, 1] * y[:, 1, None]
    Jy += Jpr[:, :, 2] * y[:, 2, None]
    Jz[:n, :, d] = rw
    Jz[tg.rows, :, d] -= Jy
    G = prob.image_gram.grams(Jz, rays)
    return Wr, V, Vinv, Tr, bp, diagV, G, held


def image_blocks(prob, st, G: F64, lam: float) -> tuple[F64, F64, F64]:
    """The images' blocks U (m, d, d) with their pseudo-observations, damped, the reduced
    right-hand side (m, d) and the exterior part's undamped diagonal (m, 6), from the
    Gram matrices ``G`` (m, d + 1, d + 1) of :func:`eliminate_points`."""
    d = G.shape[1] - 1
    U = np.ascontiguousarray(G[:, :d, :d])
    red = G[:, :d, d].copy()
    ext = prob.exterior
    trust = lam > 0 and prob.scene_centres is not None
    # the rays' part of the exterior blocks: the "trust" damping's metric
    U_rays = U[:, :6, :6].copy() if trust else None  # a copy (U itself when d = 6)
    U[:, _I3, _I3] += ext.X0_w
    red[:, :3] += ext.X0_w * (ext.X0_obs - st.X0)
    U[:, _I3 + 3, _I3 + 3] += ext.angles_w
    red[:, 3:6] += ext.angles_w * wrap(ext.angles_obs - st.angles)
    if prob.aux:
        prob.aux.add_images(U, red, st.X0, st.xyz, st.g)
    if d > 6:  # the image's own camera: its pseudo-observations a = 0
        ap = prob.ap
        k = d - 6
        wg = ap.w.reshape(-1, k)[ap.group]
        U[:, 6 + np.arange(k), 6 + np.arange(k)] += wg
        red[:, 6:] -= wg * st.ap.reshape(-1, k)[ap.group]
    diagU = U[:, _I6, _I6]
    if trust:  # the rays' part in the scene's frame (._damping), the rest × (1 + λ)
        U[:, _I6, _I6] = diagU + lam * (diagU - U_rays[:, _I6, _I6])
        seq = prob.block.sequence
        image_damping(U[:, :6, :6], lam, st.X0, st.angles, prob.scene_centres, seq, U_rays)
    elif lam > 0:
        U[:, _I6, _I6] = diagU * (1.0 + lam)
    return U, red, diagU
