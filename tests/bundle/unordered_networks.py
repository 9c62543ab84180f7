"""A small close-range network for the tests of the reduced-system solvers and poor starts."""

from __future__ import annotations

import numpy as np

from orientviz.block import Block
from orientviz.rotation import opk_from_matrix


def close_range_network(m: int = 12, p: int = 120, seed: int = 5, start_error: float = 0.0):
    """Images on a ring (radius 6 m) looking at points in a 2 m cube; 6 control points.

    Returns the block (approximations off the truth by ``start_error`` m / 10·rad) and
    the true centres.
    """
    rng = np.random.default_rng(seed)
    az = np.linspace(0, 2 * np.pi, m, endpoint=False)
    X0 = np.column_stack([6 * np.cos(az), 6 * np.sin(az), 1.5 + rng.normal(0, 0.3, m)])
    R = np.empty((m, 3, 3))
    for i in range(m):  # image z axis away from the object (the camera looks along −z)
        z = X0[i] / np.linalg.norm(X0[i])
        x = np.cross([0.0, 0.0, 1.0], z)
        x /= np.linalg.norm(x)
        R[i] = np.column_stack([x, np.cross(z, x), z])
    angles = np.column_stack(opk_from_matrix(R, "opk")).reshape(-1, 3)
    xyz = rng.uniform(-1, 1, (p, 3))
    c = 20.0  # mm
    d = np.einsum("mji,pmj->pmi", R, xyz[:, None, :] - X0[None])  # (p, m, 3) image frame
    xy = -c * d[..., :2] / d[..., 2:3]
    seen = (np.abs(xy) < 12).all(-1) & (rng.uniform(size=(p, m)) < 0.8)
    pt, im = np.nonzero(seen)
    role = np.zeros(p, np.int64)
    role[:6] = 1
    obs_xy = xy[pt, im] + rng.normal(0, 0.002, (pt.size, 2))
    block = Block.from_arrays(
        camera_c=[c], image_camera=np.zeros(m, np.int64), X0=X0, angles=angles, xyz=xyz,
        obs_image=im, obs_point=pt, obs_xy=obs_xy, obs_sigma=0.002,
        camera_format_mm=(24.0, 24.0), role=role,
    )  # fmt: skip
    if start_error:
        block.images.X0 += rng.normal(0, start_error, (m, 3))
        block.images.angles += rng.normal(0, start_error / 10, (m, 3))
        block.points.xyz[6:] += rng.normal(0, start_error, (p - 6, 3))
    return block, X0
