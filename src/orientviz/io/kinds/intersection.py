"""Kind ``intersection``: object points from the rays of images with known orientation.

Tables as in a block (``schema/intersection.json``): cameras, images with *known*
X0, Y0, Z0, ω, φ, κ (all required, held fixed), points (X, Y, Z optional: if given for
a ``check`` point they are compared with the intersection) and observations. Every
point needs at least two rays.

All points are intersected at once by
:func:`orientviz.orientation.intersection.intersect_points` (linear start, then
collinearity least squares per point); the per-point results are pooled into one
:class:`~orientviz.adjust.Adjustment` (σ̂0 from the sum of vᵀPv over the sum of the
redundancies, redundancy numbers r_i = 1 − p_i (J Q Jᵀ)_ii per image coordinate).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...adjust.result import W_CRITICAL, Adjustment, Iteration
from ...block import CHECK, ROLES, Block
from ...camera import collinearity_jacobian
from ...errors import NotDeterminableError
from ...orientation.intersection import intersect_points
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ..solution import Solution
from ._checks import reject_first
from ._frame import block_from_tables, read_frame_tables, require_finite, tables_from_block


def load(doc: dict[str, Any], units: Units, source: str) -> Block:
    """Read an ``intersection`` document into a :class:`Block` (m, mm, rad)."""
    t = read_frame_tables(doc, source)
    opts = doc.get("options", {})
    block = block_from_tables(
        t, units, source, sequence=doc["sequence"], image_sigma=opts.get("image_sigma")
    )
    im = block.images
    require_finite(t.images, np.column_stack([im.X0, im.angles]),
                   ("X0", "Y0", "Z0", "omega", "phi", "kappa"), "the known orientation")  # fmt: skip
    rays = block.rays_per_point()
    reject_first(
        t.points, rays < 2, "id",
        lambda i: f"point {block.points.ids[i]!r} is observed in {rays[i]} image(s), an "
        "intersection needs at least 2 rays",
    )  # fmt: skip
    block.meta["name"] = doc.get("name", "")
    return block


def _pooled(block: Block, res, ids: list[str]) -> Adjustment:
    """One Adjustment for all points from the per-point intersection results."""
    obs = block.observations
    cam = block.images.camera[obs.image]
    cams = block.cameras
    p = block.n_points
    _, _, Jp, _ = collinearity_jacobian(
        res.xyz[obs.point], block.images.X0[obs.image], block.images.angles[obs.image],
        cams.c[cam], cams.x0[cam], cams.y0[cam], block.sequence,
    )  # fmt: skip
    sig = obs.sigma
    Q = res.cofactor[obs.point]  # (n, 3, 3)
    h = np.einsum("nij,njk,nik->ni", Jp, Q, Jp) / sig**2
    rn = np.clip(1.0 - h, 0.0, 1.0).reshape(-1)
    v = res.residuals.reshape(-1)
    s = sig.reshape(-1)
    dof = int(2 * len(obs) - 3 * p)
    cost = float(np.sum((v / s) ** 2))
    s0 = float(np.sqrt(cost / dof)) if dof > 0 else float("nan")
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(rn > 1e-10, v / (s * np.sqrt(rn)), np.nan)
    names = [f"{i}.{a}" for i in ids for a in "XYZ"]
    labels = [
        f"{block.images.ids[i]}/{ids[k]}/{a}" for i, k in zip(obs.image, obs.point) for a in "xy"
    ]
    x = res.xyz.reshape(-1)
    reason = (
        f"all points converged (≤ {res.iterations} Gauss-Newton steps per point)"
        if res.converged
        else f"not all points converged within {res.iterations} steps"
    )
    return Adjustment(
        x=x, names=names, sigma0=s0, redundancy=dof, residuals=v, sigma_obs=s,
        converged=bool(res.converged), reason=reason,
        history=[Iteration(0, x.copy(), None, s0, cost)],
        groups={"points": slice(0, 3 * p)}, redundancy_numbers=rn, normalized_residuals=w,
        cofactor_groups={"points": res.cofactor}, obs_labels=labels,
    )  # fmt: skip


def solve(problem: Problem, method: str | None) -> Solution:
    """Forward intersection of every observed point."""
    block: Block = problem.data
    obs = block.observations
    cam = block.images.camera
    max_iter = int(problem.options.get("max_iter", 10))
    res = intersect_points(
        obs.xy, obs.image, obs.point, block.images.X0, block.rotations(), block.cameras.c[cam],
        block.cameras.x0[cam], block.cameras.y0[cam], sigma=obs.sigma,
        n_points=block.n_points, max_iter=max_iter, on_degenerate="raise",
    )  # fmt: skip
    if not np.all(np.isfinite(res.xyz)):
        bad = [block.points.ids[i] for i in np.flatnonzero(~np.all(np.isfinite(res.xyz), axis=1))]
        raise NotDeterminableError(
            f"forward intersection: point(s) {', '.join(bad[:5])} are not determinable",
            parameters=[f"{b}.X" for b in bad],
        )
    ids = list(block.points.ids)
    adj = _pooled(block, res, ids)
    notes = []
    chk = np.flatnonzero(
        (block.points.role == CHECK) & np.all(np.isfinite(block.points.xyz_known), axis=1)
    )
    if chk.size:
        d = res.xyz[chk] - block.points.xyz_known[chk]
        rms = np.sqrt(np.mean(d**2, axis=0)) / problem.units.m_per_length
        notes.append(
            f"check points ({chk.size}): r.m.s. difference X {rms[0]:.4g}, Y {rms[1]:.4g}, "
            f"Z {rms[2]:.4g} {problem.units.length}"
        )
    m = block.n_images
    return Solution(
        kind="intersection",
        method="intersection",
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        point_ids=ids,
        xyz=res.xyz,
        xyz_sigma=adj.std().reshape(-1, 3),
        point_roles=[ROLES[r] for r in block.points.role],
        observation_quantity="image",
        critical=float(problem.options.get("critical", W_CRITICAL)),
        notes=notes + [f"{m} image orientation(s) held fixed as given"],
        iterations=int(res.iterations),
    )


KIND = register_kind(
    Kind(
        name="intersection",
        schema="intersection.json",
        load=load,
        dump=tables_from_block,
        solve=solve,
        description="forward intersection: points from images with known orientation",
        methods=("intersection",),
    )
)
