"""Kind ``resection``: the exterior orientation of one image from control points.

Tables as in a block (``schema/resection.json``): one camera, exactly one image (its
X0, Y0, Z0, ω, φ, κ are optional approximate values: all six or none — without them
the closed-form three-point solution starts the iteration), points with known X, Y, Z
(role ``control`` by default; ``check`` points are left out of the adjustment) and
their image observations.

Options: ``interior`` (e.g. ``["c"]`` or ``["x0", "y0", "c"]``: estimate these too),
``max_iter``, ``critical``, ``image_sigma``. Solver:
:func:`orientviz.orientation.resection.resection`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...block import CONTROL, TIE, Block
from ...camera import FrameCamera
from ...errors import InputError
from ...orientation import resection as module
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ..solution import Parameter, Solution
from ._checks import reject_first
from ._frame import block_from_tables, read_frame_tables, tables_from_block


def load(doc: dict[str, Any], units: Units, source: str) -> Block:
    """Read a ``resection`` document into a one-image :class:`Block` (m, mm, rad)."""
    t = read_frame_tables(doc, source)
    if t.images.n != 1:
        raise InputError(f"a resection has exactly one image, got {t.images.n}", source, "images")
    opts = doc.get("options", {})
    block = block_from_tables(
        t, units, source, sequence=doc["sequence"], default_role="control",
        image_sigma=opts.get("image_sigma"),
    )  # fmt: skip
    given = np.isfinite(np.concatenate([block.images.X0[0], block.images.angles[0]]))
    fields = ("X0", "Y0", "Z0", "omega", "phi", "kappa")
    if given.any() and not given.all():
        missing = fields[int(np.flatnonzero(~given)[0])]
        raise t.images.fail(0, missing, "give all six approximate values or none")
    pts = block.points
    used = pts.role[block.observations.point] == CONTROL
    partial = np.flatnonzero((pts.role == CONTROL) & ~np.all(np.isfinite(pts.xyz_known), axis=1))
    observed = np.unique(block.observations.point[used])
    reject_first(
        t.points, partial[np.isin(partial, observed)], "X",
        lambda i: f"control point {pts.ids[i]!r} needs X, Y and Z for a resection",
    )  # fmt: skip
    reject_first(
        t.observations, pts.role[block.observations.point] == TIE, "point",
        lambda k: f"point {pts.ids[block.observations.point[k]]!r} is a tie point; a "
        "resection uses control points (give its X, Y, Z and role \"control\")",
    )  # fmt: skip
    block.meta["name"] = doc.get("name", "")
    return block


def solve(problem: Problem, method: str | None) -> Solution:
    """Space resection of the single image (collinearity least squares)."""
    func = getattr(module, "space_resection", None) or module.resection
    block: Block = problem.data
    obs, pts = block.observations, block.points
    use = pts.role[obs.point] == CONTROL
    cam_i = int(block.images.camera[0])
    cams = block.cameras
    camera = FrameCamera(
        c=float(cams.c[cam_i]), x0=float(cams.x0[cam_i]), y0=float(cams.y0[cam_i]),
        format_mm=tuple(cams.format_mm[cam_i]), name=cams.ids[cam_i],
    )  # fmt: skip
    start = None
    if np.all(np.isfinite(block.images.X0[0])):
        start = (block.images.X0[0], block.images.angles[0])
    interior = tuple(problem.options.get("interior", ()))
    ids = [pts.ids[i] for i in obs.point[use]]
    adj = func(
        obs.xy[use], pts.xyz_known[obs.point[use]], camera, sigma=obs.sigma[use],
        sequence=block.sequence, interior=interior or False, start=start, point_ids=ids,
        max_iter=int(problem.options.get("max_iter", 30)),
    )  # fmt: skip
    std = adj.std()
    params = []
    for name in ("x0", "y0", "c"):
        if name in adj.names:
            k = adj.index(name)
            params.append(Parameter(name, float(adj.x[k]), float(std[k]), "image"))
    ctrl = np.flatnonzero(pts.role == CONTROL)
    return Solution(
        kind="resection",
        method="resection",
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        image_ids=[block.images.ids[0]],
        X0=adj.x[None, :3],
        angles=adj.x[None, 3:6],
        X0_sigma=std[None, :3],
        angles_sigma=std[None, 3:6],
        point_ids=[pts.ids[i] for i in ctrl],
        xyz=pts.xyz_known[ctrl],
        xyz_sigma=np.zeros((ctrl.size, 3)),
        point_roles=["control"] * int(ctrl.size),
        parameters=params,
        observation_quantity="image",
        critical=float(problem.options.get("critical", 3.29)),
        notes=["control points are errorless in a resection (σ = 0)"],
    )


KIND = register_kind(
    Kind(
        name="resection",
        schema="resection.json",
        load=load,
        dump=tables_from_block,
        solve=solve,
        description="space resection: one image oriented from control points",
        methods=("resection",),
    )
)
