"""Shapes for the 3D viewer as plain arrays: colour ramps, ellipsoid meshes, circles, spheres.

No viser here (see :mod:`orientviz.viewer.geometry` for cameras, rays and residual
vectors). Lengths in m (or whatever unit the inputs use), line segments as (n, 2, 3).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

F64 = NDArray[np.float64]


# --------------------------------------------------------------------------- colours
def vertex_colours(rgb: ArrayLike) -> NDArray[np.uint8]:
    """sRGB colours (..., 3) uint8 as viser's per-vertex colours take them.

    viser's page takes a node's single colour as sRGB but per-vertex colours as linear,
    and encodes what it draws as sRGB; without this a per-vertex colour is drawn lighter
    than the same colour given once (and than the legend's swatch). This decodes sRGB to
    linear (IEC 61966-2-1).
    """
    c = np.asarray(rgb, dtype=float) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.round(255.0 * lin).astype(np.uint8)


def ramp(values: ArrayLike, vmax: float, stops: ArrayLike | None = None) -> NDArray[np.uint8]:
    """Map values in [0, vmax] to RGB (uint8) along a colour ramp (default green→amber→red).

    Parameters
    ----------
    values : array_like, shape (n,)
        Non-negative values, e.g. the size of a normalised residual; NaN is drawn grey.
    vmax : float
        Value that maps to the last stop; larger values saturate.
    stops : array_like, shape (k, 3), optional
        RGB stops (0-255), evenly spaced over [0, vmax].
    """
    S = np.asarray(
        [[40, 160, 80], [240, 170, 20], [210, 30, 30]] if stops is None else stops, dtype=float
    )
    v = np.asarray(values, dtype=float).reshape(-1)
    t = np.clip(np.nan_to_num(v / max(vmax, 1e-300), nan=0.0), 0.0, 1.0) * (len(S) - 1)
    i = np.minimum(t.astype(int), len(S) - 2)
    f = (t - i)[:, None]
    out = S[i] * (1 - f) + S[i + 1] * f
    out[np.isnan(v)] = 150.0
    return np.round(out).astype(np.uint8)


# --------------------------------------------------------------------------- meshes
def icosphere(subdivisions: int = 1) -> tuple[F64, NDArray[np.int32]]:
    """Unit icosphere: vertices (v, 3) on the unit sphere and triangles (f, 3)."""
    t = (1.0 + 5.0**0.5) / 2.0
    V = [
        [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
        [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
        [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
    ]  # fmt: skip
    F = [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ]  # fmt: skip
    verts = [np.array(v, dtype=float) / np.linalg.norm(v) for v in V]
    faces = F
    for _ in range(subdivisions):
        cache: dict[tuple[int, int], int] = {}

        def mid(a: int, b: int, cache: dict[tuple[int, int], int] = cache) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = verts[a] + verts[b]
                verts.append(p / np.linalg.norm(p))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = new
    return np.array(verts), np.array(faces, dtype=np.int32)


def ellipsoid_mesh(
    centers: ArrayLike, covariances: ArrayLike, scale: float = 1.0, subdivisions: int = 1
) -> tuple[F64, NDArray[np.int32]]:
    """One mesh holding the error ellipsoids of many points.

    The ellipsoid of a point is {X : (X − c)ᵀ Σ⁻¹ (X − c) = scale²}, i.e. the unit
    sphere mapped by scale · L with Σ = L Lᵀ (eigen-decomposition, negative
    eigenvalues clipped to 0).

    Parameters
    ----------
    centers : array_like, shape (n, 3)
        Centres in m.
    covariances : array_like, shape (n, 3, 3)
        Covariance matrices in m².
    scale : float
        Exaggeration (and confidence factor), e.g. 1 for the 1σ ellipsoid × 1.
    subdivisions : int
        Icosphere refinement (1 → 42 vertices per ellipsoid).

    Returns
    -------
    vertices : ndarray, shape (n·v, 3)
    faces : ndarray of int32, shape (n·f, 3)
    """
    C = np.asarray(centers, dtype=float).reshape(-1, 3)
    S = np.asarray(covariances, dtype=float).reshape(-1, 3, 3)
    ev, U = np.linalg.eigh(0.5 * (S + np.swapaxes(S, 1, 2)))
    L = U * np.sqrt(np.clip(ev, 0.0, None))[:, None, :]
    sv, sf = icosphere(subdivisions)
    verts = C[:, None, :] + scale * np.einsum("nij,vj->nvi", L, sv)
    faces = sf[None, :, :] + (np.arange(C.shape[0]) * sv.shape[0])[:, None, None]
    return verts.reshape(-1, 3), faces.reshape(-1, 3).astype(np.int32)


# --------------------------------------------------------------------------- circles, spheres
def circle_segments(centers: ArrayLike, normals: ArrayLike, radii: ArrayLike, n: int = 96) -> F64:
    """Circles (centre, plane normal, radius) as closed polylines, shape (k·n, 2, 3)."""
    C = np.asarray(centers, dtype=float).reshape(-1, 3)
    N = np.broadcast_to(np.asarray(normals, dtype=float), C.shape).copy()
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    r = np.broadcast_to(np.asarray(radii, dtype=float), (C.shape[0],))
    helper = np.where(np.abs(N[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    a = np.cross(N, helper)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(N, a)
    t = np.linspace(0.0, 2.0 * np.pi, n + 1)
    ring = (
        C[:, None, :]
        + r[:, None, None] * (np.cos(t)[None, :, None] * a[:, None, :])
        + r[:, None, None] * (np.sin(t)[None, :, None] * b[:, None, :])
    )
    return np.stack([ring[:, :-1], ring[:, 1:]], axis=2).reshape(-1, 2, 3)


def sphere_wire_segments(
    centers: ArrayLike, radii: ArrayLike, n_lat: int = 6, n_lon: int = 8, n: int = 64
) -> F64:
    """Wireframe spheres: ``n_lat`` parallels and ``n_lon`` meridians each, (k, 2, 3) segments."""
    C = np.asarray(centers, dtype=float).reshape(-1, 3)
    r = np.broadcast_to(np.asarray(radii, dtype=float), (C.shape[0],))
    parts = []
    for lat in np.linspace(-np.pi / 2, np.pi / 2, n_lat + 2)[1:-1]:
        cc = C + np.array([0.0, 0.0, 1.0]) * (r * np.sin(lat))[:, None]
        parts.append(circle_segments(cc, [0.0, 0.0, 1.0], r * np.cos(lat), n))
    for lon in np.linspace(0.0, np.pi, n_lon, endpoint=False):
        parts.append(circle_segments(C, [np.sin(lon), -np.cos(lon), 0.0], r, n))
    return np.concatenate(parts, axis=0)
