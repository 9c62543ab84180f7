"""A dense collinearity bundle for tiny test blocks: an independent reference (dense
N⁻¹) for the cofactor blocks the bundle selects (tests/viewer/test_precision_view.py).
It was the viewer's fallback solver (viewer/adjuster.small_bundle) before every viewer
path went through orientviz.bundle."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from orientviz.adjust import Adjustment, gauss_newton
from orientviz.block import Block
from orientviz.camera import collinearity_jacobian

SMALL_LIMIT = 3000


def small_bundle(block: Block, max_iter: int = 20, precision: bool = True) -> Adjustment:
    """A dense collinearity bundle for small blocks (fallback for the viewer's demos).

    Control coordinates with σ = 0 are held fixed, σ > 0 enter as weighted
    pseudo-observations; tie and check points are free. Interior orientation is fixed.

    Parameters
    ----------
    block : Block
        Start values and observations (mm, m, rad).
    max_iter : int
        Maximum number of Gauss-Newton steps (1 = a single step).
    precision : bool
        Accepted for the adjuster protocol; the dense precision is always computed.

    Returns
    -------
    Adjustment
        Blocks ``"exterior"`` and ``"points"``; residuals ordered x, y per observation
        (2n), then the control pseudo-observations.
    """
    m, p, n = block.n_images, block.n_points, block.n_observations
    u = 6 * m + 3 * p
    if u > SMALL_LIMIT:
        raise ValueError(f"small_bundle: {u} unknowns is too many for a dense test reference")
    obs, pts, cam = block.observations, block.points, block.cameras
    ci = block.images.camera[obs.image]
    given = (pts.role == 1)[:, None] & np.isfinite(pts.xyz_known) & np.isfinite(pts.sigma)
    fixed_pt = given & (pts.sigma == 0)
    weighted = np.argwhere(given & (pts.sigma > 0))
    fixed = np.zeros(u, bool)
    fixed[6 * m :] = fixed_pt.reshape(-1)
    x0 = np.concatenate(
        [np.hstack([block.images.X0, block.images.angles]).ravel(), pts.xyz.ravel()]
    )
    x0[6 * m :][fixed_pt.reshape(-1)] = pts.xyz_known[fixed_pt]
    l = np.concatenate([obs.xy.ravel(), pts.xyz_known[weighted[:, 0], weighted[:, 1]]])
    sig = np.concatenate([obs.sigma.ravel(), pts.sigma[weighted[:, 0], weighted[:, 1]]])
    rows = np.arange(2 * n).reshape(n, 2)

    def equations(x: np.ndarray):
        ext = x[: 6 * m].reshape(m, 6)
        xyz = x[6 * m :].reshape(p, 3)
        e = ext[obs.image]
        xy, Je, Jp, _ = collinearity_jacobian(
            xyz[obs.point], e[:, :3], e[:, 3:], cam.c[ci], cam.x0[ci], cam.y0[ci], block.sequence
        )
        r_e = np.repeat(rows, 6, axis=1)
        c_e = (6 * obs.image[:, None] + np.arange(6))[:, None, :].repeat(2, axis=1)
        r_p = np.repeat(rows, 3, axis=1)
        c_p = (6 * m + 3 * obs.point[:, None] + np.arange(3))[:, None, :].repeat(2, axis=1)
        k = weighted.shape[0]
        r_w = 2 * n + np.arange(k)
        c_w = 6 * m + 3 * weighted[:, 0] + weighted[:, 1]
        J = sp.csr_matrix(
            (
                np.concatenate([Je.ravel(), Jp.ravel(), np.ones(k)]),
                (
                    np.concatenate([r_e.ravel(), r_p.ravel(), r_w]),
                    np.concatenate([c_e.ravel(), c_p.ravel(), c_w]),
                ),
            ),
            shape=(2 * n + k, u),
        )
        f = np.concatenate([xy.ravel(), xyz[weighted[:, 0], weighted[:, 1]]])
        return f, J

    names = [
        f"{i}.{q}" for i in block.images.ids for q in ("X0", "Y0", "Z0", "omega", "phi", "kappa")
    ]
    names += [f"{i}.{q}" for i in pts.ids for q in ("X", "Y", "Z")]
    labels = [
        f"{block.images.ids[i]}/{pts.ids[j]}/{a}"
        for i, j in zip(obs.image, obs.point)
        for a in "xy"
    ]
    labels += [f"{pts.ids[i]}/{'XYZ'[j]}" for i, j in weighted]
    return gauss_newton(
        equations,
        x0,
        l,
        sig,
        names=names,
        groups={"exterior": slice(0, 6 * m), "points": slice(6 * m, u)},
        obs_labels=labels,
        fixed=fixed,
        max_iter=max_iter,
        context="viewer bundle",
    )
