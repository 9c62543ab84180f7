"""Space resection: the exterior orientation of one image from control points.

Conventions (see :mod:`orientviz.camera`): image coordinates in mm, object coordinates
in m, ``R`` turns image-frame vectors into the object frame, angles ω, φ, κ in radians
in the sequence ``"opk"`` (R = R_ω R_φ R_κ) unless ``sequence="pok"`` (R = R_φ R_ω R_κ).

Two steps, as in practice:

1. :func:`resection_closed_form` — the classic three-point solution (after Grunert,
   1841). The image rays of three points enclose known angles; with the known distances
   between the points the law of cosines gives three equations in the three ray
   lengths. Writing the lengths as s2 = u·s1 and s3 = v·s1 eliminates s1 and u and leaves
   a polynomial of degree 4 in v, so there are up to four real solutions. Each gives
   the three points in the camera frame; the rigid transformation from camera to
   object frame (:func:`~orientviz.orientation.absolute.similarity_closed_form`, scale 1)
   then yields X0 and R. A fourth point (or all further points) picks the right one.
2. :func:`resection` — collinearity least squares on the engine with precision,
   optionally with the interior orientation (x0, y0, c) as unknowns.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import polynomial as P
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment, gauss_newton
from ..block import check_image_points, check_points
from ..camera import FrameCamera, project
from ..errors import InputError, NotDeterminableError
from ..rotation import check_sequence, matrix_derivatives, matrix_from_opk, opk_from_matrix
from .absolute import _spread_rank

F64 = NDArray[np.float64]

#: Names of the exterior orientation unknowns, then of the optional interior ones.
EXTERIOR_NAMES: tuple[str, ...] = ("X0", "Y0", "Z0", "omega", "phi", "kappa")
INTERIOR_NAMES: tuple[str, ...] = ("x0", "y0", "c")


@dataclass(frozen=True)
class ResectionCandidate:
    """One solution of the three-point resection.

    Attributes
    ----------
    X0 : ndarray, shape (3,)
        Projection centre in m.
    R : ndarray, shape (3, 3)
        Rotation image → object.
    distances : ndarray, shape (3,)
        Distances from the projection centre to the three points in m.
    rms : float
        RMS image residual (mm) over the check points used to rank the candidates
        (NaN if there were none).
    """

    X0: F64
    R: F64
    distances: F64
    rms: float

    def angles(self, sequence: str = "opk") -> F64:
        """ω, φ, κ in radians in the given sequence."""
        return np.array([float(a) for a in opk_from_matrix(self.R, sequence)])


@dataclass
class ResectionResult(Adjustment):
    """The result of :func:`resection`: the engine's fields plus the oriented image.

    Attributes
    ----------
    R : ndarray, shape (3, 3)
        The estimated rotation image → object.
    candidates : list of ResectionCandidate
        The closed-form solutions it started from (empty with a given start).
    camera : FrameCamera
        The camera with the estimated (or given) interior orientation, mm.
    sequence : str
        Rotation sequence of ω, φ, κ in ``x``.
    residuals_xy : ndarray, shape (n, 2)
        Image residuals v per point, mm.
    """

    R: F64 | None = None
    candidates: list[ResectionCandidate] = field(default_factory=list)
    camera: FrameCamera | None = None
    sequence: str = "opk"
    residuals_xy: F64 | None = None


def _camera(camera: FrameCamera | float) -> FrameCamera:
    if isinstance(camera, FrameCamera):
        return camera
    try:
        return FrameCamera(c=float(camera))
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"camera: expected a FrameCamera or a principal distance c in mm ({exc})"
        ) from None


def _check_pairs(image_points: ArrayLike, object_points: ArrayLike) -> tuple[F64, F64]:
    try:
        xy = check_image_points(image_points)
        X = check_points(object_points, "object points")
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if xy.shape[0] != X.shape[0]:
        raise InputError(
            f"expected as many image points as object points, got {xy.shape[0]} and {X.shape[0]}"
        )
    return xy, X


def grunert_distances(directions: ArrayLike, points: ArrayLike) -> F64:
    """Ray lengths of the three-point resection (Grunert): all real, positive solutions.

    Parameters
    ----------
    directions : array_like, shape (3, 3)
        Ray directions to the three points in any common frame (need not be unit).
    points : array_like, shape (3, 3)
        The three object points in m.

    Returns
    -------
    ndarray, shape (k, 3)
        Distances (s1, s2, s3) in m, k = 0 … 4 solutions.

    Raises
    ------
    InputError
        Wrong shapes, NaN or inf, or a zero direction.
    NotDeterminableError
        Two rays in the same direction, or the quartic cannot be solved (degenerate
        geometry); names the exterior orientation unknowns.
    """
    d = np.asarray(directions, dtype=float)
    X = np.asarray(points, dtype=float)
    if d.shape != (3, 3) or X.shape != (3, 3):
        raise InputError(
            f"grunert_distances: expected directions and points of shape (3, 3), got "
            f"{d.shape} and {X.shape}"
        )
    if not (np.all(np.isfinite(d)) and np.all(np.isfinite(X))):
        raise InputError("grunert_distances: expected finite directions and points")
    norm = np.linalg.norm(d, axis=1)
    if np.any(norm == 0):
        raise InputError(f"grunert_distances: direction(s) {np.flatnonzero(norm == 0)} are zero")
    d = d / norm[:, None]
    _check_distinct_rays(d)
    try:
        return _grunert(d, X)
    except np.linalg.LinAlgError as exc:
        raise NotDeterminableError(
            f"space resection: the three-point geometry is degenerate ({exc})",
            parameters=list(EXTERIOR_NAMES),
        ) from None


def _check_distinct_rays(d: F64, tol: float = 1e-12) -> None:
    """NotDeterminableError if two unit rays point the same way (one image position)."""
    for i, j in ((0, 1), (0, 2), (1, 2)):
        if np.sum((d[i] - d[j]) ** 2) <= tol:
            raise NotDeterminableError(
                f"space resection: rays {i + 1} and {j + 1} have the same direction (the "
                "image points coincide): only two rays, the position and rotation "
                "(X0, Y0, Z0, omega, phi, kappa) are not determinable",
                parameters=list(EXTERIOR_NAMES),
            )


def _grunert(d: F64, X: F64) -> F64:
    """Grunert's quartic for unit rays d and points X (both (3, 3), checked)."""
    ca, cb, cg = d[1] @ d[2], d[0] @ d[2], d[0] @ d[1]  # angles at the centre: 23, 13, 12
    a2 = np.sum((X[1] - X[2]) ** 2)
    b2 = np.sum((X[0] - X[2]) ** 2)
    c2 = np.sum((X[0] - X[1]) ** 2)
    q = np.array([1.0, -2.0 * cb, 1.0])  # 1 + v² − 2v cos β (coefficients in v, ascending)
    # eliminate u² between the two equations quadratic in u:  u = N(v) / D(v)
    N = (a2 - c2) * q + b2 * np.array([1.0, 0.0, -1.0])
    D = np.array([2.0 * b2 * cg, -2.0 * b2 * ca])
    # c² q D² = b² (D² + N² − 2 cos γ N D): a quartic in v
    quartic = P.polysub(
        c2 * P.polymul(q, P.polymul(D, D)),
        b2 * P.polysub(P.polyadd(P.polymul(D, D), P.polymul(N, N)), 2.0 * cg * P.polymul(N, D)),
    )
    scale = np.abs(quartic).max()
    if scale == 0:
        return np.zeros((0, 3))
    roots = P.polyroots(quartic / scale)
    out = []
    for r in roots:
        if abs(r.imag) > 1e-6 * max(1.0, abs(r.real)):
            continue
        v = r.real
        s1sq = b2 / P.polyval(v, q) if P.polyval(v, q) > 0 else -1.0
        if v <= 0 or s1sq <= 0:
            continue
        den = P.polyval(v, D)
        if abs(den) > 1e-6 * (abs(D[0]) + abs(D[1] * v)):
            us = [P.polyval(v, N) / den]
        else:  # u = N/D is 0/0 (symmetric rays, s1 = s2 = s3, a double root): u from the c-equation
            disc = cg * cg - 1.0 + c2 / s1sq
            us = [cg + sg * np.sqrt(max(disc, 0.0)) for sg in (1.0, -1.0)] if disc > -1e-6 else []
            us = [u for u in us if abs(u * u + v * v - 2 * u * v * ca - a2 / s1sq) <= 1e-5 * (1 + a2 / s1sq)]
        s1 = np.sqrt(s1sq)
        out.extend((s1, u * s1, v * s1) for u in us if u > 0)
    if not out:
        return np.zeros((0, 3))
    # polish all solutions with a few Newton steps on the three cosine-law equations;
    # near a double root two roots polish to one solution: keep it once
    s = _polish(np.array(out), d, X)
    keep: list[F64] = []
    for row in s:
        if not any(np.allclose(row, k, rtol=1e-6, atol=0.0) for k in keep):
            keep.append(row)
    return np.array(keep)


_PAIRS = (np.array([1, 0, 0]), np.array([2, 2, 1]))  # (i, j) of the equations for a, b, c


def _polish(s: F64, d: F64, X: F64, steps: int = 2) -> F64:
    """Newton steps on s_i² + s_j² − 2 s_i s_j cos_ij = ‖X_i − X_j‖², all solutions (k, 3) at once."""
    i, j = _PAIRS
    cos = np.sum(d[i] * d[j], axis=1)
    dist2 = np.sum((X[i] - X[j]) ** 2, axis=1)
    rows = np.arange(3)
    for _ in range(steps):
        si, sj = s[:, i], s[:, j]
        F = si**2 + sj**2 - 2 * si * sj * cos - dist2
        J = np.zeros((s.shape[0], 3, 3))
        J[:, rows, i] = 2 * si - 2 * sj * cos
        J[:, rows, j] = 2 * sj - 2 * si * cos
        det = np.linalg.det(J)
        ok = np.abs(det) > 1e-12 * np.abs(J).max(axis=(1, 2)) ** 3
        if not ok.any():
            break
        s = s.copy()
        s[ok] -= np.linalg.solve(J[ok], F[ok][..., None])[..., 0]
    return s


def _rigid(a: F64, b: F64) -> tuple[F64, F64]:
    """Rotation R and translation t with b ≈ R a + t (SVD, det R = +1), no checks."""
    ac, bc = a.mean(axis=0), b.mean(axis=0)
    U, _, Vt = np.linalg.svd((b - bc).T @ (a - ac))
    S = np.array([1.0, 1.0, 1.0 if np.linalg.det(U) * np.linalg.det(Vt) > 0 else -1.0])
    R = (U * S) @ Vt
    return R, bc - R @ ac


def _pick_three(xy: F64) -> tuple[int, int, int]:
    """Three different image points spanning a large triangle (far pair, largest area).

    Needs at least three distinct image positions (checked by the caller).
    """
    j = int(np.argmax(np.sum((xy - xy[0]) ** 2, axis=1)))
    i = int(np.argmax(np.sum((xy - xy[j]) ** 2, axis=1)))  # re-anchor on the far end
    e = xy[j] - xy[i]
    area = np.abs(e[0] * (xy[:, 1] - xy[i, 1]) - e[1] * (xy[:, 0] - xy[i, 0]))
    area[[i, j]] = -1.0
    return i, j, int(np.argmax(area))


def resection_closed_form(
    image_points: ArrayLike,
    object_points: ArrayLike,
    camera: FrameCamera | float,
    *,
    use: tuple[int, int, int] | None = None,
) -> list[ResectionCandidate]:
    """All solutions of the three-point space resection, best first.

    Parameters
    ----------
    image_points : array_like, shape (n, 2)
        Image coordinates in mm, n ≥ 3.
    object_points : array_like, shape (n, 3)
        Object coordinates in m.
    camera : FrameCamera or float
        Interior orientation (or just c in mm, principal point at 0).
    use : tuple of 3 int, optional
        Indices of the three points that define the solution; default a well-spread
        triple. All other points rank the candidates by their RMS image residual.

    Returns
    -------
    list of ResectionCandidate
        Up to four candidates with the points in front of the camera, sorted by the RMS
        of the other points (or by input order if n = 3; then the choice is ambiguous).

    Raises
    ------
    NotDeterminableError
        Fewer than 3 points, three collinear control points, image points at fewer
        than three locations (or two of the three rays in one direction), or no real
        solution. Names the exterior orientation unknowns; numpy's ``LinAlgError``
        does not escape.
    """
    xy, X = _check_pairs(image_points, object_points)
    cam = _camera(camera)
    if xy.shape[0] < 3:
        raise NotDeterminableError(
            f"space resection: needs at least 3 control points, got {xy.shape[0]}",
            parameters=list(EXTERIOR_NAMES),
        )
    if use is None:
        distinct = np.unique(xy, axis=0).shape[0]
        if distinct < 3:
            raise NotDeterminableError(
                f"space resection: the {xy.shape[0]} image points lie at {distinct} "
                "location(s); three rays in different directions are needed, the "
                "position and rotation (X0, Y0, Z0, omega, phi, kappa) are not determinable",
                parameters=list(EXTERIOR_NAMES),
            )
        idx = _pick_three(xy)
    else:
        idx = tuple(int(i) for i in use)
    if len(set(idx)) != 3:
        raise InputError(f"use: expected three different point indices, got {idx}")
    sel = np.array(idx)
    if _spread_rank(X[sel]) < 2:
        raise NotDeterminableError(
            "space resection: the three control points are collinear",
            parameters=list(EXTERIOR_NAMES),
        )
    dirs = np.column_stack([xy[sel, 0] - cam.x0, xy[sel, 1] - cam.y0, np.full(3, -cam.c)])
    unit = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    sols = grunert_distances(unit, X[sel])  # degenerate rays: NotDeterminableError
    others = np.setdiff1d(np.arange(xy.shape[0]), sel)
    cands = []
    for s in sols:
        try:
            R, X0 = _rigid(unit * s[:, None], X[sel])
        except np.linalg.LinAlgError:  # SVD did not converge: skip this candidate
            continue
        w = (X - X0) @ R[:, 2]
        if np.any(w >= 0):  # some control point behind the camera
            continue
        rms = float("nan")
        if others.size:
            r = project(X[others], X0, R, cam.c, cam.x0, cam.y0) - xy[others]
            rms = float(np.sqrt(np.mean(r**2)))
        cands.append(ResectionCandidate(X0, R, s, rms))
    if not cands:
        raise NotDeterminableError(
            "space resection: the three-point solution has no real solution in front of the camera",
            parameters=list(EXTERIOR_NAMES),
        )
    cands.sort(key=lambda c: np.nan_to_num(c.rms, nan=0.0))
    return cands


def resection_model(params: ArrayLike, object_points: ArrayLike, sequence: str = "opk"):
    """Collinearity equations of one image and their Jacobian (one R for all points).

    Parameters
    ----------
    params : array_like, shape (9,)
        X0, Y0, Z0 (m), ω, φ, κ (rad, ``sequence``), x0, y0, c (mm).
    object_points : array_like, shape (n, 3)
        Object points in m.
    sequence : {"opk", "pok"}, default "opk"

    Returns
    -------
    f : ndarray, shape (2n,)
        x1, y1, x2, y2, … in mm.
    J : ndarray, shape (2n, 9)
        ∂f/∂params in mm/m, mm/rad and mm/mm.
    """
    p = np.asarray(params, dtype=float)
    X = np.asarray(object_points, dtype=float)
    n = X.shape[0]
    R = matrix_from_opk(p[3], p[4], p[5], sequence)
    dR = matrix_derivatives(p[3], p[4], p[5], sequence)
    d = X - p[:3]
    uvw = d @ R
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    c = p[8]
    f = np.empty((n, 2))
    f[:, 0] = p[6] - c * u / w
    f[:, 1] = p[7] - c * v / w
    g = np.zeros((n, 2, 3))  # ∂(x, y)/∂(u, v, w)
    g[:, 0, 0] = g[:, 1, 1] = -c / w
    g[:, 0, 2] = c * u / w**2
    g[:, 1, 2] = c * v / w**2
    J = np.zeros((n, 2, 9))
    J[:, :, :3] = -g @ R.T
    for k in range(3):
        J[:, :, 3 + k] = np.einsum("nab,nb->na", g, d @ dR[k])
    J[:, 0, 6] = J[:, 1, 7] = 1.0
    J[:, 0, 8] = -u / w
    J[:, 1, 8] = -v / w
    return f.reshape(-1), J.reshape(2 * n, 9)


def resection(
    image_points: ArrayLike,
    object_points: ArrayLike,
    camera: FrameCamera | float,
    *,
    sigma: ArrayLike = 0.005,
    sequence: str = "opk",
    interior: bool | tuple[str, ...] = False,
    start: tuple[ArrayLike, ArrayLike] | None = None,
    point_ids: list[str] | None = None,
    max_iter: int = 30,
) -> ResectionResult:
    """Least-squares space resection (collinearity) with precision.

    Parameters
    ----------
    image_points : array_like, shape (n, 2)
        Observed image coordinates in mm.
    object_points : array_like, shape (n, 3)
        Control points in m (errorless).
    camera : FrameCamera or float
        Interior orientation (x0, y0, c in mm), or just c.
    sigma : float or array_like, shape (n,) or (n, 2), default 0.005
        A-priori σ of the image coordinates in mm (5 µm).
    sequence : {"opk", "pok"}, default "opk"
        Rotation sequence of the estimated angles.
    interior : bool or tuple of str, default False
        ``True`` estimates x0, y0 and c too (needs ≥ 5 points, not all in one plane
        for c); or a subset such as ``("c",)``.
    start : (X0, angles), optional
        Approximate projection centre (m) and ω, φ, κ (rad, ``sequence``); default the
        best three-point closed-form candidate.
    point_ids : list of str, optional
        Names for residual labels.
    max_iter : int, default 30

    Returns
    -------
    ResectionResult
        ``names`` ``("X0", "Y0", "Z0", "omega", "phi", "kappa")`` (+ ``"x0"``, ``"y0"``,
        ``"c"`` — only those estimated), in m, rad, mm; residuals ``v = f(x̂) − l`` in mm, labelled
        ``"<id>/x"``; ``R``, ``candidates`` (closed-form solutions), ``camera``
        (FrameCamera with the estimated interior), ``sequence``, ``residuals_xy`` ((n, 2) mm).

    Raises
    ------
    InputError
        Wrong shapes or σ.
    NotDeterminableError
        Too few or collinear points, or interior parameters not separable from the
        exterior ones (e.g. c with flat control).

    Notes
    -----
    Like every resection, the solution is unstable when the projection centre lies on
    (or near) the "danger cylinder" through the control points (the circular cylinder
    through three of them, perpendicular to their plane); the adjustment then reports a
    singular normal matrix or large standard deviations.
    """
    seq = check_sequence(sequence)
    xy, X = _check_pairs(image_points, object_points)
    cam = _camera(camera)
    n = xy.shape[0]
    est = INTERIOR_NAMES if interior is True else (tuple(interior) if interior else ())
    bad = [e for e in est if e not in INTERIOR_NAMES]
    if bad:
        raise InputError(f"interior: expected names out of {INTERIOR_NAMES}, got {bad}")
    u = 6 + len(est)
    if 2 * n < u:
        raise NotDeterminableError(
            f"space resection: {u} unknowns need at least {(u + 1) // 2} points, got {n}",
            parameters=list(EXTERIOR_NAMES) + list(est),
        )
    sg = np.asarray(sigma, dtype=float)
    try:
        sg = np.broadcast_to(sg[:, None] if sg.ndim == 1 else sg, (n, 2)).reshape(-1)
    except ValueError:
        raise InputError(
            f"sigma: expected a float, shape ({n},) or ({n}, 2), got {sg.shape}"
        ) from None
    cands: list[ResectionCandidate] = []
    if start is None:
        cands = resection_closed_form(xy, X, cam)
        X0s, ang0 = cands[0].X0, cands[0].angles(seq)
    else:
        X0s, ang0 = np.asarray(start[0], float).reshape(3), np.asarray(start[1], float).reshape(3)
    x0 = np.concatenate([X0s, ang0, [cam.x0, cam.y0, cam.c]])
    fixed = np.array([False] * 6 + [name not in est for name in INTERIOR_NAMES])
    ids = [str(i) for i in range(n)] if point_ids is None else [str(i) for i in point_ids]
    labels = [f"{i}/{a}" for i in ids for a in "xy"]

    def equations(p: F64):
        return resection_model(p, X, seq)

    res = gauss_newton(
        equations, x0, xy.reshape(-1), sg, names=list(EXTERIOR_NAMES + INTERIOR_NAMES),
        groups={"exterior": slice(0, 6), "interior": slice(6, 9)}, obs_labels=labels,
        fixed=fixed, max_iter=max_iter, context="space resection",
    )  # fmt: skip
    x_int = res.x[6:9].copy()
    # report only what was estimated: the exterior orientation and the free interior names
    keep = np.array([*range(6), *(6 + INTERIOR_NAMES.index(e) for e in INTERIOR_NAMES if e in est)])
    res.x, res.names = res.x[keep], [res.names[k] for k in keep]
    res.groups = {"exterior": slice(0, 6)}
    if est:
        res.groups["interior"] = slice(6, keep.size)
    if res.cofactor is not None:
        res.cofactor = res.cofactor[np.ix_(keep, keep)]
    for h in res.history:
        h.x = h.x[keep]
        h.dx = None if h.dx is None else h.dx[keep]

    return res.extend(
        ResectionResult,
        R=matrix_from_opk(*res.x[3:6], seq),
        candidates=cands,
        camera=FrameCamera(
            c=float(x_int[2]),
            x0=float(x_int[0]),
            y0=float(x_int[1]),
            format_mm=cam.format_mm,
            name=cam.name,
        ),
        sequence=seq,
        residuals_xy=res.residuals.reshape(n, 2),
    )
