"""Kind ``block``: a photogrammetric block for the bundle (or model/polynomial) adjustment.

Tables: ``cameras``, ``images``, ``points``, ``observations`` (see
:mod:`orientviz.io.kinds._frame` and ``schema/block.json``). Images need approximate
orientations (X0, Y0, Z0, ω, φ, κ); tie points may leave X, Y, Z out, they are then
intersected from the approximate orientations before the adjustment. Every tie and
check point needs at least two rays, every control point at least one.

Options: ``control`` (``"fixed"``/``"weighted"``), ``max_iter``, ``tol``, ``critical``,
``image_sigma``. Methods: ``bundle`` (default), ``models``, ``polynomial`` (the latter
two when :mod:`orientviz.block.models` / :mod:`orientviz.block.polynomial` exist).
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any

import numpy as np

from ...errors import InputError
from ...model import CHECK, CONTROL, ROLES, TIE, Block
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ..report import Solution
from ._frame import block_from_tables, read_frame_tables, require_finite, tables_from_block

METHODS = ("bundle", "models", "polynomial")


def load(doc: dict[str, Any], units: Units, source: str) -> Block:
    """Read a ``block`` document into a :class:`Block` (m, mm, rad)."""
    t = read_frame_tables(doc, source)
    opts = doc.get("options", {})
    block = block_from_tables(
        t, units, source, sequence=doc["sequence"], image_sigma=opts.get("image_sigma")
    )
    im = block.images
    require_finite(t.images, np.column_stack([im.X0, im.angles]),
                   ("X0", "Y0", "Z0", "omega", "phi", "kappa"), "an approximate value")  # fmt: skip
    check_rays(block, t.points)
    block.meta["name"] = doc.get("name", "")
    return block


def check_rays(block: Block, points_table) -> None:
    """Tie and check points need ≥ 2 rays, control points ≥ 1 (InputError at the point)."""
    rays = block.rays_per_point()
    need = np.where(block.points.role == CONTROL, 1, 2)
    bad = np.flatnonzero(rays < need)
    if bad.size:
        i = int(bad[0])
        role = ROLES[block.points.role[i]]
        raise points_table.fail(
            i,
            "id",
            f"{role} point {block.points.ids[i]!r} is observed in {rays[i]} image(s), "
            f"needs at least {need[i]} ray(s)"
            + (f" ({bad.size - 1} more such points)" if bad.size > 1 else ""),
        )


def dump(block: Block, units: Units, columnar: bool) -> dict[str, Any]:
    """The tables of ``block`` in ``units``."""
    return tables_from_block(block, units, columnar)


def _approximate_tie_points(block: Block) -> Block:
    """Intersect tie/check points without approximate coordinates from the approximate orientations."""
    missing = np.flatnonzero(~np.all(np.isfinite(block.points.xyz), axis=1))
    if missing.size == 0:
        return block
    from ...orientation.intersection import intersect_points

    obs = block.observations
    sel = np.isin(obs.point, missing)
    cam = block.images.camera
    res = intersect_points(
        obs.xy[sel], obs.image[sel], obs.point[sel], block.images.X0, block.rotations(),
        block.cameras.c[cam], block.cameras.x0[cam], block.cameras.y0[cam],
        sigma=obs.sigma[sel], n_points=block.n_points, on_degenerate="nan",
    )  # fmt: skip
    block = block.copy()
    block.points.xyz[missing] = res.xyz[missing]
    still = missing[~np.all(np.isfinite(block.points.xyz[missing]), axis=1)]
    if still.size:
        raise InputError(
            f"point {block.points.ids[still[0]]!r}: no approximate coordinates given and its "
            "rays do not intersect (parallel or behind the cameras); give X, Y, Z",
            block.meta.get("source"),
            "points",
        )
    return block


def _call(func, block: Block, options: dict[str, Any], **extra):
    """Call a solver with the options it accepts (max_iter, tol, control, …)."""
    params = inspect.signature(func).parameters
    kw = {k: v for k, v in {**options, **extra}.items() if k in params}
    return func(block, **kw)


def solve(problem: Problem, method: str | None) -> Solution:
    """Adjust the block by ``method`` and collect the report."""
    method = method or "bundle"
    block: Block = _approximate_tie_points(problem.data)
    opts = {k: v for k, v in problem.options.items() if k in ("control", "max_iter", "tol")}
    if method == "bundle":
        from ...block.bundle import bundle_adjust

        adj = _call(bundle_adjust, block, opts)
    else:
        module = f"orientviz.block.{method}"
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name and exc.name.startswith("orientviz"):
                raise InputError(
                    f"--method {method}: not yet available in this version of orientviz "
                    "(use --method bundle)",
                    problem.source,
                ) from None
            raise
        func = getattr(mod, f"{method}_adjust", None) or getattr(mod, "adjust", None)
        if func is None:
            raise InputError(f"--method {method}: not yet available (no solver in {module})")
        adj = _call(func, block, opts)
    return solution_from_block_adjustment(problem, block, adj, method)


def _labels(block: Block, n: int) -> list[str]:
    obs = block.observations
    im, pt = block.images.ids, block.points.ids
    base = [f"{im[i]}/{pt[p]}" for i, p in zip(obs.image, obs.point)]
    labels = [f"{b}/{a}" for b in base for a in "xy"]
    return labels[:n] + [f"pseudo[{k}]" for k in range(max(n - len(labels), 0))]


def solution_from_block_adjustment(problem: Problem, block: Block, adj, method: str) -> Solution:
    """Turn a block adjustment (blocks ``exterior`` (m, 6) and ``points`` (p, 3)) into a report."""
    m, p = block.n_images, block.n_points
    if adj.obs_labels is None or len(adj.obs_labels) != adj.n_observations:
        adj.obs_labels = _labels(block, adj.n_observations)
    std = adj.std()
    ext = adj.x[adj.blocks["exterior"]].reshape(m, 6)
    sext = std[adj.blocks["exterior"]].reshape(m, 6)
    if "points" in adj.blocks:
        xyz = adj.x[adj.blocks["points"]].reshape(p, 3)
        sxyz = std[adj.blocks["points"]].reshape(p, 3)
    else:
        xyz, sxyz = block.points.xyz, np.full((p, 3), np.nan)
    notes = []
    rms = adj.extra.get("check_rms")
    if rms is not None and np.size(rms) == 3 and np.any(block.points.role == CHECK):
        L = 1.0 / problem.units.m_per_length
        r = np.asarray(rms, dtype=float) * L
        notes.append(
            f"check points: r.m.s. error X {r[0]:.4g}, Y {r[1]:.4g}, Z {r[2]:.4g} "
            f"{problem.units.length}"
        )
    ties = int(np.sum(block.points.role == TIE))
    notes.append(f"block: {block.summary()} ({ties} tie points)")
    return Solution(
        kind="block",
        method=method,
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        image_ids=list(block.images.ids),
        X0=ext[:, :3],
        angles=ext[:, 3:],
        X0_sigma=sext[:, :3],
        angles_sigma=sext[:, 3:],
        point_ids=list(block.points.ids),
        xyz=xyz,
        xyz_sigma=sxyz,
        point_roles=[ROLES[r] for r in block.points.role],
        observation_quantity="image",
        critical=float(problem.options.get("critical", 3.29)),
        notes=notes,
    )


KIND = register_kind(
    Kind(
        name="block",
        schema="block.json",
        load=load,
        dump=dump,
        solve=solve,
        description="bundle block: cameras, images, tie/control/check points, image observations",
        methods=METHODS,
    )
)
