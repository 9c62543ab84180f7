"""Load the peer bench's synthetic blocks (``make_block.py`` ``.npz``) as orientviz Blocks.

Benchmark-only helper (the bench data are not part of the package). The ``.npz``
holds angles in gon with R = R_ω R_φ R_κ (image → object), image coordinates in mm
(x right, y up, image plane at z = −c) — orientviz's own conventions, so only the
angle unit is converted.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from orientviz.block import Block
from orientviz.units import to_rad

BENCH_DIR = Path("/work/shared/bench")


def data_dir() -> Path:
    """Where make_block.py writes: $ORIENTVIZ_BENCH_DATA or /tmp/orientviz-bench."""
    return Path(os.environ.get("ORIENTVIZ_BENCH_DATA", "/tmp/orientviz-bench"))


def npz_path(size: str, seed: int = 1) -> Path:
    return data_dir() / f"aerial_{size}_seed{seed}.npz"


def user_arrays(block: Block) -> dict:
    """The in-memory arrays a user would hold for ``block``: the keyword arguments of
    ``Block.from_arrays`` (the timed path of ``bench_bundle.py`` builds the block from
    them)."""
    return dict(
        camera_c=block.cameras.c,
        camera_format_mm=block.cameras.format_mm[0],
        image_camera=block.images.camera,
        X0=block.images.X0,
        angles=block.images.angles,
        xyz=block.points.xyz,
        obs_image=block.observations.image,
        obs_point=block.observations.point,
        obs_xy=block.observations.xy,
        obs_sigma=block.observations.sigma,
        role=block.points.role,
        xyz_known=block.points.xyz_known,
        point_sigma=block.points.sigma,
    )


def load_bench_block(path, control: str = "fixed"):
    """Return ``(block, truth)`` from a make_block ``.npz``.

    ``truth`` is a dict with ``X0`` (m, 3) m, ``angles`` (m, 3) rad, ``xyz`` (p, 3) m and
    ``is_control`` (p,). With ``control="weighted"`` the control points get the npz's
    ``control_sigma_m`` as σ.
    """
    z = np.load(path)
    p = z["pt_init"].shape[0]
    role = np.zeros(p, np.int8)
    role[z["control_idx"]] = 1
    known = np.full((p, 3), np.nan)
    known[z["control_idx"]] = z["control_xyz"]
    sig = np.zeros((p, 3))
    if control == "weighted":
        sig[z["control_idx"]] = float(z["control_sigma_m"])
    block = Block.from_arrays(
        camera_c=[float(z["c_mm"])],
        camera_format_mm=(float(z["format_mm"]), float(z["format_mm"])),
        image_camera=np.zeros(z["cam_init_C"].shape[0], np.int64),
        X0=z["cam_init_C"],
        angles=to_rad(z["cam_init_opk_gon"], "gon"),
        xyz=z["pt_init"],
        obs_image=z["obs_cam"],
        obs_point=z["obs_pt"],
        obs_xy=z["obs_xy_mm"],
        obs_sigma=float(z["sigma_mm"]),
        role=role,
        xyz_known=known,
        point_sigma=sig,
        strip=z["cam_strip"],
        sequence="opk",
        meta={"source": str(path)},
    )
    truth = {
        "X0": z["cam_truth_C"],
        "angles": to_rad(z["cam_truth_opk_gon"], "gon"),
        "xyz": z["pt_truth"],
        "is_control": z["pt_is_control"].astype(bool),
    }
    return block, truth
