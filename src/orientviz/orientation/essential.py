"""The modern route to relative orientation: the essential matrix.

For a pair with the left bundle as the model frame (R1 = I, O1 = 0) and the right one
at O2 = B with rotation R2 (image → model, :mod:`orientviz.rotation`), the image rays
``d = (x, y, −c)`` (mm, orientviz's camera frame: x right, y up, z backwards) satisfy
the coplanarity condition

    d1ᵀ E d2 = 0,   E = [B]ₓ R2,

the model point being λ1 d1 = B + λ2 R2 d2 with λ1, λ2 > 0 (in front of both images).
:func:`eight_point` estimates E linearly (normalised eight-point algorithm),
:func:`decompose_essential` gives the four (R, t) factorisations and
:func:`select_by_cheirality` keeps the one with the points in front of both images;
:func:`essential_route` then scales the base to bx = b, converts to the five elements
of a dependent pair and refines them with the rigorous model
(:func:`~orientviz.orientation.relative.relative_orientation`).

OpenCV's camera frame is x right, y down, z forwards: its normalised coordinates are
(x/c, −y/c) and its (R, t) map camera-1 into camera-2 coordinates, so
``R2 = D R_cvᵀ D`` and ``B ∝ −R2 D t_cv`` with D = diag(1, −1, −1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust.result import Adjustment
from ..errors import InputError, NotDeterminableError
from ..rotation import check_sequence, opk_from_matrix, skew
from .relative import PairState, RelativeResult, check_points, relative_orientation, y_parallax

F64 = NDArray[np.float64]

#: OpenCV's camera frame in orientviz's: diag(1, −1, −1).
D_OPENCV: F64 = np.diag([1.0, -1.0, -1.0])


@dataclass
class EssentialResult(RelativeResult):
    """A relative orientation found through the essential matrix.

    Attributes
    ----------
    E : ndarray, shape (3, 3)
        The essential matrix (unit Frobenius norm up to sign).
    R_linear : ndarray, shape (3, 3)
        R2 of the linear solution (image → model).
    t_linear : ndarray, shape (3,)
        Unit base direction of the linear solution.
    linear : ndarray, shape (5,)
        The dependent pair's elements by, bz, ω, φ, κ before refinement (model units, rad).
    n_front : int
        Points in front of both images for the chosen factorisation.
    """

    E: F64 | None = None
    R_linear: F64 | None = None
    t_linear: F64 | None = None
    linear: F64 | None = None
    n_front: int = 0


def essential_from_orientation(R2: ArrayLike, base: ArrayLike) -> F64:
    """E = [B]ₓ R2 with d1ᵀ E d2 = 0 (see the module docstring)."""
    return skew(np.asarray(base, dtype=float)) @ np.asarray(R2, dtype=float)


def _homogeneous(xy: F64, c: float) -> F64:
    # (−x/c, −y/c, 1) is parallel to the ray (x, y, −c)
    return np.column_stack([-xy[:, 0] / c, -xy[:, 1] / c, np.ones(xy.shape[0])])


def _normaliser(q: F64) -> F64:
    m = q[:, :2].mean(axis=0)
    s = np.sqrt(2.0) / max(np.mean(np.linalg.norm(q[:, :2] - m, axis=1)), 1e-300)
    return np.array([[s, 0, -s * m[0]], [0, s, -s * m[1]], [0, 0, 1.0]])


def eight_point(xy_left: ArrayLike, xy_right: ArrayLike, c: float) -> F64:
    """Essential matrix by the normalised eight-point algorithm (n ≥ 8 pairs).

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates in mm, reduced to the principal point.
    c : float
        Principal distance, mm.

    Returns
    -------
    ndarray, shape (3, 3)
        E with d1ᵀ E d2 = 0 for rays d = (x, y, −c), singular values (1, 1, 0).

    Raises
    ------
    InputError
        Fewer than 8 points or mismatched shapes.
    NotDeterminableError
        The points do not determine E (fewer than 8 independent constraints).
    """
    q1 = _homogeneous(check_points(xy_left, "xy_left"), c)
    q2 = _homogeneous(check_points(xy_right, "xy_right"), c)
    if q1.shape != q2.shape:
        raise InputError(
            f"expected two point sets of the same shape, got {q1.shape} and {q2.shape}"
        )
    if q1.shape[0] < 8:
        raise InputError(f"the eight-point algorithm needs at least 8 points, got {q1.shape[0]}")
    T1, T2 = _normaliser(q1), _normaliser(q2)
    a, bb = q1 @ T1.T, q2 @ T2.T
    M = (a[:, :, None] * bb[:, None, :]).reshape(-1, 9)
    _, s, Vt = np.linalg.svd(M, full_matrices=False)
    if s.size < 9 or s[-2] < 1e-10 * s[0]:
        raise NotDeterminableError(
            "the points do not determine the essential matrix (fewer than 8 independent "
            "constraints: degenerate or planar-critical configuration)",
            parameters=["E"],
            defect=1,
        )
    En = Vt[-1].reshape(3, 3)
    E = T1.T @ En @ T2
    U, sv, Vt2 = np.linalg.svd(E)
    E = U @ np.diag([1.0, 1.0, 0.0]) @ Vt2
    return E / np.linalg.norm(E) * np.sqrt(2.0)


# ------------------------------------------------------------------ five-point solver
#: Monomials of degree ≤ 3 in (x, y, z): the ten of degree 3 first, then the basis of
#: the quotient ring (x², xy, y², xz, yz, z², x, y, z, 1) used by the action matrix.
_MONOS = np.array(
    [(3, 0, 0), (2, 1, 0), (1, 2, 0), (0, 3, 0), (2, 0, 1), (1, 1, 1), (0, 2, 1), (1, 0, 2),
     (0, 1, 2), (0, 0, 3), (2, 0, 0), (1, 1, 0), (0, 2, 0), (1, 0, 1), (0, 1, 1), (0, 0, 2),
     (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)]
)  # fmt: skip
#: The 20 lattice points (i, j, k) ≥ 0 with i + j + k ≤ 3: unisolvent for cubics.
_LATTICE = np.array([m for m in np.ndindex(4, 4, 4) if sum(m) <= 3], dtype=float) - 1.0
_VANDER = np.prod(_LATTICE[:, None, :] ** _MONOS[None, :, :], axis=2)
#: x times basis monomial k is: ("lead", row of the eliminated cubic) or ("basis", index).
_ACTION_X = [("lead", 0), ("lead", 1), ("lead", 2), ("lead", 4), ("lead", 5), ("lead", 7),
             ("basis", 0), ("basis", 1), ("basis", 3), ("basis", 6)]  # fmt: skip


def _constraints(E: F64) -> F64:
    """det E and the nine entries of 2 E Eᵀ E − tr(E Eᵀ) E, for a stack (m, 3, 3)."""
    EEt = E @ np.swapaxes(E, 1, 2)
    tr = np.trace(EEt, axis1=1, axis2=2)
    T = 2.0 * EEt @ E - tr[:, None, None] * E
    return np.column_stack([np.linalg.det(E), T.reshape(-1, 9)])


def five_point(xy_left: ArrayLike, xy_right: ArrayLike, c: float) -> list[F64]:
    """Essential matrices from five (or more) point pairs: the five-point problem.

    The null space of the coplanarity equations is 4-dimensional for five points,
    E = x X + y Y + z Z + W; det E = 0 and 2 E Eᵀ E − tr(E Eᵀ) E = 0 give ten cubics in
    (x, y, z). Their coefficients are interpolated exactly on a 20-point lattice, the ten
    cubic monomials are eliminated (Gauss-Jordan) and the real eigenvectors of the action
    matrix of x give up to ten solutions (Stewénius' formulation of Nistér's algorithm).
    With more than five points the four smallest right singular vectors are used (a
    least-squares null space).

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n ≥ 5, 2)
        Image coordinates in mm.
    c : float
        Principal distance, mm.

    Returns
    -------
    list of ndarray, shape (3, 3)
        The real solutions E (d1ᵀ E d2 = 0, ‖E‖ = √2), in no particular order.
    """
    q1 = _homogeneous(check_points(xy_left, "xy_left"), c)
    q2 = _homogeneous(check_points(xy_right, "xy_right"), c)
    if q1.shape != q2.shape:
        raise InputError(
            f"expected two point sets of the same shape, got {q1.shape} and {q2.shape}"
        )
    if q1.shape[0] < 5:
        raise InputError(f"the five-point algorithm needs at least 5 points, got {q1.shape[0]}")
    M = (q1[:, :, None] * q2[:, None, :]).reshape(-1, 9)
    _, s, Vt = np.linalg.svd(M, full_matrices=M.shape[0] < 9)  # Vt is 9 × 9 either way
    if np.sum(s > 1e-10 * s[0]) < 5:
        raise NotDeterminableError(
            "the points give fewer than 5 independent coplanarity equations",
            parameters=["E"],
            defect=1,
        )
    X, Y, Z, W = (Vt[k].reshape(3, 3) for k in (5, 6, 7, 8))
    L = _LATTICE
    Es = L[:, 0, None, None] * X + L[:, 1, None, None] * Y + L[:, 2, None, None] * Z + W
    A = np.linalg.solve(_VANDER, _constraints(Es)).T  # (10 equations, 20 monomials)
    try:
        B = np.linalg.solve(A[:, :10], A[:, 10:])
    except np.linalg.LinAlgError:
        raise NotDeterminableError(
            "degenerate five-point configuration (the cubic constraints are dependent)",
            parameters=["E"],
            defect=1,
        ) from None
    Mx = np.zeros((10, 10))
    for k, (what, j) in enumerate(_ACTION_X):
        if what == "lead":
            Mx[k] = -B[j]
        else:
            Mx[k, j] = 1.0
    # Mx b = x b for the basis vector b(x, y, z): b is a right eigenvector
    w, V = np.linalg.eig(Mx)
    out = []
    for i in range(10):
        v = V[:, i]
        if abs(w[i].imag) > 1e-8 * max(1.0, abs(w[i])) or abs(v[9]) < 1e-12:
            continue
        v = (v / v[9]).real
        E = v[6] * X + v[7] * Y + v[8] * Z + W
        out.append(E / np.linalg.norm(E) * np.sqrt(2.0))
    return out


def five_point_route(xy_left: ArrayLike, xy_right: ArrayLike, c: float) -> tuple[F64, F64, F64]:
    """The five-point solution that fits all points best, with its (R, t).

    Each real solution is decomposed (:func:`decompose_essential`); the candidate with
    the most points in front of both images and, among those, the smallest RMS of the
    coplanarity residuals d1ᵀ E d2 / (‖d1‖ ‖d2‖) over all points wins. With exactly five
    points every real solution fits them exactly and several may have all points in
    front: the choice is then arbitrary — a sixth point decides.

    Returns
    -------
    E, R, t : ndarray
        Essential matrix, rotation of the right image, unit base direction.
    """
    xy1 = check_points(xy_left, "xy_left")
    xy2 = check_points(xy_right, "xy_right")
    d1 = np.column_stack([xy1, np.full(len(xy1), -c)])
    d2 = np.column_stack([xy2, np.full(len(xy2), -c)])
    n1 = np.linalg.norm(d1, axis=1)
    n2 = np.linalg.norm(d2, axis=1)
    best = None
    for E in five_point(xy1, xy2, c):
        R, t, n_front = select_by_cheirality(E, xy1, xy2, c)
        rms = float(np.sqrt(np.mean((np.einsum("ni,ij,nj->n", d1, E, d2) / (n1 * n2)) ** 2)))
        key = (-n_front, rms)
        if best is None or key < best[0]:
            best = (key, E, R, t)
    if best is None:
        raise NotDeterminableError("the five-point problem has no real solution here", ["E"], 1)
    return best[1], best[2], best[3]


def decompose_essential(E: ArrayLike) -> list[tuple[F64, F64]]:
    """The four factorisations E ∝ [t]ₓ R: (R, t) with R proper, ‖t‖ = 1."""
    U, _, Vt = np.linalg.svd(np.asarray(E, dtype=float))
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    t = U[:, 2]
    out = []
    for R in (U @ W @ Vt, U @ W.T @ Vt):
        for s in (1.0, -1.0):
            out.append((R, s * t))
    return out


def depths(xy_left: F64, xy_right: F64, c: float, R: F64, t: F64) -> tuple[F64, F64]:
    """λ1, λ2 of λ1 d1 ≈ t + λ2 R d2 per point (least squares, vectorised)."""
    d1 = np.column_stack([xy_left, np.full(len(xy_left), -c)])
    d2 = np.column_stack([xy_right, np.full(len(xy_right), -c)]) @ R.T
    a11 = (d1 * d1).sum(1)
    a12 = -(d1 * d2).sum(1)
    a22 = (d2 * d2).sum(1)
    r1 = d1 @ t
    r2 = -(d2 @ t)
    det = a11 * a22 - a12 * a12
    with np.errstate(divide="ignore", invalid="ignore"):
        lam1 = (a22 * r1 - a12 * r2) / det
        lam2 = (a11 * r2 - a12 * r1) / det
    return lam1, lam2


def select_by_cheirality(
    E: ArrayLike, xy_left: ArrayLike, xy_right: ArrayLike, c: float
) -> tuple[F64, F64, int]:
    """The factorisation with most points in front of both images.

    Returns
    -------
    R : ndarray, shape (3, 3)
        Rotation of the right image (image → model frame of the left image).
    t : ndarray, shape (3,)
        Unit base direction O2 − O1.
    n_front : int
        Number of points with λ1 > 0 and λ2 > 0.
    """
    xy1 = check_points(xy_left, "xy_left")
    xy2 = check_points(xy_right, "xy_right")
    best = None
    for R, t in decompose_essential(E):
        l1, l2 = depths(xy1, xy2, c, R, t)
        n = int(np.sum((l1 > 0) & (l2 > 0)))
        if best is None or n > best[2]:
            best = (R, t, n)
    return best


def essential_route(
    xy_left: ArrayLike,
    xy_right: ArrayLike,
    c: float,
    *,
    b: float | None = None,
    sequence: str = "opk",
    sigma: float = 0.005,
    refine: bool = True,
    solver: str = "eight",
) -> EssentialResult:
    """Relative orientation via the essential matrix, refined by the rigorous model.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates in mm (n ≥ 8).
    c : float
        Principal distance, mm.
    b : float, optional
        Model base bx; default the median x-parallax (model at about image scale).
    sequence : {"opk", "pok"}
        Rotation sequence of the returned angles.
    sigma : float
        A-priori σ of a y-parallax for the refinement, model units.
    refine : bool
        Refine with :func:`~orientviz.orientation.relative.relative_orientation`
        (default); otherwise return the linear solution only (no precision).
    solver : {"eight", "five"}
        :func:`eight_point` (n ≥ 8) or :func:`five_point_route` (n ≥ 5).

    Returns
    -------
    EssentialResult
        Elements by, bz, ω, φ, κ of a dependent pair (the fields of
        :class:`~orientviz.orientation.relative.RelativeResult`; without refinement the
        model points at the linear elements) and ``E``, ``R_linear``, ``t_linear``,
        ``linear`` (the elements before refinement) and ``n_front``.
    """
    seq = check_sequence(sequence)
    xy1 = check_points(xy_left, "xy_left")
    xy2 = check_points(xy_right, "xy_right")
    if solver == "eight":
        E = eight_point(xy1, xy2, c)
        R, t, n_front = select_by_cheirality(E, xy1, xy2, c)
    elif solver == "five":
        E, R, t = five_point_route(xy1, xy2, c)
        n_front = select_by_cheirality(E, xy1, xy2, c)[2]
    else:
        raise InputError(f"expected solver 'eight' or 'five', got {solver!r}")
    if b is None:
        b = float(np.median(xy1[:, 0] - xy2[:, 0]))
    if abs(t[0]) < 1e-6:
        raise NotDeterminableError(
            "the base found from E has no component along x: the pair is not a "
            "dependent pair along X (by, bz cannot be scaled to bx = b)",
            parameters=["by", "bz"],
        )
    B = t * (b / t[0])
    lin = np.r_[B[1], B[2], np.array(opk_from_matrix(R, seq), dtype=float)]
    if refine:
        res = relative_orientation(xy1, xy2, c, b=b, approx=lin, sigma=sigma, sequence=seq)
    else:
        st = PairState.from_elements(lin, b, "dependent", seq)
        res = Adjustment(
            lin,
            ["by", "bz", "omega", "phi", "kappa"],
            float("nan"),
            len(xy1) - 5,
            np.zeros(len(xy1)),
            np.full(len(xy1), sigma),
            True,
            "linear solution only",
        ).extend(
            RelativeResult, kind="dependent", base=float(b), sequence=seq, c=float(c),
            points=y_parallax(xy1, xy2, c, st)[1], state=st,
        )  # fmt: skip
    return res.extend(
        EssentialResult, E=E, R_linear=R, t_linear=t, linear=lin, n_front=int(n_front)
    )
