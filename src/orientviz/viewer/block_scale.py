"""The sizes and directions a block's scene is drawn with, for any block.

An aerial block has a natural scale and a natural up: the flying height above the
ground and Z. A reconstruction from hand-held or close-range photographs (a COLMAP or
BAL model) has neither: its frame points anywhere and its unit is arbitrary. These
functions read both from the block itself, so that frustums, the first view and the
sliders fit the data at any scale:

* :func:`viewing_depth` — the typical distance from a camera to the points it sees,
  measured along its axis (an aerial block: about the flying height);
* :func:`camera_spacing` — the typical distance between neighbouring cameras;
* :func:`up_direction` — Z for an aerial block, else the mean "up" of the images (their
  image y axis in the object frame: photographs are held upright), or against their
  common viewing direction (a drone's nadir images in a frame of its own);
* :func:`view_direction` — the first view's direction: obliquely down onto the block,
  from behind the cameras when they look one way.

Units: whatever the block's lengths are (m, or a reconstruction's model units).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..block import Block

F64 = NDArray[np.float64]

#: At most this many observations are sampled for the viewing depth.
DEPTH_SAMPLE: int = 20_000


def viewing_depth(block: Block, rotations: F64) -> float:
    """The median depth of the observed points in front of their cameras (block units).

    Depth = the distance along the camera's axis (−z of the image frame), over up to
    :data:`DEPTH_SAMPLE` observations spread over the block; points behind a camera and
    non-finite values do not count. NaN when nothing counts.
    """
    o = block.observations
    n = o.image.size
    if n == 0:
        return float("nan")
    k = np.linspace(0, n - 1, min(n, DEPTH_SAMPLE)).astype(np.int64)
    img, pt = o.image[k], o.point[k]
    d = block.points.xyz[pt] - block.images.X0[img]
    depth = -np.einsum("ni,ni->n", d, rotations[img, :, 2])  # R·(0, 0, −1) is the axis
    depth = depth[np.isfinite(depth) & (depth > 0)]
    return float(np.median(depth)) if depth.size else float("nan")


def camera_spacing(X0: F64) -> float:
    """The median distance from each projection centre to its nearest neighbour (block
    units); NaN for fewer than two finite centres."""
    X = np.asarray(X0, dtype=float).reshape(-1, 3)
    X = X[np.all(np.isfinite(X), axis=1)]
    if X.shape[0] < 2:
        return float("nan")
    if X.shape[0] > 1500:  # a tree instead of all pairs (memory)
        from scipy.spatial import cKDTree  # only for very large blocks

        dist = cKDTree(X).query(X, k=2)[0][:, 1]
    else:
        D = np.linalg.norm(X[:, None, :] - X[None, :, :], axis=2)
        np.fill_diagonal(D, np.inf)
        dist = D.min(axis=1)
    dist = dist[dist > 0]
    return float(np.median(dist)) if dist.size else float("nan")


def up_direction(rotations: F64, aerial: bool) -> F64:
    """The scene's up (3,): Z for an aerial block, else the mean image y axis in the
    object frame (photographs are taken upright); when the images disagree on that (a
    drone's strips flown back and forth) but look one way, against their viewing
    direction (they look down); else Z."""
    z = np.array([0.0, 0.0, 1.0])
    if aerial or rotations.shape[0] == 0:
        return z
    # the image y axis (upright photographs), then the image z axis = against the view
    for axis, least in ((1, 0.3), (2, 0.7)):
        m = np.nanmean(rotations[:, :, axis], axis=0)
        norm = float(np.linalg.norm(m)) if np.all(np.isfinite(m)) else 0.0
        if norm > least:
            return m / norm
    return z


def view_direction(up: F64, rotations: F64) -> F64:
    """The first view's direction (3,), unit length: about 40° down (against ``up``),
    horizontally along the cameras' mean viewing direction when they look one way (a
    street, a façade), else along a fixed horizontal axis (an object seen all round)."""
    look = -np.nanmean(rotations[:, :, 2], axis=0) if rotations.shape[0] else np.zeros(3)
    h = look - float(look @ up) * up if np.all(np.isfinite(look)) else np.zeros(3)
    if np.linalg.norm(h) < 0.3:
        for axis in np.eye(3)[[1, 0, 2]]:  # the first axis clearly off the up direction
            h = axis - float(axis @ up) * up
            if np.linalg.norm(h) > 0.5:
                break
    h = h / np.linalg.norm(h)
    d = 0.77 * h - 0.64 * up
    return d / np.linalg.norm(d)
