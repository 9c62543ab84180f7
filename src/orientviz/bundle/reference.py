"""The bundle adjustment as a textbook writes it: start reading here.

One Gauss-Newton iteration, step by step, in plain numpy (no ordering, no sparse
factor, no reuse between iterations). Conventions of :mod:`orientviz.camera`: image
plane at z = −c (mm), R = R(ω, φ, κ) turns image vectors into the object frame
(:func:`orientviz.rotation.matrix_from_opk`), radians inside, residuals v = f(x̂) − l.

1. **Linearise** the collinearity equations of every ray (image i, point j)::

       (u, v, w)ᵀ = Rᵀ (X − X0),   x = x0 − c·u/w,   y = y0 − c·v/w

   with analytic partial derivatives by X0, Y0, Z0, ω, φ, κ and X, Y, Z
   (:func:`collinearity`).
2. **Form the normal-equation blocks** (:func:`normal_equations`), the unknowns split
   into x1 (6 exterior elements per image, then the additional parameters shared by
   groups of images) and x2 (3 coordinates per unknown point)::

       [N11  N12] [dx1]   [n1]      N11 = A1ᵀ P A1,  N12 = A1ᵀ P B,  N22 = Bᵀ P B
       [N21  N22] [dx2] = [n2]      n1 = A1ᵀ P (l − f),  n2 = Bᵀ P (l − f)

   N22 is block-diagonal: one 3×3 block per point. Weighted control coordinates and
   observed projection centres/attitudes/additional parameters add their weights 1/σ²
   to the diagonal (the datum; points held fixed are no unknowns at all).
3. **Reduce** to x1 (Schur complement): S = N11 − N12 N22⁻¹ N21, s = n1 − N12 N22⁻¹ n2.
4. **Solve** S dx1 = s densely, **back-substitute** dx2 = N22⁻¹ (n2 − N21 dx1) point by
   point, **update** x̂ += dx.
5. **Stop** when every correction is below ``tol`` times its conditional σ 1/√N_kk
   (the rule of :func:`orientviz.bundle.bundle_adjust`).

There is no damping: the iteration needs approximations good enough for Gauss-Newton
(:func:`orientviz.approximate.approximate_values`). ``bundle_adjust(block, solver="reference")``
runs it and returns the usual :class:`~orientviz.bundle.BundleResult`; the fast solvers
are tested against it (tests/bundle/test_reference*.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..rotation import matrix_derivatives, matrix_from_opk
from ._reference_data import ReferenceData, reference_data

F64 = NDArray[np.float64]

__all__ = [
    "ReferenceData",
    "ReferenceSolution",
    "collinearity",
    "linearise",
    "normal_equations",
    "reference_bundle",
    "reference_data",
    "solve_step",
]


@dataclass
class ReferenceSolution:
    """What :func:`reference_bundle` returns.

    Attributes
    ----------
    X0, angles : ndarray, shape (m, 3)
        Projection centres (m) and ω, φ, κ (rad) at the end.
    xyz : ndarray, shape (p, 3)
        All block points (m); fixed control at its given value, check points untouched.
    ap : ndarray, shape (q,)
        Additional parameters (units of their set, e.g. µm).
    x : list of ndarray
        Per iterate (index 0: the start) the parameters: exterior (6m), points (3p), ap.
    cost : list of float
        vᵀPv per iterate; σ̂0 = √(cost[-1] / redundancy).
    max_correction : list of float
        Per step, its largest correction in units of the conditional σ (the stopping
        measure).
    converged : bool
    reason : str
    """

    X0: F64
    angles: F64
    xyz: F64
    ap: F64
    x: list[F64] = field(default_factory=list)
    cost: list[float] = field(default_factory=list)
    max_correction: list[float] = field(default_factory=list)
    converged: bool = False
    reason: str = ""


def collinearity(X: F64, X0: F64, R: F64, dR: F64, c: F64) -> tuple[F64, F64, F64, F64]:
    """The collinearity equations of n rays and their partial derivatives.

    Parameters
    ----------
    X, X0 : ndarray, shape (n, 3)
        Object point and projection centre of each ray, m.
    R : ndarray, shape (n, 3, 3)
        Rotation (image → object) of each ray's image.
    dR : ndarray, shape (3, n, 3, 3)
        ∂R/∂ω, ∂R/∂φ, ∂R/∂κ of each ray's image (per rad).
    c : ndarray, shape (n,), or float
        Principal distance, mm.

    Returns
    -------
    xy : ndarray, shape (n, 2)
        x − x0, y − y0 in mm.
    dX0, dangles, dX : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(X0, Y0, Z0) in mm/m, ∂(x, y)/∂(ω, φ, κ) in mm/rad,
        ∂(x, y)/∂(X, Y, Z) in mm/m.
    """
    d = X - X0
    uvw = np.einsum("nki,nk->ni", R, d)  # Rᵀ (X − X0)
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]

    def quotient_rule(duvw):  # ∂(−c·u/w, −c·v/w) from ∂(u, v, w) (n, 3, k)
        uv_w = np.stack([u / w, v / w], 1)[:, :, None]
        return -(c / w)[:, None, None] * (duvw[:, :2] - uv_w * duvw[:, 2:3])

    xy = -(c / w)[:, None] * np.stack([u, v], 1)
    d_point = quotient_rule(np.transpose(R, (0, 2, 1)))  # ∂(u, v, w)/∂X = Rᵀ
    duvw_dangles = np.stack([np.einsum("nki,nk->ni", dR[a], d) for a in range(3)], 2)
    d_angles = quotient_rule(duvw_dangles)  # ∂(u, v, w)/∂θ = (∂R/∂θ)ᵀ (X − X0)
    return xy, -d_point, d_angles, d_point


def linearise(data: ReferenceData, X0: F64, angles: F64, xyz: F64, ap: F64, sequence: str = "opk"):
    """The observation equations at the current values, linearised.

    Parameters
    ----------
    data : ReferenceData
        What enters (:func:`reference_data`).
    X0, angles : ndarray, shape (m, 3)
        Projection centres (m), ω, φ, κ (rad).
    xyz : ndarray, shape (p, 3)
        All block points, m.
    ap : ndarray, shape (q,)
        Additional parameters.
    sequence : {"opk", "pok"}
        Rotation sequence of ``angles``.

    Returns
    -------
    f : ndarray, shape (n, 2)
        Predicted image coordinates of the rays, mm.
    A1 : ndarray, shape (n, 2, 6m + q)
        ∂f/∂x1: by the exterior orientations (6 columns per image) and the additional
        parameters.
    B : ndarray, shape (n, 2, 3)
        ∂f/∂(X, Y, Z) of each ray's point, mm/m.
    """
    m, n = X0.shape[0], data.image.size
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)[data.image]
    dR = np.stack(matrix_derivatives(angles[:, 0], angles[:, 1], angles[:, 2], sequence))
    c, x0, y0 = data.cam
    A1 = np.zeros((n, 2, 6 * m + ap.size))
    if data.lens is None:  # the pinhole: x = x0 − c·u/w, y = y0 − c·v/w
        xy, dX0, dang, B = collinearity(xyz[data.point], X0[data.image], R, dR[:, data.image], c)
        f = xy + np.stack([x0, y0], 1)
    else:  # the camera model maps the normalised point n = −(u, v)/w (c = 1) to f
        nrm, dX0, dang, B = collinearity(xyz[data.point], X0[data.image], R, dR[:, data.image], 1.0)
        f, M, D = data.lens.evaluate(ap, data.group, nrm, data.l, True)
        dX0, dang, B = M @ dX0, M @ dang, M @ B
    for i in range(m):  # a ray's row has non-zeros only in its own image's six columns
        ray = data.image == i
        A1[ray, :, 6 * i : 6 * i + 3] = dX0[ray]
        A1[ray, :, 6 * i + 3 : 6 * i + 6] = dang[ray]
    if data.k:  # and in the k columns of its image's group of additional parameters
        D = data.design if data.lens is None else D
        if data.lens is None:  # a linear set: f = collinearity + A(x_obs)·a
            f = f + np.einsum("nkj,nj->nk", D, ap.reshape(-1, data.k)[data.group])
        for g in range(ap.size // data.k):
            ray, col = data.group == g, 6 * m + g * data.k
            A1[ray, :, col : col + data.k] = D[ray]
    return f, A1, B


def normal_equations(data: ReferenceData, f: F64, A1: F64, B: F64, X0, angles, xyz, ap):
    """The normal-equation blocks (see the module docstring) and vᵀPv.

    Parameters
    ----------
    data : ReferenceData
    f, A1, B : ndarray
        From :func:`linearise`.
    X0, angles, xyz, ap : ndarray
        The current values (as :func:`linearise`).

    Returns
    -------
    N11 : ndarray, shape (u1, u1)
        u1 = 6m + q.
    N12 : ndarray, shape (p_var, u1, 3)
        One u1 × 3 column block per point unknown.
    N22 : ndarray, shape (p_var, 3, 3)
        One 3 × 3 block per point unknown.
    n1 : ndarray, shape (u1,)
    n2 : ndarray, shape (p_var, 3)
    cost : float
        vᵀPv (image coordinates and pseudo-observations).
    """
    m, q, P, l_f = X0.shape[0], ap.size, data.p, data.l - f
    A = A1.reshape(-1, A1.shape[2])  # the design matrix of x1, rows x, y of every ray
    N11 = A.T @ (P.reshape(-1, 1) * A)
    n1 = A.T @ (P * l_f).reshape(-1)
    j = data.col[data.point]
    var = j >= 0  # rays to points held fixed have no B
    N22, n2 = np.zeros((data.unknown.size, 3, 3)), np.zeros((data.unknown.size, 3))
    N12 = np.zeros((data.unknown.size, A1.shape[2], 3))
    PB = P[var, :, None] * B[var]
    np.add.at(N22, j[var], np.einsum("nki,nkj->nij", B[var], PB))
    np.add.at(N12, j[var], np.einsum("nki,nkj->nij", A1[var], PB))
    np.add.at(n2, j[var], np.einsum("nki,nk->ni", PB, l_f[var]))
    cost = float(np.sum(P * l_f**2))
    # pseudo-observations: control coordinates, observed exterior orientations, a = 0
    d = data.prior - xyz[data.unknown]
    N22[:, [0, 1, 2], [0, 1, 2]] += data.prior_w
    n2 += data.prior_w * d
    d_eo = data.eo - np.hstack([X0, angles])
    d_eo[:, 3:] = (d_eo[:, 3:] + np.pi) % (2 * np.pi) - np.pi  # angles to [−π, π)
    N11[np.diag_indices(6 * m)] += data.eo_w.ravel()
    n1[: 6 * m] += (data.eo_w * d_eo).ravel()
    N11[6 * m + np.arange(q), 6 * m + np.arange(q)] += data.ap_w
    n1[6 * m :] -= data.ap_w * ap
    cost += float(
        np.sum(data.prior_w * d**2) + np.sum(data.eo_w * d_eo**2) + np.sum(data.ap_w * ap**2)
    )
    return N11, N12, N22, n1, n2, cost


def solve_step(N11: F64, N12: F64, N22: F64, n1: F64, n2: F64) -> tuple[F64, F64]:
    """One Gauss-Newton step: reduce to x1, solve densely, back-substitute the points.

    Parameters
    ----------
    N11, N12, N22, n1, n2 : ndarray
        From :func:`normal_equations`.

    Returns
    -------
    dx1 : ndarray, shape (u1,)
        Corrections of the exterior orientations (m, rad) and additional parameters.
    dx2 : ndarray, shape (p_var, 3)
        Corrections of the point unknowns, m.
    """
    N22inv = np.linalg.inv(N22)  # one 3×3 inverse per point
    T = np.einsum("pia,pab->pib", N12, N22inv)  # N12 N22⁻¹, point by point
    S = N11 - np.einsum("pia,pja->ij", T, N12)
    s = n1 - np.einsum("pia,pa->i", T, n2)
    dx1 = np.linalg.solve(S, s)
    dx2 = np.einsum("pab,pb->pa", N22inv, n2 - np.einsum("pia,i->pa", N12, dx1))
    return dx1, dx2


def reference_bundle(
    block: Block, *, control: str = "fixed", additional=None, ap_group=None, ap_sigma=None,
    max_iter: int = 30, tol: float = 5e-3,
) -> ReferenceSolution:  # fmt: skip
    """Adjust ``block`` by the textbook Gauss-Newton iteration (see the module docstring).

    Parameters
    ----------
    block : Block
        Approximate values in ``images.X0``/``angles`` (m, rad) and ``points.xyz`` (m).
    control : {"fixed", "weighted"}
        The datum, as in :func:`orientviz.bundle.bundle_adjust`: with ``"fixed"`` every
        given control coordinate is held (a point given in X, Y and Z is no unknown, a
        partly given one is weighted with σ = 1 µm); with ``"weighted"`` given
        coordinates with σ > 0 are observations of weight 1/σ², σ = 0 still holds. Check
        points and their rays stay out; observed projection centres and attitudes
        (``images.X0_obs``, ``angles_obs`` with their σ) are observations too.
    additional : str, AdditionalParameters or LensModel, optional
        Self-calibration: a set's name, a set, or the camera model.
    ap_group, ap_sigma : optional
        Group of each image for the additional parameters; σ of their pseudo-
        observations a = 0 (None: free).
    max_iter : int
        Maximum number of steps.
    tol : float
        Stop when every correction is below ``tol`` times its conditional σ 1/√N_kk.

    Returns
    -------
    ReferenceSolution
    """
    data = reference_data(block, control, additional, ap_group, ap_sigma)
    m = block.n_images
    X0, angles, xyz, ap = block.images.X0.copy(), block.images.angles.copy(), data.xyz0, data.ap0
    out, rel = ReferenceSolution(X0, angles, xyz, ap), np.inf
    for it in range(max_iter + 1):
        f, A1, B = linearise(data, X0, angles, xyz, ap, block.sequence)
        N11, N12, N22, n1, n2, cost = normal_equations(data, f, A1, B, X0, angles, xyz, ap)
        out.cost.append(cost)
        out.x.append(np.concatenate([np.hstack([X0, angles]).ravel(), xyz.ravel(), ap]))
        if out.converged or it == max_iter:
            break
        dx1, dx2 = solve_step(N11, N12, N22, n1, n2)
        X0 = X0 + dx1[: 6 * m].reshape(m, 6)[:, :3]
        angles = angles + dx1[: 6 * m].reshape(m, 6)[:, 3:]
        ap = ap + dx1[6 * m :]
        xyz = xyz.copy()
        xyz[data.unknown] += dx2
        # the largest correction in units of its conditional σ = 1/√N_kk
        diag2 = N22[:, [0, 1, 2], [0, 1, 2]]
        rel = max(np.max(np.abs(dx1) * np.sqrt(np.diag(N11))),
                  np.max(np.abs(dx2) * np.sqrt(diag2), initial=0.0))  # fmt: skip
        out.max_correction.append(float(rel))
        out.converged = rel < tol
    out.X0, out.angles, out.xyz, out.ap = X0, angles, xyz, ap
    n_it = len(out.max_correction)
    its = "iteration" if n_it == 1 else "iterations"
    out.reason = (
        f"corrections below {tol:g} σ after {n_it} {its}" if out.converged
        else f"no convergence in {max_iter} iterations (last correction {rel:.3g} σ)"
    )  # fmt: skip
    return out
