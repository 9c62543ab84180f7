"""Absolute orientation: the 3D similarity (7 parameters) and rigid (6) transformations.

A relatively oriented model is brought into the object (control) frame by a
translation, a spatial rotation and a scale ("Verschiebung und räumliche Drehstreckung",
Leeb 1968)::

    X = T + m · R · x

with ``x`` the model (source) coordinates, ``X`` the object (target) coordinates in m,
``T = (tx, ty, tz)`` in m, ``m`` the scale (dimensionless) and ``R = R(ω, φ, κ)`` built
by :func:`orientviz.rotation.matrix_from_opk` — rotations about the *object* axes, by
default in the sequence ω-φ-κ (``R = R_ω R_φ R_κ``), optionally φ-ω-κ.

Two solutions are offered:

* :func:`similarity_closed_form` — a direct, weighted solution via the singular value
  decomposition of the cross-covariance of the centred point sets (no start values,
  reflection-safe: always det R = +1). Needs ≥ 3 non-collinear points with all three
  coordinates known in both frames.
* :func:`similarity_transform` — least squares on the engine
  (:func:`orientviz.adjust.gauss_newton`) with precision, correlations and residuals per
  control coordinate. Control coordinates are weighted one by one, so planimetric-only
  (X, Y) and height-only (Z) control points take part with just their known coordinates.

Which coordinates are observations? Classically the **model coordinates are treated as
errorless constants** and only the control (target) coordinates are observed; σ̂0 then
absorbs both error sources. If ``sigma_source`` is given, the model coordinates become
observations too and the model points become unknowns (a Gauss-Markov model equivalent
to the Gauss-Helmert adjustment of both coordinate sets); the residuals then come in two
groups, model first, control second.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment, gauss_newton
from ..errors import InputError, NotDeterminableError
from ..rotation import check_sequence, matrix_derivatives, matrix_from_opk, opk_from_matrix

F64 = NDArray[np.float64]

#: Parameter names of the 7-parameter transformation, in the order of ``Adjustment.x``.
NAMES: tuple[str, ...] = ("tx", "ty", "tz", "omega", "phi", "kappa", "scale")
#: Relative singular value below which a point set counts as collinear.
COLLINEAR_TOLERANCE: float = 1e-9


@dataclass(frozen=True)
class SimilarityTransform:
    """A 3D similarity transformation ``X = t + scale · R · x``.

    Attributes
    ----------
    scale : float
        Scale factor m (dimensionless, > 0); 1 for a rigid transformation.
    R : ndarray, shape (3, 3)
        Proper rotation (det +1) from the source (model) frame to the target frame.
    t : ndarray, shape (3,)
        Translation in target units (m): the target coordinates of the source origin.
    """

    scale: float
    R: F64
    t: F64

    def apply(self, points: ArrayLike) -> F64:
        """Transform source points (n, 3) (or one point (3,)) into the target frame."""
        p = np.asarray(points, dtype=float)
        return self.t + self.scale * (p @ self.R.T)

    def inverse(self) -> SimilarityTransform:
        """The transformation from target back to source: ``x = R⁻¹ (X − t) / m``."""
        Rt = self.R.T
        return SimilarityTransform(1.0 / self.scale, Rt, -(Rt @ self.t) / self.scale)

    def angles(self, sequence: str = "opk") -> F64:
        """ω, φ, κ of ``R`` in radians for the rotation sequence ``sequence`` ("opk"/"pok")."""
        return np.array([float(a) for a in opk_from_matrix(self.R, sequence)])

    def params(self, sequence: str = "opk") -> F64:
        """(tx, ty, tz [m], ω, φ, κ [rad], scale) for the given rotation sequence."""
        return np.concatenate([self.t, self.angles(sequence), [self.scale]])

    @classmethod
    def from_params(cls, params: ArrayLike, sequence: str = "opk") -> SimilarityTransform:
        """Build from (tx, ty, tz [m], ω, φ, κ [rad], scale), angles in ``sequence``."""
        p = np.asarray(params, dtype=float).reshape(-1)
        if p.shape != (7,):
            raise InputError(f"similarity parameters: expected 7 values, got {p.shape[0]}")
        return cls(float(p[6]), matrix_from_opk(p[3], p[4], p[5], sequence), p[:3].copy())


@dataclass
class SimilarityResult(Adjustment):
    """The result of :func:`similarity_transform`: the engine's fields plus the transform.

    Attributes
    ----------
    transform : SimilarityTransform
        The estimated transformation.
    start : SimilarityTransform
        The approximate values it started from.
    sequence : str
        Rotation sequence of ω, φ, κ in ``x``.
    used : ndarray of bool, shape (n, 3)
        The control coordinates that entered.
    residuals_xyz : ndarray, shape (n, 3)
        Residuals v per control coordinate, m (NaN where not used).
    transformed : ndarray, shape (n, 3)
        The source points in the target frame, m (adjusted ones with ``sigma_source``).
    """

    transform: SimilarityTransform | None = None
    start: SimilarityTransform | None = None
    sequence: str = "opk"
    used: NDArray[np.bool_] | None = None
    residuals_xyz: F64 | None = None
    transformed: F64 | None = None


# --------------------------------------------------------------------------- validation
def _check_pair(source: ArrayLike, target: ArrayLike) -> tuple[F64, F64]:
    try:
        s = np.asarray(source, dtype=float)
        t = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise InputError("source/target: expected arrays of numbers") from None
    if s.ndim != 2 or s.shape[1] != 3:
        raise InputError(f"source points: expected shape (n, 3), got {s.shape}")
    if t.shape != s.shape:
        raise InputError(f"target points: expected shape {s.shape} like the source, got {t.shape}")
    if not np.all(np.isfinite(s)):
        raise InputError("source points: expected finite coordinates, got NaN or inf")
    return s, t


def _spread_rank(points: F64) -> int:
    """Number of independent directions of a centred point set (0..3)."""
    if points.shape[0] < 2:
        return 0
    sv = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    if sv[0] <= 0:
        return 0
    return int(np.sum(sv > COLLINEAR_TOLERANCE * sv[0]))


# --------------------------------------------------------------------------- closed form
def similarity_closed_form(
    source: ArrayLike, target: ArrayLike, weights: ArrayLike | None = None, *, scale: bool = True
) -> SimilarityTransform:
    """Direct weighted similarity (or rigid) transformation via SVD; no start values.

    Minimises ``Σ w_i |X_i − t − m R x_i|²`` over t, R (det R = +1) and m: centre both
    sets on their weighted centroids, decompose the weighted cross-covariance
    ``H = Σ w_i (X_i − X̄)(x_i − x̄)ᵀ = U D Vᵀ`` and take ``R = U S Vᵀ`` with
    ``S = diag(1, 1, det(U Vᵀ))`` (this is what excludes reflections),
    ``m = tr(D S) / Σ w_i |x_i − x̄|²`` and ``t = X̄ − m R x̄``.

    Parameters
    ----------
    source : array_like, shape (n, 3)
        Model (source) coordinates, any length unit.
    target : array_like, shape (n, 3)
        Object (target) coordinates in m. Rows with a NaN are ignored (the closed form
        needs full XYZ points; use :func:`similarity_transform` for partial control).
    weights : array_like, shape (n,), optional
        Weight per point (≥ 0), e.g. 1/σ²; default 1.
    scale : bool, default True
        Estimate the scale (7 parameters); ``False`` fixes m = 1 (rigid, 6 parameters).

    Returns
    -------
    SimilarityTransform
        ``R`` maps source to target axes; angles via :meth:`SimilarityTransform.angles`.

    Raises
    ------
    InputError
        Wrong shapes, negative weights.
    NotDeterminableError
        Fewer than 3 usable points, or all usable points on one line (the rotation
        about that line is free).
    """
    s, t = _check_pair(source, target)
    w = np.ones(s.shape[0]) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
    if w.shape != (s.shape[0],):
        raise InputError(f"weights: expected shape ({s.shape[0]},), got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InputError("weights: expected finite non-negative weights")
    use = np.all(np.isfinite(t), axis=1) & (w > 0)
    s, t, w = s[use], t[use], w[use]
    if s.shape[0] < 3:
        raise NotDeterminableError(
            f"similarity transformation: needs at least 3 full XYZ control points, got {s.shape[0]}",
            parameters=list(NAMES),
        )
    if _spread_rank(s) < 2 or _spread_rank(t) < 2:
        raise NotDeterminableError(
            "similarity transformation: the control points are collinear; "
            "the rotation about their line is not determinable",
            parameters=["omega", "phi", "kappa"],
            defect=1,
        )
    W = w.sum()
    sc = (w @ s) / W
    tc = (w @ t) / W
    ds, dt = s - sc, t - tc
    H = (dt * w[:, None]).T @ ds  # Σ w (X − X̄)(x − x̄)ᵀ
    U, D, Vt = np.linalg.svd(H)
    S = np.ones(3)
    S[2] = np.sign(np.linalg.det(U) * np.linalg.det(Vt)) or 1.0
    R = (U * S) @ Vt
    m = float((D * S).sum() / (w @ np.sum(ds**2, axis=1))) if scale else 1.0
    if m <= 0:
        raise NotDeterminableError(
            "similarity transformation: the control gives no positive scale", parameters=["scale"]
        )
    return SimilarityTransform(m, R, tc - m * (R @ sc))


def _planimetric_start(s: F64, t: F64, used: NDArray[np.bool_], scale: bool) -> SimilarityTransform:
    """Start values for near-vertical models with partial control (ω = φ = 0).

    A 2D similarity from the points with known X and Y gives κ, m, tx, ty; the points
    with known Z give tz.
    """
    xy = used[:, 0] & used[:, 1]
    z = used[:, 2]
    if xy.sum() < 2 or not z.any():
        raise NotDeterminableError(
            "similarity transformation: needs at least 2 planimetric (X, Y) and 1 height control "
            "points (or 3 full XYZ points); "
            f"got {int(xy.sum())} planimetric and {int(z.sum())} height coordinates",
            parameters=list(NAMES),
        )
    a = s[xy, 0] + 1j * s[xy, 1]
    b = t[xy, 0] + 1j * t[xy, 1]
    a0, b0 = a - a.mean(), b - b.mean()
    k = np.vdot(a0, b0) / np.vdot(a0, a0).real  # b0 ≈ k a0, k = m e^{iκ}
    m = abs(k) if scale else 1.0
    kap = float(np.angle(k))
    R = matrix_from_opk(0.0, 0.0, kap)
    txy = b.mean() - m * np.exp(1j * kap) * a.mean()
    tz = float(np.mean(t[z, 2] - m * s[z, 2]))
    return SimilarityTransform(float(m), R, np.array([txy.real, txy.imag, tz]))


def _sigma_table(sigma: ArrayLike, n: int, name: str) -> F64:
    sg = np.asarray(sigma, dtype=float)
    try:
        sg = np.broadcast_to(sg, (n, 3)).copy()
    except ValueError:
        raise InputError(
            f"{name}: expected a float, shape (3,) or ({n}, 3), got {sg.shape}"
        ) from None
    if np.any(sg[np.isfinite(sg)] <= 0):
        raise InputError(
            f"{name}: expected σ > 0 in m (NaN/inf marks a coordinate that is not given; "
            "a fixed coordinate σ = 0 is not supported, use a small σ)"
        )
    return sg


# --------------------------------------------------------------------------- least squares
def similarity_model(
    params: ArrayLike, points: ArrayLike, sequence: str = "opk"
) -> tuple[F64, F64]:
    """Transformed points and their Jacobian with respect to the 7 parameters.

    Parameters
    ----------
    params : array_like, shape (7,)
        (tx, ty, tz [m], ω, φ, κ [rad], scale), angles in ``sequence``.
    points : array_like, shape (n, 3)
        Source (model) points.
    sequence : {"opk", "pok"}, default "opk"
        Rotation sequence of the angles.

    Returns
    -------
    f : ndarray, shape (n, 3)
        ``t + m R x`` in m.
    J : ndarray, shape (n, 3, 7)
        ∂f/∂(tx, ty, tz, ω, φ, κ, m) in m/m, m/rad and m per unit scale.
    """
    p = np.asarray(params, dtype=float).reshape(-1)
    pts = np.asarray(points, dtype=float)
    R = matrix_from_opk(p[3], p[4], p[5], sequence)
    dR = matrix_derivatives(p[3], p[4], p[5], sequence)
    Rx = pts @ R.T
    J = np.empty((pts.shape[0], 3, 7))
    J[:, :, :3] = np.eye(3)
    for k in range(3):
        J[:, :, 3 + k] = p[6] * (pts @ dR[k].T)
    J[:, :, 6] = Rx
    return p[:3] + p[6] * Rx, J


def similarity_transform(
    source: ArrayLike,
    target: ArrayLike,
    *,
    sigma_target: ArrayLike = 0.01,
    sigma_source: ArrayLike | None = None,
    rigid: bool = False,
    sequence: str = "opk",
    start: SimilarityTransform | None = None,
    point_ids: list[str] | None = None,
    max_iter: int = 30,
) -> SimilarityResult:
    """Least-squares 3D similarity (7 p.) or rigid (6 p.) transformation with precision.

    Model: ``X_i + v_X = t + m R(ω, φ, κ) x_i`` for every *given* control coordinate.

    Parameters
    ----------
    source : array_like, shape (n, 3)
        Model (source) coordinates; errorless unless ``sigma_source`` is given.
    target : array_like, shape (n, 3)
        Control (object) coordinates in m; NaN marks a coordinate that is not given
        (e.g. ``[x, y, nan]`` planimetric or ``[nan, nan, z]`` height control).
    sigma_target : float or array_like, shape (3,) or (n, 3), default 0.01
        A-priori σ of the control coordinates in m; NaN/inf also marks "not given".
    sigma_source : float or array_like, shape (3,) or (n, 3), optional
        A-priori σ of the model coordinates (source units). When given, the model points
        become unknowns (names ``"<id>.x"`` …) observed with this σ.
    rigid : bool, default False
        Fix the scale at m = 1 (6-parameter rigid transformation); ``"scale"`` then stays
        in ``names`` with standard deviation 0.
    sequence : {"opk", "pok"}, default "opk"
        Rotation sequence of ω, φ, κ: ``R = R_ω R_φ R_κ`` or ``R = R_φ R_ω R_κ``.
    start : SimilarityTransform, optional
        Approximate values; default the closed form (≥ 3 full points) or, for partial
        control, a planimetric 2D start with ω = φ = 0 (near-vertical models).
    point_ids : list of str, optional
        Point names for the residual labels (default ``"0"``, ``"1"``, …).
    max_iter : int, default 30
        Maximum number of Gauss-Newton steps.

    Returns
    -------
    SimilarityResult
        ``names`` = ``("tx", "ty", "tz", "omega", "phi", "kappa", "scale")`` (+ model
        points), m and rad; residuals ``v = f(x̂) − l`` in m per control coordinate,
        labelled ``"<id>/X"``; ``transform`` (SimilarityTransform), ``start`` (the start
        transform), ``sequence``, ``used`` ((n, 3) bool mask of the control coordinates
        used), ``residuals_xyz`` ((n, 3) m, NaN where unused), ``transformed`` ((n, 3)
        transformed source points).

    Raises
    ------
    InputError
        Wrong shapes, non-positive σ.
    NotDeterminableError
        Too little or collinear control (names the parameters concerned), or a rotation
        in gimbal lock for the chosen sequence (secondary angle ±100 gon), where the
        angles cannot be separated — use the other sequence there.

    Notes
    -----
    The partial-control start (ω = φ = 0) converged in tests for tilts up to 40 gon;
    pass ``start`` for models that are tilted more.
    """
    seq = check_sequence(sequence)
    s, t = _check_pair(source, target)
    n = s.shape[0]
    st = _sigma_table(sigma_target, n, "sigma_target")
    used = np.isfinite(t) & np.isfinite(st)
    n_obs = int(used.sum())
    u = 6 if rigid else 7
    if n_obs < u:
        raise NotDeterminableError(
            f"similarity transformation: {u} parameters need at least {u} control coordinates, "
            f"got {n_obs}",
            parameters=list(NAMES[:u]),
        )
    ids = [str(i) for i in range(n)] if point_ids is None else [str(i) for i in point_ids]
    if len(ids) != n:
        raise InputError(f"point_ids: expected {n} ids, got {len(ids)}")
    if start is None:
        full = used.all(axis=1)
        if full.sum() >= 3 and _spread_rank(s[full]) >= 2:
            start = similarity_closed_form(s[full], t[full], scale=not rigid)
        else:
            start = _planimetric_start(s, t, used, not rigid)
    x0 = start.params(seq)
    if rigid:
        x0[6] = 1.0
    rows, cols = np.nonzero(used)  # control coordinates in row-major order
    l_ctrl = t[rows, cols]
    s_ctrl = st[rows, cols]
    labels = [f"{ids[i]}/{'XYZ'[k]}" for i, k in zip(rows, cols)]
    fixed = np.zeros(7, bool)
    fixed[6] = rigid
    names = list(NAMES)
    groups = {"transform": slice(0, 7)}

    def transform_jac(p: F64, pts: F64):
        f, J = similarity_model(p, pts, seq)
        return f, J, matrix_from_opk(p[3], p[4], p[5], seq)

    if sigma_source is None:

        def equations(p: F64):
            f, J, _ = transform_jac(p, s)
            return f[rows, cols], J[rows, cols, :]

        res = gauss_newton(
            equations, x0, l_ctrl, s_ctrl, names=names, groups=groups, obs_labels=labels,
            fixed=fixed, max_iter=max_iter, context="similarity transformation",
        )  # fmt: skip
    else:
        ss = _sigma_table(sigma_source, n, "sigma_source")
        if not np.all(np.isfinite(ss)):
            raise InputError("sigma_source: expected finite σ > 0 for every model coordinate")
        names += [f"{i}.{a}" for i in ids for a in "xyz"]
        groups["model points"] = slice(7, 7 + 3 * n)
        x0 = np.concatenate([x0, s.reshape(-1)])
        fixed = np.concatenate([fixed, np.zeros(3 * n, bool)])
        l_all = np.concatenate([s.reshape(-1), l_ctrl])
        s_all = np.concatenate([ss.reshape(-1), s_ctrl])
        labels = [f"{i}/{a}" for i in ids for a in "xyz"] + labels
        eye = sp.identity(3 * n, format="csr")
        ctrl_idx = rows * 3 + cols

        def equations(p: F64):
            pts = p[7:].reshape(n, 3)
            f, J, R = transform_jac(p, pts)
            Jt = sp.csr_matrix(J[rows, cols, :])
            # ∂X_i/∂x_i = m R (3x3 block per point), taken at the used rows only
            blk = sp.block_diag([p[6] * R] * n, format="csr")[ctrl_idx]
            top = sp.hstack([sp.csr_matrix((3 * n, 7)), eye])
            bottom = sp.hstack([Jt, blk])
            return np.concatenate([p[7:], f[rows, cols]]), sp.vstack([top, bottom], format="csr")

        res = gauss_newton(
            equations, x0, l_all, s_all, names=names, groups=groups, obs_labels=labels,
            fixed=fixed, max_iter=max_iter, context="similarity transformation",
        )  # fmt: skip
    tf = SimilarityTransform.from_params(res.x[:7], seq)
    vxyz = np.full((n, 3), np.nan)
    vxyz[rows, cols] = res.residuals[-n_obs:]
    return res.extend(
        SimilarityResult,
        transform=tf,
        start=start,
        sequence=seq,
        used=used,
        residuals_xyz=vxyz,
        transformed=tf.apply(s if sigma_source is None else res.x[7:].reshape(n, 3)),
    )
