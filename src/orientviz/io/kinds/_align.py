"""Bring given approximations into the frame of the control points before a bundle.

A block imported from COLMAP (or any free network) comes with orientations and points in
its own arbitrary frame, while control points are given in a national grid: the bundle
would start hundreds of metres (and a scale factor) away and diverge. This step
intersects the control points from the given orientations, fits the 7-parameter
similarity (closed form, :func:`orientviz.orientation.absolute.similarity_closed_form`)
from that frame onto the control, and — when the frames differ — carries every given
orientation and point through it. When it cannot (fewer than three usable control
points, collinear control) and the frames evidently differ, it says so and names the
datum choices. Units: m, rad; rotations in the block's sequence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...block import CONTROL, Block
from ...errors import InputError
from ...rotation import opk_from_matrix

#: The frames differ when the control misfits the approximations by more than this share
#: of the control's extent (and the similarity removes most of it).
FRAME_MISFIT: float = 0.01


@dataclass
class Alignment:
    """What :func:`align_to_control` did: ``applied``, the similarity (scale, R, t), the
    control points used and the r.m.s. misfit before/after (m)."""

    applied: bool
    scale: float = 1.0
    used: int = 0
    rms_before: float = 0.0
    rms_after: float = 0.0

    def note(self) -> str:
        if not self.applied:
            return ""
        return (
            f"approximations aligned to the control first (7-parameter similarity from "
            f"{self.used} control points: scale {self.scale:.6g}, control misfit "
            f"{self.rms_before:.4g} → {self.rms_after:.4g} m r.m.s.)"
        )


def intersect_from_orientations(block: Block, points: np.ndarray) -> np.ndarray:
    """XYZ (p, 3) m of the points ``points`` (bool mask) intersected from the block's given
    orientations (NaN where fewer than two rays or parallel ones)."""
    from ...orientation.intersection import intersect_points  # only for points without coordinates

    obs = block.observations
    sel = points[obs.point]
    cam = block.images.camera
    return intersect_points(
        obs.xy[sel], obs.image[sel], obs.point[sel], block.images.X0, block.rotations(),
        block.cameras.c[cam], block.cameras.x0[cam], block.cameras.y0[cam],
        sigma=obs.sigma[sel], n_points=block.n_points, on_degenerate="nan",
    ).xyz  # fmt: skip


def align_to_control(block: Block) -> tuple[Block, Alignment]:
    """``block`` in the control's frame if its approximations are in another one."""
    pts = block.points
    full = (pts.role == CONTROL) & np.isfinite(pts.xyz_known).all(axis=1)
    if not full.any():
        return block, Alignment(False)
    xyz = intersect_from_orientations(block, full)
    use = full & np.isfinite(xyz).all(axis=1)  # control seen in ≥ 2 images
    known = pts.xyz_known[use]
    approx = xyz[use]
    extent = float(np.max(np.ptp(known, axis=0))) if use.sum() > 1 else 0.0
    misfit = float(np.sqrt(np.mean(np.sum((approx - known) ** 2, axis=1)))) if use.any() else 0.0
    scale_ok = extent > 0 and misfit <= FRAME_MISFIT * extent
    if use.sum() < 3 or _collinear(known):
        if use.any() and not scale_ok and misfit > 0:
            ids = [pts.ids[i] for i in np.flatnonzero(use)]
            raise InputError(
                f"the control points ({', '.join(ids)}) lie {misfit:.4g} m (r.m.s.) from where "
                "the given orientations put them: the approximations are in another frame, and "
                f"{int(use.sum())} usable control point(s){' (collinear)' if use.sum() >= 3 else ''} "
                "cannot carry them over (a 7-parameter similarity needs 3 non-collinear "
                "points). Datum choices: give at least 3 control points seen in 2 images, or "
                "give the orientations in the control's frame, or remove the control and "
                "adjust as a free network",
                block.meta.get("source"),
            )
        return block, Alignment(False)
    from ...orientation.absolute import similarity_closed_form  # only a block with control

    T = similarity_closed_form(approx, known)
    after = float(np.sqrt(np.mean(np.sum((T.apply(approx) - known) ** 2, axis=1))))
    if scale_ok or misfit < 3 * after:
        return block, Alignment(False, used=int(use.sum()), rms_before=misfit, rms_after=misfit)
    out = block.copy()
    out.images.X0 = T.apply(block.images.X0)
    R = T.R[None] @ block.rotations()
    out.images.angles = np.column_stack(opk_from_matrix(R, block.sequence)).reshape(-1, 3)
    free = np.isfinite(pts.xyz).all(axis=1)
    out.points.xyz[free] = T.apply(pts.xyz[free])
    out.points.xyz[full] = pts.xyz_known[full]
    return out, Alignment(True, float(T.scale), int(use.sum()), misfit, after)


def _collinear(xyz: np.ndarray) -> bool:
    if xyz.shape[0] < 3:
        return True
    s = np.linalg.svd(xyz - xyz.mean(axis=0), compute_uv=False)
    return bool(s[1] <= 1e-6 * max(s[0], 1e-300))
