"""Structural edits of a design block: images added (cross strips) or removed, and a
design made from any block with orientations.

All keep a design block a design block: planned geometry, image coordinates without
errors (projections of the points by the collinearity equations), weighted control.
They change the structure of the normal equations; :class:`orientviz.design.LiveDesign`
(``add_images``, ``remove_images``) updates the quality of such a change by one low-rank
step, or assesses the new design anew when the step would be too wide.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..block import CONTROL, TIE, Block
from ..camera import project
from ..errors import InputError
from ..rotation import matrix_from_opk

F64 = NDArray[np.float64]

#: Margin (mm) inside the image format within which a projected point counts as seen.
MARGIN_MM = 5.0


def _visible(block: Block, X0: F64, angles: F64, camera: int) -> tuple[NDArray, NDArray, F64]:
    """(image k, point j, xy mm) of every point inside the format of the new images."""
    cam = block.cameras
    c, x0, y0 = float(cam.c[camera]), float(cam.x0[camera]), float(cam.y0[camera])
    half = 0.5 * np.asarray(cam.format_mm[camera], float) - MARGIN_MM
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], block.sequence)
    P = block.points.xyz
    ks, js, xys = [], [], []
    for k in range(X0.shape[0]):
        uvw = (P - X0[k]) @ R[k]
        front = uvw[:, 2] < 0  # the image looks along −w
        xy = project(P, X0[k], R[k], c, x0, y0)
        inside = front & (np.abs(xy[:, 0] - x0) <= half[0]) & (np.abs(xy[:, 1] - y0) <= half[1])
        j = np.flatnonzero(inside)
        ks.append(np.full(j.size, k))
        js.append(j)
        xys.append(xy[j])
    return np.concatenate(ks), np.concatenate(js), np.concatenate(xys)


def add_images(
    block: Block, X0: ArrayLike, angles: ArrayLike, *, strip: ArrayLike | int | None = None,
    ids: list[str] | None = None, camera: int = 0,
) -> Block:  # fmt: skip
    """A copy of a design block with images added at planned orientations.

    Each new image observes every point inside its format (less :data:`MARGIN_MM`), with
    error-free image coordinates and the block's median image σ.

    Parameters
    ----------
    block : Block
        A design block.
    X0 : array_like, shape (k, 3)
        Projection centres of the new images, m.
    angles : array_like, shape (k, 3)
        Their ω, φ, κ (rad, the block's sequence).
    strip : int or array_like of int, optional
        Strip index of the new images (default: one new strip).
    ids : list of str, optional
        Their ids (default ``x<k>`` numbered after the block's images).
    camera : int
        Camera index.

    Returns
    -------
    Block

    Raises
    ------
    InputError
        If a new image sees fewer than 3 points.
    """
    X0 = np.atleast_2d(np.asarray(X0, float))
    ang = np.atleast_2d(np.asarray(angles, float))
    k = X0.shape[0]
    m = block.n_images
    if strip is None:
        strip = int(block.images.strip.max()) + 1 if m else 0
    st = np.broadcast_to(np.asarray(strip, np.int64), (k,))
    if ids is None:
        ids = [f"x{m + i:03d}" for i in range(k)]
    oi, op, xy = _visible(block, X0, ang, camera)
    few = [ids[i] for i in range(k) if np.sum(oi == i) < 3]
    if few:
        raise InputError(f"image {few[0]} would see fewer than 3 points of the design")
    I, O, P = block.images, block.observations, block.points
    s = float(np.median(O.sigma)) if O.sigma.size else 0.005
    b = Block.from_arrays(
        camera_c=block.cameras.c, camera_x0=block.cameras.x0, camera_y0=block.cameras.y0,
        camera_format_mm=block.cameras.format_mm, camera_ids=list(block.cameras.ids),
        image_camera=np.r_[I.camera, np.full(k, camera)], X0=np.vstack([I.X0, X0]),
        angles=np.vstack([I.angles, ang]), xyz=P.xyz.copy(), obs_image=np.r_[O.image, oi + m],
        obs_point=np.r_[O.point, op], obs_xy=np.vstack([O.xy, xy]),
        obs_sigma=np.vstack([O.sigma, np.full((oi.size, 2), s)]),
        image_ids=list(I.ids) + list(ids), point_ids=list(P.ids), role=P.role,
        xyz_known=P.xyz_known.copy(), point_sigma=P.sigma, strip=np.r_[I.strip, st],
        sequence=block.sequence, meta=dict(block.meta),
    )  # fmt: skip
    for name in ("X0_obs", "X0_sigma", "angles_obs", "angles_sigma"):
        old = getattr(I, name)
        new = getattr(b.images, name)
        new[:m] = old
        if name == "X0_obs":  # GNSS of the new images like the others' (if any)
            new[m:] = X0 if np.isfinite(old).any() else np.nan
        elif name == "X0_sigma":
            fin = old[np.isfinite(old)]
            new[m:] = float(np.median(fin)) if fin.size else np.nan
    return b


def cross_strip_images(
    block: Block, spec: dict[str, Any], x: float, *, ids_prefix: str = "c"
) -> tuple[F64, F64, int, list[str]]:
    """The images of a cross strip at X = ``x`` (m): projection centres (k, 3) m, ω φ κ
    (k, 3) rad, strip index and ids, as :func:`cross_strip` adds them."""
    P = block.points.xyz
    B = float(spec["base_m"])
    y0, y1 = float(P[:, 1].min()) - B, float(P[:, 1].max()) + B
    n = int(np.ceil((y1 - y0) / B)) + 1
    ys = y0 + B * np.arange(n)
    Z = float(np.median(block.images.X0[:, 2]))
    X0 = np.column_stack([np.full(n, float(x)), ys, np.full(n, Z)])
    ang = np.tile([0.0, 0.0, 0.5 * np.pi], (n, 1))
    seen = _visible(block, X0, ang, 0)[0]
    keep = np.bincount(seen, minlength=n) >= 3  # drop the images beyond the block's ends
    if keep.sum() < 2:
        raise InputError(f"a cross strip at X = {x:.0f} m would not overlap the block")
    X0, ang = X0[keep], ang[keep]
    strip = int(block.images.strip.max()) + 1
    ids = [f"{ids_prefix}{strip:02d}_{i:03d}" for i in range(X0.shape[0])]
    return X0, ang, strip, ids


def cross_strip(block: Block, spec: dict[str, Any], x: float, *, ids_prefix: str = "c") -> Block:
    """A copy of a design block with a cross strip flown along +Y at X = ``x`` (m).

    The cross strip has the block's flying height and air base (``spec["base_m"]``, so
    its forward overlap is the block's), κ = 90° (image x along +Y), and spans the
    block's points in Y (images that would see fewer than 3 points are left out). Its
    consecutive images may share too few points to form stereo models: the bundle takes
    such a strip, independent models (:func:`assess_models`) refuse it and name the models.
    """
    X0, ang, strip, ids = cross_strip_images(block, spec, x, ids_prefix=ids_prefix)
    return add_images(block, X0, ang, strip=strip, ids=ids)


def kept_after_removal(block: Block, images: ArrayLike) -> tuple[NDArray, NDArray]:
    """The rays (n,) and points (p,) of a block that stay when ``images`` are removed:
    the rays of the other images, less those of points left with fewer than 2 rays."""
    drop = np.zeros(block.n_images, bool)
    drop[np.asarray(images, np.int64)] = True
    O = block.observations
    keep_o = ~drop[O.image]
    keep_p = np.bincount(O.point[keep_o], minlength=block.n_points) >= 2
    return keep_o & keep_p[O.point], keep_p


def remove_images(block: Block, images: ArrayLike) -> Block:
    """A copy of a design block without some images (and their rays).

    Points left with fewer than 2 rays are removed too.

    Raises
    ------
    InputError
        If fewer than 2 images would remain.
    """
    drop = np.zeros(block.n_images, bool)
    drop[np.asarray(images, np.int64)] = True
    if (~drop).sum() < 2:
        raise InputError("a design needs at least 2 images")
    I, O, P = block.images, block.observations, block.points
    keep_o, keep_p = kept_after_removal(block, images)
    new_i = np.cumsum(~drop) - 1
    new_p = np.cumsum(keep_p) - 1
    b = Block.from_arrays(
        camera_c=block.cameras.c, camera_x0=block.cameras.x0, camera_y0=block.cameras.y0,
        camera_format_mm=block.cameras.format_mm, camera_ids=list(block.cameras.ids),
        image_camera=I.camera[~drop], X0=I.X0[~drop], angles=I.angles[~drop],
        xyz=P.xyz[keep_p], obs_image=new_i[O.image[keep_o]], obs_point=new_p[O.point[keep_o]],
        obs_xy=O.xy[keep_o], obs_sigma=O.sigma[keep_o],
        image_ids=[x for x, d in zip(I.ids, drop) if not d],
        point_ids=[x for x, k in zip(P.ids, keep_p) if k], role=P.role[keep_p],
        xyz_known=P.xyz_known[keep_p], point_sigma=P.sigma[keep_p], strip=I.strip[~drop],
        sequence=block.sequence, meta=dict(block.meta),
    )  # fmt: skip
    for name in ("X0_obs", "X0_sigma", "angles_obs", "angles_sigma"):
        getattr(b.images, name)[:] = getattr(I, name)[~drop]
    return b


def design_from_block(
    block: Block, *, sigma_control: float = 0.02, sigma_image_mm: float | None = None
) -> tuple[Block, dict[str, Any]]:
    """A design block with the geometry of any block (e.g. an adjusted problem file).

    The image coordinates become the projections of the block's points by its
    orientations (no errors; lens distortion not modelled); control coordinates are
    weighted (their σ where given and > 0, else ``sigma_control``); check points become
    tie points; points with fewer than 2 rays are removed.

    Parameters
    ----------
    block : Block
        Orientations (``images.X0``, ``angles``) and points (``points.xyz``) in m, rad.
    sigma_control : float
        σ (m) of control coordinates that the block holds fixed (σ = 0 or NaN).
    sigma_image_mm : float, optional
        σ of every image coordinate, mm (default: the block's own).

    Returns
    -------
    block : Block
    spec : dict
        ``base_m`` (median distance of each projection centre to its nearest one, m),
        ``flying_height_m`` (median height of the centres above the points, m),
        ``source`` ("block").
    """
    if not sigma_control > 0:
        raise InputError(f"sigma_control: expected σ > 0 m, got {sigma_control}")
    b = block.copy()
    k = len(b.cameras.ids)
    b.cameras.ap_set, b.cameras.model = [""] * k, [{} for _ in range(k)]  # geometry only
    ok = np.isfinite(b.points.xyz).all(axis=1)
    fine = np.isfinite(b.images.X0).all(axis=1) & np.isfinite(b.images.angles).all(axis=1)
    O = b.observations
    use = ok[O.point] & fine[O.image]
    R = b.rotations()
    cam = b.cameras
    ci = b.images.camera[O.image]
    xy = project(b.points.xyz[O.point], b.images.X0[O.image], R[O.image], cam.c[ci],
                 cam.x0[ci], cam.y0[ci])  # fmt: skip
    O.xy[use] = xy[use]
    if sigma_image_mm is not None:
        O.sigma[:] = sigma_image_mm
    P = b.points
    ctrl = P.role == CONTROL
    P.role[P.role != CONTROL] = TIE
    P.xyz_known[~ctrl] = np.nan
    P.sigma[~ctrl] = np.nan
    given = np.isfinite(P.xyz_known) & ctrl[:, None]
    P.xyz_known[given] = P.xyz[given]
    weak = given & ~(np.nan_to_num(P.sigma, nan=0.0) > 0)
    P.sigma[weak] = sigma_control
    P.sigma[~given] = np.nan
    bad_images = np.flatnonzero(~fine)
    out = remove_images(b, bad_images) if bad_images.size else b
    rays = out.rays_per_point()
    if (rays < 2).any() or not use.all():
        keep_o = np.isfinite(out.observations.xy).all(axis=1)
        out = _drop_points(out, rays >= 2, keep_o)
    X0 = out.images.X0
    d = np.linalg.norm(X0[:, None, :2] - X0[None, :, :2], axis=2)
    np.fill_diagonal(d, np.inf)
    spec = {
        "base_m": float(np.median(d.min(axis=1))),
        "flying_height_m": float(np.median(X0[:, 2]) - np.median(out.points.xyz[:, 2])),
        "source": "block",
    }
    out.meta = {**out.meta, "source": "orientviz.design.design_from_block"}
    return out, spec


def _drop_points(block: Block, keep_p: NDArray, keep_o: NDArray) -> Block:
    """The block without the points not in ``keep_p`` and the rays not in ``keep_o``."""
    O = block.observations
    keep_o = keep_o & keep_p[O.point]
    rays = np.bincount(O.point[keep_o], minlength=block.n_points)
    keep_p = keep_p & (rays >= 2)
    keep_o &= keep_p[O.point]
    new_p = np.cumsum(keep_p) - 1
    I, P = block.images, block.points
    b = Block.from_arrays(
        camera_c=block.cameras.c, camera_x0=block.cameras.x0, camera_y0=block.cameras.y0,
        camera_format_mm=block.cameras.format_mm, camera_ids=list(block.cameras.ids),
        image_camera=I.camera, X0=I.X0, angles=I.angles, xyz=P.xyz[keep_p],
        obs_image=O.image[keep_o], obs_point=new_p[O.point[keep_o]], obs_xy=O.xy[keep_o],
        obs_sigma=O.sigma[keep_o], image_ids=list(I.ids),
        point_ids=[x for x, k in zip(P.ids, keep_p) if k], role=P.role[keep_p],
        xyz_known=P.xyz_known[keep_p], point_sigma=P.sigma[keep_p], strip=I.strip,
        sequence=block.sequence, meta=dict(block.meta),
    )  # fmt: skip
    for name in ("X0_obs", "X0_sigma", "angles_obs", "angles_sigma"):
        getattr(b.images, name)[:] = getattr(I, name)
    return b
