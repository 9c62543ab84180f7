"""Automatic approximate values for the bundle adjustment.

Ackermann (1974, §11) stresses that the bundle method, unlike independent models,
depends strongly on approximate values and that obtaining them automatically is a
problem of its own. This module builds them from the image coordinates and the control
alone — the stored orientations and tie-point coordinates of the block are ignored:

1. **Seed pair** — among the pairs with at least 80 % of the largest number of common
   points, the one nearest the middle of the image graph; their relative orientation
   from the essential matrix (normalised eight-point algorithm and the cheirality test,
   :mod:`orientviz.orientation.essential`), base length 1 in a local model frame (left
   image: X0 = 0, R = I).
2. **Growth in waves** (``approximate/_growth.py``) — each wave orients
   all images that see enough intersected points (≥ ``min_points`` and ≥ half as many
   as the best-connected waiting image) in one stacked Levenberg-Marquardt resection
   (``approximate/_batch.py``; start: the attitude of the best-connected
   oriented neighbour turned by the in-image rotation between the two images, and the
   centre that fits the rays best with it; the three-point closed form of
   :mod:`orientviz.orientation.resection` only when the batch orients none), intersects
   every point of the new images from all its oriented rays in one call
   (:func:`~orientviz.orientation.intersection.intersect_rays`), and adjusts the images
   of the last two waves with their points by a local bundle, the rest held (``approximate/_front.py``).
   The whole oriented part is re-adjusted in the model frame (2 Gauss-Newton steps of
   :func:`~orientviz.bundle.bundle_adjust`) when it has doubled since the last time, and
   when the local bundle fits poorly (σ̂0 > 20: the chain has bent — in an aerial block
   the strips hang on narrow side-overlap bands, and their roll errors grow from strip to
   strip), and at the end.
3. **Datum** — a 3D similarity transformation (closed form) from the model frame to
   the control points carries everything into object space; without 3 control points
   not on a line, to the observed projection centres (``images.X0_obs`` with σ > 0,
   e.g. GNSS; 3 or more not on a line); with ``frame="model"`` (a free network) the
   result stays in the seed pair's model frame. Control points with given X, Y, Z need
   only one ray (they keep their coordinates).

Units: m, mm, rad; rotation sequence of the block (``"opk"`` R = R_ω R_φ R_κ or
``"pok"`` R = R_φ R_ω R_κ). Timings on the peer bench's blocks:
``benchmarks/bench_approximations.py`` and benchmarks/README.md.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, Block
from ..errors import NotDeterminableError
from ..orientation.absolute import SimilarityTransform, similarity_closed_form
from ..rotation import opk_from_matrix
from ._growth import Growth

F64 = NDArray[np.float64]


def approximate_values(block: Block, *, min_points: int = 6, frame: str = "control") -> Block:
    """A copy of ``block`` with approximate orientations and points computed from scratch.

    Parameters
    ----------
    block : Block
        Image observations, interior orientation and control (role 1 with
        ``xyz_known``); check points are not used.
    min_points : int
        Minimum number of known points for resecting an image.
    frame : {"control", "model"}
        ``"control"``: carry the result onto the control points (3 or more full XYZ
        control points needed). ``"model"``: leave it in the model frame of the seed
        pair (first image at the origin with R = I, base length 1 m) — the start of a
        free network, whose datum is then chosen by the caller.

    Returns
    -------
    Block
        ``images.X0`` (m), ``images.angles`` (rad, ``block.sequence``) and
        ``points.xyz`` (m) replaced; control points keep their given coordinates.

    Raises
    ------
    NotDeterminableError
        If images cannot be reached from the seed pair, points stay without two
        oriented rays, or fewer than 3 full XYZ control points are intersected.
    """
    g = Growth(block, min_points)
    g.grow()
    out, T = into_frame(block, g.P, g.Xm, g.Rm, g.done, frame)
    out.meta = dict(
        block.meta,
        approximate_values={
            "seed_pair": [int(g.seed[0]), int(g.seed[1])],
            "similarity_scale": T.scale,
            "waves": g.waves,
            "refines": g.refines,
        },
    )
    return out


def into_frame(block: Block, P: F64, Xm: F64, Rm: F64, done: NDArray[np.bool_], frame: str):
    """Carry a model-frame orientation of ``block`` into the frame of the datum.

    Parameters
    ----------
    block : Block
        The block whose approximations are computed.
    P : ndarray, shape (p, 3)
        Points in the model frame (NaN where not intersected).
    Xm : ndarray, shape (m, 3)
        Projection centres in the model frame.
    Rm : ndarray, shape (m, 3, 3)
        Rotations image → model frame.
    done : ndarray of bool, shape (m,)
        Images that were oriented.
    frame : {"control", "model"}
        See :func:`approximate_values`.

    Returns
    -------
    out : Block
        A copy of ``block`` with X0 (m), angles (rad) and points (m) replaced.
    T : SimilarityTransform
        Model frame → datum frame (the identity for ``"model"``).

    Raises
    ------
    NotDeterminableError
        Too few or collinear control points / observed centres, or points left
        without two oriented rays.
    """
    # ---- datum: similarity from the model frame onto the full-XYZ control points
    ctrl = np.flatnonzero(
        (block.points.role == CONTROL)
        & np.isfinite(block.points.xyz_known).all(axis=1)
        & np.isfinite(P).all(axis=1)
    )
    # observed projection centres (GNSS) can carry the datum where control cannot
    gnss = np.flatnonzero(np.isfinite(block.images.X0_obs).all(axis=1)
                          & (block.images.X0_sigma > 0).all(axis=1) & done)  # fmt: skip
    if frame == "model":
        T = SimilarityTransform(1.0, np.eye(3), np.zeros(3))  # stay in the model frame
    elif (ctrl.size < 3 or _collinear(block.points.xyz_known[ctrl])) and (
        gnss.size >= 3 and not _collinear(block.images.X0_obs[gnss])
    ):
        T = similarity_closed_form(Xm[gnss], block.images.X0_obs[gnss])
    elif ctrl.size < 3 or _collinear(block.points.xyz_known[ctrl]):
        raise NotDeterminableError(
            f"approximate values: {ctrl.size} full XYZ control point(s) reached"
            + (" (on a line)" if ctrl.size >= 3 else "")
            + ", the similarity into the control's frame needs 3 not on a line. Datum "
            "choices: give 3 or more control points (X, Y, Z) seen in the images; or observed "
            "projection centres (3 or more not on a line); or give the images' approximate "
            "orientations and hold some (options.fix / --fix ID); or adjust as a free "
            "network (options.free / --free)"
        )
    else:
        T = similarity_closed_form(P[ctrl], block.points.xyz_known[ctrl])
    # a control point with given X, Y, Z needs no intersection (one ray suffices)
    given_xyz = (block.points.role == CONTROL) & np.isfinite(block.points.xyz_known).all(axis=1)
    missing = ~np.isfinite(P).all(axis=1) & (block.points.role != CHECK) & ~given_xyz
    if missing.any():
        ids = [block.points.ids[j] for j in np.flatnonzero(missing)[:8]]
        raise NotDeterminableError(
            f"approximate values: {int(missing.sum())} point(s) without two oriented rays: "
            f"{', '.join(ids)}",
            parameters=[f"{j}.X" for j in ids],
        )
    out = block.copy()
    R = T.R[None] @ Rm
    om, ph, ka = opk_from_matrix(R, block.sequence)
    out.images.X0 = T.apply(Xm)
    out.images.angles = np.column_stack([om, ph, ka])
    xyz = np.where(np.isfinite(P), T.apply(np.nan_to_num(P)), block.points.xyz)
    given = np.isfinite(block.points.xyz_known) & (block.points.role == CONTROL)[:, None]
    out.points.xyz = np.where(given, block.points.xyz_known, xyz)
    return out, T


def _collinear(xyz: F64) -> bool:
    """Points (k, 3) on one line (or fewer than 3)."""
    if xyz.shape[0] < 3:
        return True
    s = np.linalg.svd(xyz - xyz.mean(axis=0), compute_uv=False)
    return bool(s[1] <= 1e-6 * max(s[0], 1e-300))
