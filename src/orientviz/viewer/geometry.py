"""Pure geometry for the 3D viewer: frustums, rays, residual vectors, meshes, circles.

Nothing here imports viser; every function takes and returns numpy arrays so that the
scene content can be tested (and timed) without a browser. All functions are
vectorised over images, observations or points.

Conventions
-----------
* Object coordinates in m, right-handed, Z up (:mod:`orientviz.camera`). The viewer
  draws in a *scene frame* that is the object frame shifted by an origin
  (:class:`SceneFrame`), because the browser renders in float32 and block coordinates
  of 10⁵ m would lose the centimetres.
* Image coordinates in mm; a camera looks along −z of its image frame, R (image →
  object) from :mod:`orientviz.rotation` (ω-φ-κ: R = R_ω R_φ R_κ, or φ-ω-κ by name).
* Line segments are arrays of shape (n, 2, 3): start and end point of each segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

# shapes (colours, meshes, circles) live in their own module; re-exported for convenience
from .shapes import (  # noqa: F401
    circle_segments,
    ellipsoid_mesh,
    icosphere,
    ramp,
    sphere_wire_segments,
)

F64 = NDArray[np.float64]

#: R_cv = R · FLIP turns the orientviz image frame (x right, y up, looking along −z) into
#: the OpenCV camera frame viser uses (x right, y down, looking along +z).
FLIP: F64 = np.diag([1.0, -1.0, -1.0])


def core_points(points: ArrayLike) -> F64:
    """The finite points (k, 3) without far strays, which frames and scales must ignore.

    A real reconstruction may hold a few points thrown far away (weakly determined, rays
    meeting at a small angle: 10⁴–10⁷ times the object's size). Kept: the points within
    half the extent of the central 98 % (per axis, 1st–99th percentile) around it; a
    compact object or a block keeps every point. Fewer than 20 points: all finite ones.
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    P = P[np.all(np.isfinite(P), axis=1)]
    if P.shape[0] < 20:
        return P
    lo, hi = np.percentile(P, [1.0, 99.0], axis=0)
    ext = np.maximum(hi - lo, 0.1 * np.max(hi - lo))  # a flat block keeps its heights
    return P[np.all((P >= lo - 0.5 * ext) & (P <= hi + 0.5 * ext), axis=1)]


@dataclass(frozen=True)
class SceneFrame:
    """The local frame the viewer draws in: ``scene = object − origin`` (m).

    Attributes
    ----------
    origin : ndarray, shape (3,)
        Object coordinates (m) of the scene origin, rounded to whole metres.
    size : float
        A length that characterises the scene (m): the larger horizontal extent of
        the content, used to scale point sizes, frustums and the default camera.
    """

    origin: F64
    size: float

    @classmethod
    def around(cls, points: ArrayLike) -> SceneFrame:
        """Frame centred on the bounding box of ``points`` (n, 3) m (far strays left out,
        :func:`core_points`)."""
        P = core_points(points)
        if P.shape[0] == 0:
            return cls(np.zeros(3), 1.0)
        lo, hi = P.min(axis=0), P.max(axis=0)
        size = float(max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-3))
        return cls(np.round((lo + hi) / 2.0), size)

    def to_scene(self, xyz: ArrayLike) -> F64:
        """Object coordinates (…, 3) m → scene coordinates (…, 3) m."""
        return np.asarray(xyz, dtype=float) - self.origin


# --------------------------------------------------------------------------- rotations
def wxyz_from_matrix(R: ArrayLike) -> F64:
    """Unit quaternions (w, x, y, z) of rotation matrices (…, 3, 3), w ≥ 0.

    Shepperd's method, vectorised: the largest of the four squared components is
    computed from the trace and the others from the off-diagonal sums.
    """
    R = np.asarray(R, dtype=float)
    m = R.reshape(-1, 3, 3)
    t = np.stack(
        [
            1.0 + m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2],
            1.0 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2],
            1.0 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2],
            1.0 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2],
        ],
        axis=1,
    )
    k = np.argmax(t, axis=1)
    q = np.empty((m.shape[0], 4))
    s = np.sqrt(np.maximum(t[np.arange(m.shape[0]), k], 1e-300)) * 2.0  # s = 4·|q_k|
    a, b, c = m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]
    d, e, f = m[:, 0, 1] + m[:, 1, 0], m[:, 0, 2] + m[:, 2, 0], m[:, 1, 2] + m[:, 2, 1]
    cases = [
        np.stack([s / 4, a / s, b / s, c / s], axis=1),
        np.stack([a / s, s / 4, d / s, e / s], axis=1),
        np.stack([b / s, d / s, s / 4, f / s], axis=1),
        np.stack([c / s, e / s, f / s, s / 4], axis=1),
    ]
    for j in range(4):
        q[k == j] = cases[j][k == j]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q.reshape(R.shape[:-2] + (4,))


def matrix_from_wxyz(q: ArrayLike) -> F64:
    """Rotation matrices (…, 3, 3) of unit quaternions (…, 4) in (w, x, y, z) order."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(q.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


# --------------------------------------------------------------------------- cameras
def frustum_corners(
    X0: ArrayLike,
    R: ArrayLike,
    c: ArrayLike,
    format_mm: ArrayLike,
    depth: float,
    x0: ArrayLike = 0.0,
    y0: ArrayLike = 0.0,
) -> F64:
    """Apex and image corners of camera frustums, drawn at ``depth`` metres.

    The image plane (z = −c in the image frame) is scaled so that it lies ``depth``
    metres from the projection centre: corner = X0 + R·(x − x0, y − y0, −c)·depth/c.

    Parameters
    ----------
    X0 : array_like, shape (m, 3)
        Projection centres in m.
    R : array_like, shape (m, 3, 3)
        Rotations image → object.
    c : array_like, shape (m,)
        Principal distances in mm.
    format_mm : array_like, shape (m, 2) or (2,)
        Image format (width along x, height along y) in mm.
    depth : float
        Drawn distance of the image plane from the apex in m.
    x0, y0 : float or array_like, shape (m,)
        Principal point in mm (the apex sits above it).

    Returns
    -------
    ndarray, shape (m, 5, 3)
        Apex, then the corners (+x,+y), (−x,+y), (−x,−y), (+x,−y) in object coordinates.
    """
    X0 = np.asarray(X0, dtype=float).reshape(-1, 3)
    m = X0.shape[0]
    R = np.broadcast_to(np.asarray(R, dtype=float), (m, 3, 3))
    c = np.broadcast_to(np.asarray(c, dtype=float), (m,))
    fmt = np.broadcast_to(np.asarray(format_mm, dtype=float), (m, 2))
    sx = np.array([1.0, -1.0, -1.0, 1.0])
    sy = np.array([1.0, 1.0, -1.0, -1.0])
    img = np.empty((m, 4, 3))
    img[..., 0] = sx * fmt[:, :1] / 2 - np.broadcast_to(np.asarray(x0, float), (m,))[:, None]
    img[..., 1] = sy * fmt[:, 1:] / 2 - np.broadcast_to(np.asarray(y0, float), (m,))[:, None]
    img[..., 2] = -c[:, None]
    img *= (depth / c)[:, None, None]
    out = np.empty((m, 5, 3))
    out[:, 0] = X0
    out[:, 1:] = X0[:, None, :] + np.einsum("mij,mkj->mki", R, img)
    return out


def frustum_segments(corners: ArrayLike) -> F64:
    """Line segments (8 per camera) of frustums from :func:`frustum_corners`.

    Returns
    -------
    ndarray, shape (m·8, 2, 3)
        Per camera: four edges apex → corner, then the four edges of the image rectangle.
    """
    C = np.asarray(corners, dtype=float)
    m = C.shape[0]
    seg = np.empty((m, 8, 2, 3))
    seg[:, :4, 0] = C[:, :1]
    seg[:, :4, 1] = C[:, 1:]
    seg[:, 4:, 0] = C[:, 1:]
    seg[:, 4:, 1] = C[:, [2, 3, 4, 1]]
    return seg.reshape(m * 8, 2, 3)


def viser_frustum(
    c: float, format_mm: ArrayLike, depth: float
) -> tuple[float, float, tuple[float, float, float]]:
    """Arguments ``(fov, aspect, scale)`` that make viser draw a frustum ``depth`` m deep.

    viser's client normalises the frustum volume: for a vertical field of view ``fov``
    and ``aspect`` = width/height it draws the image rectangle at
    z = scale / cbrt(tan(fov/2)² · aspect / 3). This inverts that so that the drawn
    image plane lies ``depth`` m in front of the apex, exactly as
    :func:`frustum_corners` (principal-point offsets are not drawn by viser).

    Parameters
    ----------
    c : float
        Principal distance in mm.
    format_mm : array_like, shape (2,)
        Image width (along x) and height (along y) in mm.
    depth : float
        Distance of the drawn image plane from the apex in m.

    Returns
    -------
    fov : float
        Vertical field of view in rad, 2·atan(height / 2c).
    aspect : float
        Width / height.
    scale : tuple of float
        Per-axis scale to pass to ``add_camera_frustum``.
    """
    w, h = (float(v) for v in np.asarray(format_mm, dtype=float).reshape(2))
    fov = 2.0 * float(np.arctan(h / (2.0 * c)))
    aspect = w / h
    y = np.tan(fov / 2.0)
    volume_scale = float(np.cbrt(y * y * aspect / 3.0))
    s = depth * volume_scale
    return fov, aspect, (s, s, s)


def ray_segments(X0: ArrayLike, points: ArrayLike) -> F64:
    """Segments from projection centres to object points, shape (n, 2, 3)."""
    A = np.asarray(X0, dtype=float).reshape(-1, 3)
    B = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.stack(np.broadcast_arrays(A, B), axis=1)


def residual_offsets(
    points: ArrayLike, X0: ArrayLike, R: ArrayLike, c: ArrayLike, misclosure: ArrayLike
) -> F64:
    """Where the *observed* ray passes a point: an image misclosure carried to object space.

    For a point at depth w (third component of Rᵀ(X − X0), negative in front of the
    camera) an image displacement (dx, dy) mm moves the ray sideways by
    R·(dx, dy, 0)·(−w/c) metres at the point's depth (the local image scale).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    X0 : array_like, shape (n, 3)
        Projection centre of each observation's image, m.
    R : array_like, shape (n, 3, 3)
        Rotation (image → object) of each observation's image.
    c : array_like, shape (n,)
        Principal distances in mm.
    misclosure : array_like, shape (n, 2)
        Observed minus computed image coordinates in mm (``Block.residuals()``).

    Returns
    -------
    ndarray, shape (n, 3)
        Offsets in m from the point to the observed ray, at the point's depth.
    """
    P = np.asarray(points, dtype=float)
    R = np.asarray(R, dtype=float)
    d = P - np.asarray(X0, dtype=float)
    w = np.einsum("nji,nj->ni", R, d)[:, 2]
    e = np.asarray(misclosure, dtype=float)
    local = np.zeros((P.shape[0], 3))
    local[:, :2] = e * (-w / np.asarray(c, dtype=float))[:, None]
    return np.einsum("nij,nj->ni", R, local)


def vector_segments(start: ArrayLike, offset: ArrayLike, exaggeration: float = 1.0) -> F64:
    """Segments from ``start`` (n, 3) to ``start + exaggeration·offset``, shape (n, 2, 3)."""
    S = np.asarray(start, dtype=float).reshape(-1, 3)
    out = np.empty((S.shape[0], 2, 3))
    out[:, 0] = S
    out[:, 1] = S + exaggeration * np.asarray(offset, dtype=float).reshape(-1, 3)
    return out


def arrow_segments(
    start: ArrayLike, vector: ArrayLike, head: float = 0.25, up: ArrayLike = (0.0, 0.0, 1.0)
) -> F64:
    """Arrows as line segments: a shaft and two head strokes each, shape (n·3, 2, 3).

    Parameters
    ----------
    start : array_like, shape (n, 3)
        Arrow tails (m).
    vector : array_like, shape (n, 3)
        Arrow vectors (m); zero vectors give degenerate (zero-length) arrows.
    head : float
        Head length as a fraction of the arrow length.
    up : array_like, shape (3,)
        The head strokes lie in the plane of the vector and this direction (or X if
        parallel).
    """
    S = np.asarray(start, dtype=float).reshape(-1, 3)
    V = np.asarray(vector, dtype=float).reshape(-1, 3)
    E = S + V
    u = np.broadcast_to(np.asarray(up, dtype=float), V.shape)
    side = np.cross(V, u)
    bad = np.linalg.norm(side, axis=1) < 1e-12 * (np.linalg.norm(V, axis=1) + 1e-300)
    side[bad] = np.cross(V[bad], [1.0, 0.0, 0.0])
    n = np.linalg.norm(side, axis=1, keepdims=True)
    side = np.divide(side, n, out=np.zeros_like(side), where=n > 0)
    L = np.linalg.norm(V, axis=1, keepdims=True)
    back = -V * head
    wing = side * L * head * 0.5
    out = np.empty((S.shape[0], 3, 2, 3))
    out[:, 0, 0], out[:, 0, 1] = S, E
    out[:, 1, 0], out[:, 1, 1] = E, E + back + wing
    out[:, 2, 0], out[:, 2, 1] = E, E + back - wing
    return out.reshape(-1, 2, 3)


def closest_points_of_rays(
    O1: ArrayLike, d1: ArrayLike, O2: ArrayLike, d2: ArrayLike
) -> tuple[F64, F64]:
    """Closest points of two families of rays Oᵢ + tᵢ·dᵢ (vectorised, m).

    The gap between the two points is the part of the ray pair that a stereo model
    cannot close: its component across the base is the y-parallax of the pair.
    Parallel rays give the feet of the perpendicular from O1.

    Returns
    -------
    P1, P2 : ndarray, shape (n, 3)
        The closest point on ray 1 and on ray 2.
    """
    O1, d1, O2, d2 = (np.asarray(a, dtype=float).reshape(-1, 3) for a in (O1, d1, O2, d2))
    w0 = O1 - O2
    a = np.einsum("ij,ij->i", d1, d1)
    b = np.einsum("ij,ij->i", d1, d2)
    c = np.einsum("ij,ij->i", d2, d2)
    d = np.einsum("ij,ij->i", d1, w0)
    e = np.einsum("ij,ij->i", d2, w0)
    den = a * c - b * b
    par = den <= 1e-12 * a * c
    safe = np.where(par, 1.0, den)
    t1 = np.where(par, 0.0, (b * e - c * d) / safe)
    t2 = np.where(par, e / c, (a * e - b * d) / safe)
    return O1 + t1[:, None] * d1, O2 + t2[:, None] * d2


def ray_segment_distances(origin: ArrayLike, direction: ArrayLike, segments: ArrayLike) -> F64:
    """Shortest distances (n,) in m from the ray origin + s·direction (s ≥ 0, a click into
    the scene) to each of ``segments`` (n, 2, 3).

    The minimum of ‖o + s·d − a − t·(b − a)‖² over s ≥ 0, 0 ≤ t ≤ 1 is the free
    stationary point if it lies in that range, else the smallest of the minima along
    the edges s = 0, t = 0 and t = 1.
    """
    o, d = np.asarray(origin, float).reshape(3), np.asarray(direction, float).reshape(3)
    seg = np.asarray(segments, float).reshape(-1, 2, 3)
    a, u = seg[:, 0], seg[:, 1] - seg[:, 0]
    w = a - o
    A, B, C = d @ d, u @ d, np.maximum(np.einsum("ij,ij->i", u, u), 1e-300)
    D, E = w @ d, np.einsum("ij,ij->i", u, w)
    den = np.where(np.abs(A * C - B * B) > 1e-12 * A * C, A * C - B * B, np.nan)
    cand = [((D * C - B * E) / den, (B * D - A * E) / den)]  # free stationary point
    t0 = np.clip(-E / C, 0.0, 1.0)
    cand += [(np.zeros_like(t0), t0)]  # s = 0: the nearest point of the segment to o
    cand += [(np.maximum(0.0, (D + t * B) / A), np.full_like(B, t)) for t in (0.0, 1.0)]
    best = np.full(len(seg), np.inf)
    for s, t in cand:
        ok = np.isfinite(s) & (s >= 0) & (t >= 0) & (t <= 1)
        r = o + s[:, None] * d - a - t[:, None] * u
        best = np.where(ok, np.minimum(best, np.einsum("ij,ij->i", r, r)), best)
    return np.sqrt(best)


# --------------------------------------------------------------------------- strips
def polyline_segments(points: ArrayLike, groups: ArrayLike) -> F64:
    """Segments joining consecutive points of each group (in the given order).

    Parameters
    ----------
    points : array_like, shape (m, 3)
    groups : array_like of int, shape (m,)
        Group label per point (e.g. the strip of each image); −1 = no group.

    Returns
    -------
    ndarray, shape (k, 2, 3)
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    g = np.asarray(groups).reshape(-1)
    order = np.argsort(g, kind="stable")
    Ps, gs = P[order], g[order]
    same = (gs[1:] == gs[:-1]) & (gs[1:] >= 0)
    return np.stack([Ps[:-1][same], Ps[1:][same]], axis=1)


def footprints(
    X0: ArrayLike, R: ArrayLike, c: ArrayLike, format_mm: ArrayLike, ground_z: float
) -> F64:
    """Image corners projected onto the horizontal plane Z = ``ground_z`` (m).

    Returns
    -------
    ndarray, shape (m, 4, 3)
        Ground corners in the order of :func:`frustum_corners`; NaN where a corner ray
        does not reach the plane (looking upwards).
    """
    corners = frustum_corners(X0, R, c, format_mm, 1.0)
    apex = corners[:, :1]
    d = corners[:, 1:] - apex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (ground_z - apex[..., 2]) / d[..., 2]
    t = np.where(t > 0, t, np.nan)
    return apex + t[..., None] * d


def loop_segments(polygons: ArrayLike) -> F64:
    """Closed outlines of polygons (m, k, 3) as segments (m·k, 2, 3)."""
    Q = np.asarray(polygons, dtype=float)
    return np.stack([Q, np.roll(Q, -1, axis=1)], axis=2).reshape(-1, 2, 3)


def typical_spacing(points: ArrayLike) -> float:
    """A typical distance between neighbouring points (m): √(area / count), the area
    spanned by the two largest extents of their bounding box (a block: the horizontal
    one; a façade or an object photographed from the side: its own), far strays left out
    (:func:`core_points`)."""
    P = core_points(points)
    if P.shape[0] < 2:
        return 1.0
    ext = np.sort(P.max(axis=0) - P.min(axis=0))[::-1]
    if ext[0] < 1e-9 or ext[1] < 1e-9:
        return float(max(ext.max(), 1e-3) / P.shape[0])
    return float(np.sqrt(ext[0] * ext[1] / P.shape[0]))


#: Vertical field of view of the viewer's camera (rad) and the share of the window
#: width left of the GUI panel (1280 × 800 px: the panel takes the right ~28 %).
VIEW_FOV: float = np.radians(50.0)
VISIBLE_WIDTH: float = 0.72


def framing(
    points: ArrayLike,
    direction: ArrayLike = (0.3, 0.85, -0.65),
    fov: float = VIEW_FOV,
    aspect: float = 1.6,
    visible: float = VISIBLE_WIDTH,
    margin: float = 1.1,
    up: ArrayLike = (0.0, 0.0, 1.0),
    strays: bool = True,
) -> tuple[F64, F64]:
    """Camera (position, look_at) that shows all ``points`` (but far strays,
    :func:`core_points`, unless ``strays`` is False: then every finite point) left of
    the GUI panel.

    The bounding sphere of the points (about their bounding box's centre) fits the
    vertical field of view ``fov`` (rad) and the visible width (share ``visible`` of a
    window of ``aspect`` = width / height) with ``margin``; the camera looks along
    ``direction`` (its screen's up towards ``up``, default Z) and is shifted sideways so
    that the object sits in the middle of the part of the window the panel leaves free.
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    P = core_points(P) if strays else P[np.all(np.isfinite(P), axis=1)]
    if P.shape[0] == 0:
        return np.array([0.0, -3.0, 2.0]), np.zeros(3)
    centre = (P.min(axis=0) + P.max(axis=0)) / 2
    r = max(float(np.max(np.linalg.norm(P - centre, axis=1))), 1e-6)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    t = np.tan(fov / 2)
    half = min(np.arctan(t), np.arctan(aspect * visible * t))  # the narrower half-angle
    dist = margin * r / np.sin(half)
    right = np.cross(d, np.asarray(up, dtype=float))
    right = right / (np.linalg.norm(right) or 1.0)
    shift = (1.0 - visible) * dist * aspect * t * right
    return centre - dist * d + shift, centre + shift
