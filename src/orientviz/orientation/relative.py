"""Relative orientation of a stereo pair from y-parallaxes.

**Conventions** (used throughout ``relative``, ``schemes`` and ``plotter``).

*Model frame*: origin at the left projection centre O1, X along the base towards the
right projection centre O2, Y to the left of the flight direction (towards the upper
image edge), Z up; right-handed. Model points lie *below* the projection centres, so
**Z < 0**; the "ordinate" (projection distance) is ``|Z|``. Model units are the
plotter's machine millimetres (or any length unit, as long as the base ``b`` and the
coordinates share it).

*Dependent pair* ("Folgebildanschluss"): the left bundle is fixed (R1 = I); the right
bundle has the base components ``by``, ``bz`` (O2 = (b, by, bz)) and the rotation
``R2 = matrix_from_opk(omega, phi, kappa, sequence)`` (right-handed about X, Y, Z; see
:mod:`orientviz.rotation`). Elements in this order: ``by, bz, omega, phi, kappa``.

*Independent pair*: O1 = 0, O2 = (b, 0, 0); the left bundle turns by (0, φ1, κ1), the
right by (ω2, φ2, κ2). Elements: ``phi1, kappa1, phi2, omega2, kappa2``.

*y-parallax* at a point: the two rays are intersected in their projection on the XZ
plane (where the operator clears the x-parallax) and ``p_y = Y_left − Y_right`` there.
This is the amount by which the right projector's ``by`` has to move to clear the
parallax, i.e. the *by reading* of a plotter relative to the current ``by``. The
corrections ``d`` that clear all parallaxes satisfy, to first order about the normal
case (all elements zero),

    p_y = dby − (Y/Z) dbz − Z (1 + Y²/Z²) dω − (b − X)(Y/Z) dφ − (b − X) dκ.

Kovarik (1968) prints ``p_y = dby + (y/z) dbz − z(1 + y²/z²) dω − ((b−x) y/z) dφ +
(b−x) dκ`` with z the (negative) model ordinate and the upper edge at y > 0 — his
closed-form 9-point formulas are consistent with exactly that (``y3/z = −k``). His
equation equals ours when his ``dbz`` and ``dκ`` are counted the other way round (bz
positive downwards, along the plotter's z counter; κ clockwise seen from above); see
:data:`KOVARIK_SIGNS`. Angles are radians inside; the papers' centesimal minutes (c)
appear only at the edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust.engine import gauss_newton
from ..adjust.rank import describe_defect, null_space_of_normal
from ..adjust.result import Adjustment
from ..errors import InputError, NotDeterminableError
from ..rotation import check_sequence, matrix_derivatives, matrix_from_opk
from .relative_collinearity import collinearity_pair
from .relative_coplanarity import coplanarity_pair

F64 = NDArray[np.float64]

#: Element names of a dependent pair (right bundle to the fixed left one).
DEPENDENT: tuple[str, ...] = ("by", "bz", "omega", "phi", "kappa")
#: Element names of an independent pair (base fixed along X).
INDEPENDENT: tuple[str, ...] = ("phi1", "kappa1", "phi2", "omega2", "kappa2")
#: orientviz element = KOVARIK_SIGNS × Kovarik's element (dependent pair order).
KOVARIK_SIGNS: F64 = np.array([1.0, -1.0, 1.0, 1.0, -1.0])
#: The estimators of :func:`relative_orientation`.
METHODS: tuple[str, ...] = ("parallax", "collinearity", "coplanarity")
#: Below this smallest/largest eigenvalue ratio of the Jacobi-scaled normal matrix of
#: the linearised equations a geometry counts as critical (not determinable).
CRITICAL_TOLERANCE: float = 1e-7


def _elements(kind: str) -> tuple[str, ...]:
    if kind == "dependent":
        return DEPENDENT
    if kind == "independent":
        return INDEPENDENT
    raise InputError(f"expected kind 'dependent' or 'independent', got {kind!r}")


def check_points(points: ArrayLike, name: str = "points", min_points: int = 0) -> F64:
    """Return ``points`` as a float array of shape (n, k) or raise :class:`InputError`."""
    a = np.asarray(points, dtype=float)
    if a.ndim != 2:
        raise InputError(f"expected {name} of shape (n, k), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"expected finite {name}, got NaN or inf")
    if a.shape[0] < min_points:
        raise InputError(
            f"relative orientation needs at least {min_points} points (5 elements), "
            f"got {a.shape[0]}"
        )
    return a


# ------------------------------------------------------------------ linearised model
def design_dependent(X: ArrayLike, Y: ArrayLike, Z: ArrayLike, b: float) -> F64:
    """Linearised y-parallax equation of a dependent pair (orientviz signs).

    Parameters
    ----------
    X, Y, Z : array_like, shape (n,)
        Model coordinates of the points (model units, Z < 0 below the base).
    b : float
        Model base (X of O2), model units.

    Returns
    -------
    ndarray, shape (n, 5)
        ∂p_y/∂(by, bz, ω, φ, κ) in model units per model unit and per radian, so that
        ``p_y ≈ A @ d`` for the corrections d that clear the parallaxes.
    """
    X, Y, Z = (np.asarray(v, dtype=float) for v in (X, Y, Z))
    q = Y / Z
    A = np.empty(np.broadcast(X, Y, Z).shape + (5,))
    A[..., 0] = 1.0
    A[..., 1] = -q
    A[..., 2] = -Z * (1.0 + q * q)
    A[..., 3] = -(b - X) * q
    A[..., 4] = -(b - X)
    return A


def design_independent(X: ArrayLike, Y: ArrayLike, Z: ArrayLike, b: float) -> F64:
    """Linearised y-parallax equation of an independent pair.

    ``p_y = −X(Y/Z) dφ1 − X dκ1 − (b − X)(Y/Z) dφ2 − Z(1 + Y²/Z²) dω2 − (b − X) dκ2``
    (model units and radians; same frame and sign of p_y as :func:`design_dependent`).

    Returns
    -------
    ndarray, shape (n, 5)
        Columns in the order φ1, κ1, φ2, ω2, κ2.
    """
    X, Y, Z = (np.asarray(v, dtype=float) for v in (X, Y, Z))
    q = Y / Z
    A = np.empty(np.broadcast(X, Y, Z).shape + (5,))
    A[..., 0] = -X * q
    A[..., 1] = -X
    A[..., 2] = -(b - X) * q
    A[..., 3] = -Z * (1.0 + q * q)
    A[..., 4] = -(b - X)
    return A


def design(X: ArrayLike, Y: ArrayLike, Z: ArrayLike, b: float, kind: str = "dependent") -> F64:
    """:func:`design_dependent` or :func:`design_independent` by ``kind``."""
    _elements(kind)
    return (design_dependent if kind == "dependent" else design_independent)(X, Y, Z, b)


def kovarik_to_orientviz(elements: ArrayLike) -> F64:
    """Kovarik's (dby, dbz, dω, dφ, dκ) → orientviz's dependent-pair elements (same units)."""
    return np.asarray(elements, dtype=float) * KOVARIK_SIGNS


def orientviz_to_kovarik(elements: ArrayLike) -> F64:
    """orientviz's (by, bz, ω, φ, κ) → Kovarik's sign convention (same units)."""
    return np.asarray(elements, dtype=float) * KOVARIK_SIGNS


def check_determinable(A: ArrayLike, names: tuple[str, ...] | list[str], context: str = "") -> None:
    """Raise :class:`NotDeterminableError` if the design ``A`` cannot determine all elements.

    The normal matrix AᵀA is scaled to unit diagonal; a smallest/largest eigenvalue
    ratio below :data:`CRITICAL_TOLERANCE` counts as a defect (points on one profile,
    on a danger cylinder through the base, too few distinct points). The message names
    the elements that take part in the undetermined combinations.
    """
    A = np.asarray(A, dtype=float)
    null = null_space_of_normal(A.T @ A, tol=CRITICAL_TOLERANCE)
    if null.shape[1] == 0:
        return
    involved = describe_defect(list(names), null)
    prefix = f"{context}: " if context else ""
    raise NotDeterminableError(
        f"{prefix}{null.shape[1]} combination(s) of the relative orientation elements not "
        f"determinable from these points (critical geometry); involved: {', '.join(involved)}",
        parameters=involved,
        defect=null.shape[1],
    )


# ------------------------------------------------------------------ rigorous model
@dataclass
class PairState:
    """Orientation of a pair in the model frame (see the module docstring).

    Attributes
    ----------
    base : ndarray, shape (3,)
        O2 − O1 = (b, by, bz), model units.
    angles_left, angles_right : ndarray, shape (3,)
        ω, φ, κ of each bundle in radians (``sequence``).
    sequence : str
        Rotation sequence, ``"opk"`` (R = R_ω R_φ R_κ) or ``"pok"`` (R = R_φ R_ω R_κ).
    """

    base: F64
    angles_left: F64
    angles_right: F64
    sequence: str = "opk"

    @classmethod
    def from_elements(
        cls, elements: ArrayLike, b: float, kind: str = "dependent", sequence: str = "opk"
    ) -> PairState:
        """State from the five elements of ``kind`` (radians, model units)."""
        e = np.asarray(elements, dtype=float).reshape(5)
        if kind == "dependent":
            return cls(np.array([b, e[0], e[1]]), np.zeros(3), e[2:5].copy(), sequence)
        _elements(kind)
        return cls(
            np.array([b, 0.0, 0.0]),
            np.array([0.0, e[0], e[1]]),
            np.array([e[3], e[2], e[4]]),
            sequence,
        )


@dataclass
class RelativeResult(Adjustment):
    """The result of a relative orientation: the engine's fields plus the pair.

    Attributes
    ----------
    kind : {"dependent", "independent"}
        Which five elements ``x`` holds (see the module docstring).
    base : float
        The model base bx, model units (mm at image scale by default).
    sequence : str
        Rotation sequence of the angles.
    c : float
        Principal distance, mm.
    points : ndarray, shape (n, 3)
        The model points at the estimated elements, model units (Z < 0).
    state : PairState
        The estimated orientation of the pair in the model frame.
    method : {"parallax", "collinearity", "coplanarity"}
        The estimator (see :func:`relative_orientation`).
    """

    kind: str = "dependent"
    base: float = float("nan")
    sequence: str = "opk"
    c: float = float("nan")
    points: F64 | None = None
    state: PairState | None = None
    method: str = "parallax"


def _rays(xy: F64, angles: F64, c: float, sequence: str, derivatives: bool = True):
    d = np.empty((xy.shape[0], 3))
    d[:, :2] = xy
    d[:, 2] = -c
    R = matrix_from_opk(*angles, sequence=sequence)
    if not derivatives:
        return d @ R.T, None
    dR = matrix_derivatives(*angles, sequence=sequence)
    return d @ R.T, [d @ D.T for D in dR]


def _cross(a: F64, b: F64) -> F64:
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def y_parallax(
    xy_left: ArrayLike, xy_right: ArrayLike, c: float, state: PairState
) -> tuple[F64, F64]:
    """Rigorous y-parallaxes and model points of image-point pairs.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates in mm (principal point at the origin).
    c : float
        Principal distance, mm.
    state : PairState
        Orientation of the pair.

    Returns
    -------
    p_y : ndarray, shape (n,)
        ``Y_left − Y_right`` where the rays meet in the XZ projection, model units
        (equals −B·(r1 × r2) / (r1z r2x − r1x r2z)).
    points : ndarray, shape (n, 3)
        The model points: X, Z of that meeting point, Y the mean of the two rays.
    """
    p, pts, _ = _parallax_and_jacobian(
        check_points(xy_left, "xy_left"), check_points(xy_right, "xy_right"), c, state, None
    )
    return p, pts


def _parallax_and_jacobian(xy1: F64, xy2: F64, c: float, st: PairState, kind: str | None):
    seq = st.sequence
    need = kind is not None
    r1, dr1 = _rays(xy1, st.angles_left, c, seq, need and kind == "independent")
    r2, dr2 = _rays(xy2, st.angles_right, c, seq, need)
    B = st.base
    D = r1[:, 2] * r2[:, 0] - r1[:, 0] * r2[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (r2[:, 0] * B[2] - r2[:, 2] * B[0]) / D
        mu = (r1[:, 0] * B[2] - r1[:, 2] * B[0]) / D
    cross = _cross(r1, r2)
    p = -(cross @ B) / D
    pts = np.empty((xy1.shape[0], 3))
    pts[:, 0] = lam * r1[:, 0]
    pts[:, 1] = 0.5 * (lam * r1[:, 1] + B[1] + mu * r2[:, 1])
    pts[:, 2] = lam * r1[:, 2]
    if kind is None:
        return p, pts, None
    # dp = −(dg + p dD) / D with g = B·(r1 × r2)
    Bb = np.broadcast_to(B, r1.shape)
    Bxr1 = _cross(Bb, r1)
    r2xB = _cross(r2, Bb)

    def d_right(dr):
        return -((dr * Bxr1).sum(1) + p * (r1[:, 2] * dr[:, 0] - r1[:, 0] * dr[:, 2])) / D

    def d_left(dr):
        return -((dr * r2xB).sum(1) + p * (dr[:, 2] * r2[:, 0] - dr[:, 0] * r2[:, 2])) / D

    J = np.empty((xy1.shape[0], 5))
    if kind == "dependent":
        J[:, 0] = -cross[:, 1] / D
        J[:, 1] = -cross[:, 2] / D
        J[:, 2] = d_right(dr2[0])
        J[:, 3] = d_right(dr2[1])
        J[:, 4] = d_right(dr2[2])
    else:
        J[:, 0] = d_left(dr1[1])
        J[:, 1] = d_left(dr1[2])
        J[:, 2] = d_right(dr2[1])
        J[:, 3] = d_right(dr2[0])
        J[:, 4] = d_right(dr2[2])
    return p, pts, J


def y_parallax_jacobian(
    xy_left: ArrayLike,
    xy_right: ArrayLike,
    c: float,
    elements: ArrayLike,
    b: float,
    kind: str = "dependent",
    sequence: str = "opk",
) -> tuple[F64, F64]:
    """Rigorous y-parallaxes and their derivatives by the five elements of ``kind``.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates, mm.
    c : float
        Principal distance, mm.
    elements : array_like, shape (5,)
        ``by, bz, ω, φ, κ`` (dependent) or ``φ1, κ1, φ2, ω2, κ2`` (independent); model
        units and radians.
    b : float
        Model base (bx), model units.
    kind : {"dependent", "independent"}
    sequence : {"opk", "pok"}

    Returns
    -------
    p_y : ndarray, shape (n,)
        y-parallaxes, model units.
    J : ndarray, shape (n, 5)
        ∂p_y/∂elements (model units per model unit / per radian). Note the sign: a
        correction d clears the parallax when J d ≈ −p_y.
    """
    _elements(kind)  # validates kind
    st = PairState.from_elements(elements, b, kind, check_sequence(sequence))
    p, _, J = _parallax_and_jacobian(
        check_points(xy_left, "xy_left"), check_points(xy_right, "xy_right"), c, st, kind
    )
    return p, J


# ------------------------------------------------------------------ estimation
def relative_orientation(
    xy_left: ArrayLike,
    xy_right: ArrayLike,
    c: float,
    *,
    kind: str = "dependent",
    b: float | str | None = None,
    sigma: float = 0.005,
    approx: ArrayLike | None = None,
    sequence: str = "opk",
    max_iter: int = 20,
    labels: list[str] | None = None,
    method: str = "parallax",
) -> RelativeResult:
    """Relative orientation from image coordinates of n ≥ 5 points (least squares).

    ``method="parallax"`` (Kovarik's estimator, the default): the rigorous y-parallaxes
    (:func:`y_parallax`) are the observations, each observed as zero with standard
    deviation ``sigma``; the five elements are adjusted by
    :func:`orientviz.adjust.gauss_newton`. ``method="collinearity"`` (the textbook
    method, e.g. Wolf/DeWitt): starting from that solution, all 4n image coordinates
    are observations of the collinearity equations (σ = ``sigma`` brought to image
    scale, sigma · c / mean ``|Z|`` of the model points, mm), and the five
    elements are adjusted together with the 3n model points
    (:func:`orientviz.orientation.relative_collinearity.collinearity_pair`); dependent
    pairs only. ``method="coplanarity"`` (the textbook's other method): one condition
    per point, the triple product F = B·(r1 × r2) of the base and the two rays = 0, its
    σ propagated from image coordinates of σ = sigma · c / mean ``|Z|`` (mm); the
    residuals are the triple products at the estimate, model units
    (:mod:`orientviz.orientation.relative_coplanarity`); both kinds. All three agree
    for error-free data; coplanarity and collinearity also with measuring errors, up
    to terms of the second order in them.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Homologous image coordinates in mm, reduced to the principal point.
    c : float
        Principal distance, mm (both images).
    kind : {"dependent", "independent"}
        Which five elements (see the module docstring).
    b : float or {"median", "mean"}, optional
        Model base in model units; by default (or ``"median"``) the median x-parallax
        x' − x'' (mm), which puts the model at about image scale (Z ≈ −c); ``"mean"``
        the mean x-parallax, as many textbooks choose it.
    sigma : float
        A-priori σ of a y-parallax in model units (default 5 µm at image scale).
    approx : array_like, shape (5,), optional
        Approximate elements (default: the normal case, all zero).
    sequence : {"opk", "pok"}
        Rotation sequence of the angles.
    max_iter : int
        Maximum number of Gauss-Newton steps.
    labels : list of str, optional
        Point labels for the residual report.
    method : {"parallax", "collinearity", "coplanarity"}
        The estimator (see above).

    Returns
    -------
    RelativeResult
        ``x`` = the five elements (model units, radians), with σ0, cofactors,
        correlations and per-iteration history; ``kind``, ``base``, ``sequence``, ``c``,
        ``points`` (the model points, shape (n, 3)) and ``state``.

    Raises
    ------
    InputError
        Fewer than 5 points, mismatched shapes, non-finite values, zero base.
    NotDeterminableError
        Critical geometry (points on one profile, on a danger cylinder containing the
        base, …); the message names the elements involved.
    """
    names = _elements(kind)
    seq = check_sequence(sequence)
    xy1 = check_points(xy_left, "xy_left", min_points=5)
    xy2 = check_points(xy_right, "xy_right", min_points=5)
    if xy1.shape != xy2.shape or xy1.shape[1] != 2:
        raise InputError(
            f"expected xy_left and xy_right of the same shape (n, 2), got {xy1.shape} and {xy2.shape}"
        )
    if not np.isfinite(c) or c <= 0:
        raise InputError(f"expected a principal distance c > 0 mm, got {c}")
    if method not in METHODS:
        raise InputError(f"expected method {' or '.join(map(repr, METHODS))}, got {method!r}")
    if method == "collinearity" and kind != "dependent":
        raise InputError("method 'collinearity' estimates a dependent pair; use kind 'dependent'")
    if b is None or isinstance(b, str):
        if b not in (None, "median", "mean"):
            raise InputError(f"expected a base length, 'median' or 'mean', got {b!r}")
        px = xy1[:, 0] - xy2[:, 0]
        b = float(np.mean(px) if b == "mean" else np.median(px))
    if not np.isfinite(b) or abs(b) < 1e-9 * c:
        raise InputError(
            "zero base: the images show no x-parallax (b = 0), so the rays cannot be intersected"
        )
    x0 = np.zeros(5) if approx is None else np.asarray(approx, dtype=float).reshape(5)
    # geometry check on the linearised equations at the approximate model points
    _, pts = y_parallax(xy1, xy2, c, PairState.from_elements(x0, b, kind, seq))
    if not np.all(np.isfinite(pts)):
        raise InputError("some rays are parallel in the XZ projection (no model point)")
    check_determinable(
        design(pts[:, 0], pts[:, 1], pts[:, 2], b, kind), names, "relative orientation"
    )

    if method == "coplanarity":

        def sigma_image(x):  # as for collinearity, at the model points of the elements x
            _, p = y_parallax(xy1, xy2, c, PairState.from_elements(x, b, kind, seq))
            return sigma * c / float(np.mean(np.abs(p[:, 2])))

        res = coplanarity_pair(xy1, xy2, c, b, kind, x0, sigma_image, seq, labels, max_iter)
    else:  # parallax, and the start of collinearity

        def equations(x):
            st = PairState.from_elements(x, b, kind, seq)
            p, _, J = _parallax_and_jacobian(xy1, xy2, c, st, kind)
            return p, J

        res = gauss_newton(
            equations, x0, np.zeros(xy1.shape[0]), sigma, names=list(names), obs_labels=labels,
            max_iter=max_iter, tol=1e-8, context="relative orientation",
        )  # fmt: skip
    st = PairState.from_elements(res.x, b, kind, seq)
    _, pts = y_parallax(xy1, xy2, c, st)
    if method == "collinearity":
        # σ of an image coordinate: the parallax σ (model units) brought to image scale
        sigma_image = sigma * c / float(np.mean(np.abs(pts[:, 2])))
        res, pts = collinearity_pair(
            xy1, xy2, c, b, res.x, pts, sigma_image, seq, labels, max(max_iter, 10)
        )
        st = PairState.from_elements(res.x[:5], b, kind, seq)
    return res.extend(
        RelativeResult, kind=kind, base=float(b), sequence=seq, c=float(c), points=pts,
        state=st, method=method,
    )  # fmt: skip
