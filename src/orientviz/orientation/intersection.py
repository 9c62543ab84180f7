"""Forward intersection: object points from rays of oriented images.

Conventions (see :mod:`orientviz.camera`): image coordinates in mm, object coordinates
in m, ``R`` (image → object) as built by :func:`orientviz.rotation.matrix_from_opk`;
the collinearity equations are ``x = x0 − c·u/w``, ``y = y0 − c·v/w`` with
``(u, v, w) = Rᵀ (X − X0)``.

Each point is solved in two steps:

1. a **linear** start: the point closest (in the least-squares sense) to all its rays,
   ``Σ (I − dᵢdᵢᵀ) (X − X0ᵢ) = 0`` with unit directions dᵢ — a 3 × 3 system per point;
2. the **rigorous** collinearity adjustment: Gauss-Newton on the image coordinates with
   their weights, again a 3 × 3 normal system per point.

Both steps are vectorised over all points at once (:func:`intersect_points`), so that
block code can intersect tens of thousands of points without a Python loop; the rigorous
step iterates on the engine's one loop (:func:`orientviz.adjust.iterate`), all points in
one step (their normal matrix is block diagonal). This is the package's one
``intersect_points``.
:func:`forward_intersection` solves one point on the engine and returns a full
:class:`~orientviz.adjust.Adjustment`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment, Evaluation, Step, StopRule, gauss_newton, iterate
from ..camera import rays
from ..errors import InputError, NotDeterminableError

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Smallest/largest eigenvalue ratio of Σ(I − ddᵀ) below which the rays of a point count
#: as parallel (≈ sin² of the largest intersection angle; 1e-12 ↔ 0.2 cc … 0.0001 gon).
PARALLEL_TOLERANCE: float = 1e-12


def intersect_rays(
    X0: F64, d: F64, point: NDArray[np.int64], n_points: int, *, tolerance: float = 1e-8
) -> tuple[F64, F64]:
    """Linear least-squares intersection of rays (vectorised over points).

    Minimises Σ ‖(I − d dᵀ)(X − X0)‖² per point (d unit ray directions).

    Parameters
    ----------
    X0 : ndarray, shape (k, 3)
        Ray origins (projection centres).
    d : ndarray, shape (k, 3)
        Ray directions (object frame, any length).
    point : ndarray of int, shape (k,)
        Point index of each ray.
    n_points : int
    tolerance : float
        Smallest eigenvalue ratio (cond) of a point's 3×3 system that is still solved;
        below it the rays count as parallel and the point stays NaN.

    Returns
    -------
    X : ndarray, shape (n_points, 3)
        Intersections (NaN where fewer than two rays or a degenerate geometry).
    cond : ndarray, shape (n_points,)
        Smallest/largest eigenvalue of the 3×3 system (0 = parallel rays).
    """
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    P = np.eye(3)[None] - u[:, :, None] * u[:, None, :]
    PX = np.einsum("nij,nj->ni", P, X0)
    A = np.stack([np.bincount(point, P[:, i, j], n_points) for i in range(3) for j in range(3)], 1)
    A = A.reshape(n_points, 3, 3)
    b = np.stack([np.bincount(point, PX[:, i], n_points) for i in range(3)], 1)
    ev = np.linalg.eigvalsh(A)
    cond = ev[:, 0] / np.maximum(ev[:, 2], 1e-300)
    X = np.full((n_points, 3), np.nan)
    ok = cond > tolerance
    X[ok] = np.linalg.solve(A[ok], b[ok][:, :, None])[:, :, 0]
    return X, cond


@dataclass
class Intersection:
    """Result of :func:`intersect_points` for p points.

    Attributes
    ----------
    xyz : ndarray, shape (p, 3)
        Object coordinates in m (NaN for points that are not determinable).
    cofactor : ndarray, shape (p, 3, 3)
        Q = N⁻¹ per point in m² (covariance for a-priori σ0 = 1; NaN if not determinable).
    sigma0 : ndarray, shape (p,)
        A-posteriori σ̂0 per point (NaN where the redundancy is 0, i.e. two rays give
        redundancy 1, so σ̂0 exists from two rays on).
    redundancy : ndarray of int, shape (p,)
        2·(rays) − 3.
    n_rays : ndarray of int, shape (p,)
    residuals : ndarray, shape (n, 2)
        v = f(X̂) − l in mm per observation.
    determinable : ndarray of bool, shape (p,)
    iterations : int
        Gauss-Newton steps of the rigorous adjustment (0 for ``rigorous=False``).
    converged : bool
    """

    xyz: F64
    cofactor: F64
    sigma0: F64
    redundancy: I64
    n_rays: I64
    residuals: F64
    determinable: NDArray[np.bool_]
    iterations: int
    converged: bool

    def std(self, a_posteriori: bool = False) -> F64:
        """Standard deviations (p, 3) in m: a-priori (σ0 = 1) or scaled by each point's σ̂0.

        Per-point σ̂0 rests on very few redundant observations (1 for two rays), so the
        a-priori value is the default.
        """
        s = np.sqrt(np.clip(np.diagonal(self.cofactor, axis1=1, axis2=2), 0.0, None))
        if a_posteriori:
            s = s * self.sigma0[:, None]
        return s


@dataclass
class ForwardIntersection(Adjustment):
    """The result of :func:`forward_intersection` (one point on the engine).

    Attributes
    ----------
    start : ndarray, shape (3,)
        The linear solution it started from, m.
    """

    start: F64 | None = None


def _as_per_image(value: ArrayLike, m: int, name: str) -> F64:
    v = np.asarray(value, dtype=float)
    try:
        return np.broadcast_to(v, (m,)).astype(float)
    except ValueError:
        raise InputError(f"{name}: expected a float or shape ({m},), got {v.shape}") from None


def _sum_per_point(values: F64, point: I64, p: int) -> F64:
    """Σ over observations of each point for arrays (n, ...) → (p, ...), via bincount."""
    flat = values.reshape(values.shape[0], -1)
    out = np.empty((p, flat.shape[1]))
    for k in range(flat.shape[1]):
        out[:, k] = np.bincount(point, weights=flat[:, k], minlength=p)
    return out.reshape((p,) + values.shape[1:])


def _point_jacobian(X: F64, X0: F64, R: F64, c: F64, x0: F64, y0: F64) -> tuple[F64, F64]:
    """Image coordinates (n, 2) and ∂(x, y)/∂(X, Y, Z) (n, 2, 3) for n rays.

    With (u, v, w) = Rᵀ(X − X0): ∂x/∂X = −(c/w)·R[:, 0] + (c·u/w²)·R[:, 2] (columns of R),
    ∂y/∂X = −(c/w)·R[:, 1] + (c·v/w²)·R[:, 2].
    """
    uvw = np.einsum("nji,nj->ni", R, X - X0)
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    cw = c / w
    f = np.empty((X.shape[0], 2))
    f[:, 0] = x0 - cw * u
    f[:, 1] = y0 - cw * v
    J = np.empty((X.shape[0], 2, 3))
    J[:, 0, :] = -cw[:, None] * R[:, :, 0] + (cw * u / w)[:, None] * R[:, :, 2]
    J[:, 1, :] = -cw[:, None] * R[:, :, 1] + (cw * v / w)[:, None] * R[:, :, 2]
    return f, J


# Symmetric 3 × 3 matrices of many points are kept as 6 components (xx, yy, zz, xy, xz, yz).
_I6, _J6 = np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2])


def _sym_outer(a: F64, b: F64) -> F64:
    """Components of the symmetric part of a bᵀ, shape (n, 6)."""
    return a[:, _I6] * b[:, _J6]


def _sym_full(S: F64) -> F64:
    out = np.empty((S.shape[0], 3, 3))
    out[:, _I6, _J6] = S
    out[:, _J6, _I6] = S
    return out


def _sym_inverse(S: F64) -> tuple[F64, F64]:
    """Inverse (n, 6) and determinant (n,) of symmetric 3 × 3 matrices via the adjugate."""
    a, b, c, d, e, f = (S[:, k] for k in range(6))  # [[a, d, e], [d, b, f], [e, f, c]]
    A = b * c - f * f
    B = e * f - d * c
    C = d * f - b * e
    det = a * A + d * B + e * C
    adj = np.column_stack([A, a * c - e * e, a * b - d * d, B, C, d * e - a * f])
    with np.errstate(divide="ignore", invalid="ignore"):
        return adj / det[:, None], det


def _sym_apply(S: F64, x: F64) -> F64:
    """S · x for symmetric S (n, 6) and vectors x (n, 3)."""
    return np.column_stack(
        [
            S[:, 0] * x[:, 0] + S[:, 3] * x[:, 1] + S[:, 4] * x[:, 2],
            S[:, 3] * x[:, 0] + S[:, 1] * x[:, 1] + S[:, 5] * x[:, 2],
            S[:, 4] * x[:, 0] + S[:, 5] * x[:, 1] + S[:, 2] * x[:, 2],
        ]
    )


class _PointBatch:
    """Forward intersection of many points as one problem of :func:`orientviz.adjust.iterate`.

    The iterate is the (p, 3) array of all points; a step solves the 3 × 3 normal system
    of every determinable point (the normal matrix is block diagonal: the points do not
    share unknowns), so one Gauss-Newton step corrects all of them at once. Points that
    are not determinable (``ok`` False) stay as they are (NaN).
    """

    def __init__(self, ok, pu, lu, wu, rays, scale) -> None:
        self.ok, self.pu, self.lu, self.wu = ok, pu, lu, wu
        self.rays = rays  # X0, R, c, x0, y0 per used ray
        self.scale = scale  # per point, m
        self.p = ok.size

    def small(self, tol: float):
        """The stopping test: every correction below ``tol`` × the mean distance to its cameras."""

        def test(step: Step) -> bool:
            return bool(np.all(np.abs(step.data) <= tol * self.scale[self.ok, None]))

        return test

    def evaluate(self, X: F64, jacobian: bool) -> Evaluation:
        pu, p = self.pu, self.p
        f_u, J = _point_jacobian(X[pu], *self.rays)
        wu = self.wu
        r = self.lu - f_u
        J0, J1 = J[:, 0, :], J[:, 1, :]
        N = _sum_per_point(wu[:, :1] * _sym_outer(J0, J0) + wu[:, 1:] * _sym_outer(J1, J1), pu, p)
        b = _sum_per_point((wu[:, :1] * r[:, :1]) * J0 + (wu[:, 1:] * r[:, 1:]) * J1, pu, p)
        # a point behind a camera is NaN for itself only: the batch goes on
        cost = float(np.nansum(wu * r**2))
        return Evaluation(cost, True, (f_u, J0, J1, N, b))

    def solve(self, X: F64, ev: Evaluation, lam: float, iteration: int) -> Step:
        N, b = ev.data[3], ev.data[4]
        dx = _sym_apply(_sym_inverse(N[self.ok])[0], b[self.ok])
        rel = np.abs(dx) / self.scale[self.ok, None]
        return Step(float(np.max(rel, initial=0.0)), None, dx)

    def apply(self, X: F64, step: Step) -> F64:
        out = X.copy()
        out[self.ok] += step.data
        return out

    def snapshot(self, X: F64) -> F64:
        # no per-step copy of every point (blocks intersect 10⁵ points)
        return np.empty(0)


def intersect_points(
    xy: ArrayLike,
    image: ArrayLike,
    point: ArrayLike,
    X0: ArrayLike,
    R: ArrayLike,
    c: ArrayLike,
    x0: ArrayLike = 0.0,
    y0: ArrayLike = 0.0,
    *,
    sigma: ArrayLike = 0.005,
    n_points: int | None = None,
    rigorous: bool = True,
    max_iter: int = 10,
    tol: float = 1e-10,
    on_degenerate: str = "raise",
) -> Intersection:
    """Forward intersection of many points at once (linear start + collinearity LS).

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Image coordinates in mm, one row per ray.
    image : array_like of int, shape (n,)
        Image index of each ray (into ``X0``/``R``/``c``).
    point : array_like of int, shape (n,)
        Point index of each ray, in [0, p).
    X0 : array_like, shape (m, 3)
        Projection centres in m.
    R : array_like, shape (m, 3, 3)
        Rotations image → object.
    c, x0, y0 : float or array_like, shape (m,)
        Interior orientation per image in mm.
    sigma : float or array_like, shape (n,) or (n, 2), default 0.005
        σ of the image coordinates in mm (weights of the rigorous step).
    n_points : int, optional
        Number of points p (default ``point.max() + 1``).
    rigorous : bool, default True
        Refine the linear solution by collinearity least squares.
    max_iter : int, default 10
    tol : float, default 1e-10
        Stop when every correction is below ``tol`` × (distance to the cameras) m.
    on_degenerate : {"raise", "nan"}, default "raise"
        What to do with points seen by fewer than 2 rays or by parallel rays: raise
        :class:`NotDeterminableError` naming them, or return NaN for them.

    Returns
    -------
    Intersection
    """
    try:
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        X0 = np.asarray(X0, dtype=float).reshape(-1, 3)
        R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    except ValueError as exc:
        raise InputError(f"forward intersection: {exc}") from None
    img = np.asarray(image, dtype=np.int64).reshape(-1)
    pt = np.asarray(point, dtype=np.int64).reshape(-1)
    n, m = xy.shape[0], X0.shape[0]
    if img.shape != (n,) or pt.shape != (n,):
        raise InputError(f"forward intersection: expected {n} image and point indices")
    if R.shape[0] != m:
        raise InputError(f"forward intersection: expected {m} rotations like X0, got {R.shape[0]}")
    if n and (img.min() < 0 or img.max() >= m or pt.min() < 0):
        raise InputError("forward intersection: image or point index out of range")
    if on_degenerate not in ("raise", "nan"):
        raise InputError(f"on_degenerate: expected 'raise' or 'nan', got {on_degenerate!r}")
    if not np.all(np.isfinite(xy)):
        raise InputError("forward intersection: expected finite image coordinates")
    p = int(pt.max()) + 1 if n_points is None and n else int(n_points or 0)
    cc, xx0, yy0 = (_as_per_image(v, m, k) for k, v in (("c", c), ("x0", x0), ("y0", y0)))
    if n and pt.max() >= p:
        raise InputError(f"forward intersection: point index {pt.max()} ≥ n_points = {p}")
    sg = np.asarray(sigma, dtype=float)
    try:
        sg = np.broadcast_to(sg[:, None] if sg.ndim == 1 else sg, (n, 2))
    except ValueError:
        raise InputError(
            f"sigma: expected a float, shape ({n},) or ({n}, 2), got {sg.shape}"
        ) from None
    if not np.all(np.isfinite(sg)) or np.any(sg <= 0):
        raise InputError("sigma: expected positive finite σ of the image coordinates in mm")
    # ---- linear start: Σ (I − d dᵀ) X = Σ (I − d dᵀ) X0
    # (the one linear ray intersection of the package, shared with the block's approximations)
    d = rays(xy, R[img], cc[img], xx0[img], yy0[img])
    X_linear, _ = intersect_rays(X0[img], d, pt, p, tolerance=PARALLEL_TOLERANCE)
    nr = np.bincount(pt, minlength=p)
    ok = (nr >= 2) & np.isfinite(X_linear).all(axis=1)
    if not ok.all() and on_degenerate == "raise":
        bad = np.flatnonzero(~ok)
        few = bad[nr[bad] < 2]
        par = bad[nr[bad] >= 2]
        parts = []
        if few.size:
            parts.append(f"fewer than 2 rays for point(s) {', '.join(map(str, few[:10]))}")
        if par.size:
            parts.append(f"parallel rays for point(s) {', '.join(map(str, par[:10]))}")
        raise NotDeterminableError(
            "forward intersection: " + "; ".join(parts),
            parameters=[f"{i}.{a}" for i in bad[:10] for a in "XYZ"],
        )
    X = np.where(ok[:, None], X_linear, np.nan)
    # ---- rigorous collinearity adjustment per point (3 × 3 normal equations each), on the
    # engine's loop: one step corrects every determinable point at once
    wgt = 1.0 / sg**2
    use = ok[pt]
    pu, iu = pt[use], img[use]
    rays_u = (X0[iu], R[iu], cc[iu], xx0[iu], yy0[iu])
    scale = np.ones(p)  # the stopping scale: each point's mean distance to its cameras, m
    if use.any():
        dist = np.linalg.norm(X[pu] - rays_u[0], axis=1)
        scale = np.maximum(_sum_per_point(dist, pu, p) / np.maximum(nr, 1), 1.0)
    batch = _PointBatch(ok, pu, xy[use], wgt[use], rays_u, scale)
    stop = StopRule(
        step_test=batch.small(tol),
        step_reason=f"corrections below {tol:g} × distance after {{it}} steps",
    )
    run = iterate(
        batch, X, redundancy=int(np.sum(2 * nr[ok] - 3)), stop=stop,
        max_iter=max_iter if rigorous else 0,
    )  # fmt: skip
    X = run.state
    it = len(run.history) - 1
    converged = run.converged or not rigorous
    f_u, N = run.evaluation.data[0], run.evaluation.data[3]
    f = np.full((n, 2), np.nan)
    f[use] = f_u
    Q = np.full((p, 3, 3), np.nan)
    if ok.any():
        Q[ok] = _sym_full(_sym_inverse(N[ok])[0])
    v = f - xy
    red = 2 * nr - 3
    vpv = _sum_per_point(np.sum(wgt * np.nan_to_num(v) ** 2, axis=1) * use, pt, p)
    with np.errstate(invalid="ignore", divide="ignore"):
        s0 = np.where((red > 0) & ok, np.sqrt(vpv / np.maximum(red, 1)), np.nan)
    return Intersection(X, Q, s0, red, nr, v, ok, it, converged)


def forward_intersection(
    xy: ArrayLike,
    X0: ArrayLike,
    R: ArrayLike,
    c: ArrayLike,
    x0: ArrayLike = 0.0,
    y0: ArrayLike = 0.0,
    *,
    sigma: ArrayLike = 0.005,
    image_ids: list[str] | None = None,
) -> ForwardIntersection:
    """Intersect the rays of one point from k ≥ 2 images, on the engine, with precision.

    Parameters
    ----------
    xy : array_like, shape (k, 2)
        Image coordinates of the point in each image, mm.
    X0 : array_like, shape (k, 3)
        Projection centres in m.
    R : array_like, shape (k, 3, 3)
        Rotations image → object.
    c, x0, y0 : float or array_like, shape (k,)
        Interior orientation in mm.
    sigma : float or array_like, default 0.005
        σ of the image coordinates in mm.
    image_ids : list of str, optional
        Names for the residual labels.

    Returns
    -------
    ForwardIntersection
        ``names`` ``("X", "Y", "Z")`` in m; residuals ``v = f(X̂) − l`` in mm labelled
        ``"<image>/x"``; ``start`` the linear solution.

    Raises
    ------
    NotDeterminableError
        Fewer than two rays, or parallel rays.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    k = xy.shape[0]
    if k < 2:
        raise NotDeterminableError(
            f"forward intersection: needs at least 2 rays, got {k}", parameters=["X", "Y", "Z"]
        )
    try:
        X0 = np.asarray(X0, dtype=float).reshape(-1, 3)
        R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    except ValueError as exc:
        raise InputError(
            f"forward intersection: expected X0 (k, 3) and R (k, 3, 3): {exc}"
        ) from None
    if X0.shape[0] != k or R.shape[0] != k:
        raise InputError(f"forward intersection: expected {k} projection centres and rotations")
    cc, xx0, yy0 = (_as_per_image(v, k, n) for n, v in (("c", c), ("x0", x0), ("y0", y0)))
    try:
        start = intersect_points(
            xy, np.arange(k), np.zeros(k, int), X0, R, cc, xx0, yy0, rigorous=False
        )
    except NotDeterminableError as exc:
        raise NotDeterminableError(
            str(exc).replace("point(s) 0", "the point"), parameters=["X", "Y", "Z"]
        ) from None
    sg = np.asarray(sigma, dtype=float)
    sg = np.broadcast_to(sg[:, None] if sg.ndim == 1 else sg, (k, 2)).reshape(-1)

    def equations(X: F64):
        f, J = _point_jacobian(np.tile(X, (k, 1)), X0, R, cc, xx0, yy0)
        return f.reshape(-1), J.reshape(2 * k, 3)

    ids = [str(i) for i in range(k)] if image_ids is None else [str(i) for i in image_ids]
    res = gauss_newton(
        equations, start.xyz[0], xy.reshape(-1), sg, names=["X", "Y", "Z"],
        obs_labels=[f"{i}/{a}" for i in ids for a in "xy"], context="forward intersection",
    )  # fmt: skip
    return res.extend(ForwardIntersection, start=start.xyz[0])
