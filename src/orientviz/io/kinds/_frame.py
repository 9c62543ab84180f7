"""Tables shared by the frame-camera kinds (``block``, ``resection``, ``intersection``).

The four tables ``cameras``, ``images``, ``points`` and ``observations`` (schema
``frame.json``) are read into a :class:`~orientviz.block.Block` in internal units
(object space m, image mm, angles rad) and written back in the file's units.

Fields (file units in brackets; see ``orientviz/io/schema/frame.json``):

* cameras: ``id``, ``c`` [image], ``x0``, ``y0`` [image, default 0], ``format`` [image,
  default 230 × 230 mm].
* images: ``id``, ``camera`` (a camera id), ``X0``, ``Y0``, ``Z0`` [length], ``omega``,
  ``phi``, ``kappa`` [angle, in the file's ``sequence``], ``strip``, and optional
  observed ``X0_obs`` [length] / ``angles_obs`` [angle] with ``*_sigma``.
* points: ``id``, ``role`` (tie/control/check), ``X``, ``Y``, ``Z`` [length; null = not
  known], ``sigma`` [length; 0 = fixed].
* observations: ``image``, ``point`` (ids), ``x``, ``y``, ``sigma`` [image; default
  ``options.image_sigma``].
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...block import CONTROL, ROLES, Block, Cameras, Images, Observations, Points
from ...errors import InputError
from ..problem import Units
from ..tables import REQUIRED, Table, json_numbers, read_table, write_table
from ._cameras import MODEL_FIELDS, camera_model_cells, read_camera_models

CAMERA_FIELDS = {
    "id": REQUIRED,
    "c": REQUIRED,
    "x0": 0.0,
    "y0": 0.0,
    "format": None,
    **MODEL_FIELDS,
}
IMAGE_FIELDS = {
    "id": REQUIRED,
    "camera": REQUIRED,
    "X0": None,
    "Y0": None,
    "Z0": None,
    "omega": None,
    "phi": None,
    "kappa": None,
    "strip": None,
    "X0_obs": None,
    "X0_obs_sigma": None,
    "angles_obs": None,
    "angles_obs_sigma": None,
}
POINT_FIELDS = {"id": REQUIRED, "role": None, "X": None, "Y": None, "Z": None, "sigma": None}
OBS_FIELDS = {"image": REQUIRED, "point": REQUIRED, "x": REQUIRED, "y": REQUIRED, "sigma": None}


class FrameTables:
    """The four tables of a frame problem, kept for messages that name a place."""

    def __init__(self, cameras: Table, images: Table, points: Table, observations: Table):
        self.cameras = cameras
        self.images = images
        self.points = points
        self.observations = observations


def read_frame_tables(doc: dict[str, Any], source: str) -> FrameTables:
    """Normalise the four tables of a schema-validated document."""
    return FrameTables(
        read_table(doc, "cameras", CAMERA_FIELDS, source),
        read_table(doc, "images", IMAGE_FIELDS, source),
        read_table(doc, "points", POINT_FIELDS, source),
        read_table(doc, "observations", OBS_FIELDS, source),
    )


def block_from_tables(
    t: FrameTables,
    units: Units,
    source: str,
    *,
    sequence: str,
    default_role: str = "tie",
    image_sigma: float | None = None,
    camera_models: bool = False,
) -> Block:
    """Build a :class:`Block` (internal units) from the tables; ids are checked here.

    Unknown values (a missing approximation, a coordinate that is not given) are NaN.

    Parameters
    ----------
    t : FrameTables
    units : Units
        Units of the file.
    source : str
        The file, for messages.
    sequence : {"opk", "pok"}
        Rotation sequence of the angles.
    default_role : {"tie", "control", "check"}
        Role of points that do not state one.
    image_sigma : float, optional
        ``options.image_sigma`` in file image units, used where an observation gives none.
    camera_models : bool
        The kind estimates camera models (``model``/``additional`` in ``cameras[]``,
        :mod:`orientviz.io.kinds._cameras`); otherwise such fields are refused.
    """
    L, A, I = units.m_per_length, units.rad_per_angle, units.mm_per_image
    Y = I * units.y_sign  # image y: pixels count downwards
    cam_idx = t.cameras.index("id", "camera")
    img_idx = t.images.index("id", "image")
    pt_idx = t.points.index("id", "point")

    fmt = np.array(
        [(230.0, 230.0) if f is None else (f[0] * I, f[1] * I) for f in t.cameras.columns["format"]]
    ).reshape(-1, 2)
    cameras = Cameras(
        ids=t.cameras.strings("id"),
        c=t.cameras.floats("c", I),
        x0=t.cameras.floats("x0", I),
        y0=t.cameras.floats("y0", Y),
        format_mm=fmt,
        ap_set=[""] * t.cameras.n,
        model=read_camera_models(t.cameras, units),
    )
    if not camera_models:
        for i, spec in enumerate(cameras.model):
            if spec:
                field = "model" if "model" in spec else "additional"
                raise t.cameras.fail(i, field, "camera models are estimated by kind block only")
    im = t.images
    strip = im.ints("strip")
    images = Images(
        ids=im.strings("id"),
        camera=im.lookup("camera", cam_idx, "camera"),
        X0=np.column_stack([im.floats("X0", L), im.floats("Y0", L), im.floats("Z0", L)]),
        angles=np.column_stack(
            [im.floats("omega", A), im.floats("phi", A), im.floats("kappa", A)]
        ).reshape(-1, 3),
        strip=strip,
        X0_obs=im.vectors("X0_obs", 3, L),
        X0_sigma=im.vectors("X0_obs_sigma", 3, L),
        angles_obs=im.vectors("angles_obs", 3, A),
        angles_sigma=im.vectors("angles_obs_sigma", 3, A),
    )
    images.X0 = images.X0.reshape(-1, 3)
    for name, obs, sig in (
        ("X0_obs", images.X0_obs, images.X0_sigma),
        ("angles_obs", images.angles_obs, images.angles_sigma),
    ):
        bad = np.flatnonzero(np.any(np.isfinite(obs) & ~(sig > 0), axis=1))
        if bad.size:
            raise im.fail(int(bad[0]), f"{name}_sigma", f"an observed {name} needs a σ > 0")

    pt = t.points
    role = np.array(
        [ROLES.index(default_role if r is None else r) for r in pt.columns["role"]], dtype=np.int8
    )
    xyz = np.column_stack([pt.floats("X", L), pt.floats("Y", L), pt.floats("Z", L)]).reshape(-1, 3)
    known = np.where((role > 0)[:, None], xyz, np.nan)
    sig = pt.vectors("sigma", 3, L)
    sig = np.where(np.isnan(sig), 0.0, sig)
    sig = np.where(np.isnan(known) & (role > 0)[:, None], np.nan, sig)
    for i in np.flatnonzero((role > 0) & np.all(np.isnan(known), axis=1)):
        raise pt.fail(
            int(i), "X", f"{ROLES[role[i]]} point {pt.columns['id'][i]!r} has no coordinates"
        )
    points = Points(ids=pt.strings("id"), xyz=xyz, role=role, xyz_known=known, sigma=sig)

    ob = t.observations
    oi = ob.lookup("image", img_idx, "image")
    op = ob.lookup("point", pt_idx, "point")
    pair = oi * max(len(pt_idx), 1) + op
    order = np.argsort(pair, kind="stable")
    dup = np.flatnonzero(np.diff(pair[order]) == 0)
    if dup.size:
        i, j = sorted((int(order[dup[0]]), int(order[dup[0] + 1])))
        raise ob.fail(
            j,
            None,
            f"point {ob.columns['point'][j]!r} is observed twice in image "
            f"{ob.columns['image'][j]!r} (also at {ob.where(i)})",
        )
    osig = ob.vectors("sigma", 2, I)
    missing = np.flatnonzero(np.any(np.isnan(osig), axis=1))
    if missing.size:
        if image_sigma is None:
            raise ob.fail(
                int(missing[0]), "sigma", "no σ: give sigma per observation or options.image_sigma"
            )
        osig[missing] = np.where(np.isnan(osig[missing]), image_sigma * I, osig[missing])
    zero = np.flatnonzero(np.any(osig <= 0, axis=1))
    if zero.size:
        raise ob.fail(int(zero[0]), "sigma", "expected σ > 0 for an image coordinate")
    observations = Observations(
        image=oi,
        point=op,
        xy=np.column_stack([ob.floats("x", I), ob.floats("y", Y)]).reshape(-1, 2),
        sigma=osig,
    )
    block = Block(cameras, images, points, observations, sequence=sequence)
    block.meta.update({"source": source, "units": units.as_dict()})
    try:
        block.validate()
    except ValueError as exc:  # ids/shapes were checked above; this is a safety net
        raise InputError(str(exc), source) from None
    return block


def require_finite(table: Table, values: np.ndarray, fields: tuple[str, ...], what: str) -> None:
    """Fail at the first row where one of ``fields`` (columns of ``values``) is unknown."""
    bad = np.argwhere(~np.isfinite(values.reshape(values.shape[0], -1)))
    if bad.size:
        row, col = int(bad[0][0]), int(bad[0][1])
        raise table.fail(row, fields[col], f"{what} is required here")


def _ids_at(ids: list[str], index: np.ndarray) -> list[str]:
    """``[ids[i] for i in index]`` (the same objects), gathered in C."""
    table = np.empty(len(ids), dtype=object)
    table[:] = ids
    return table[index].tolist()


def _pairs(values: list) -> list[list]:
    """``values`` in consecutive pairs."""
    return [values[i : i + 2] for i in range(0, len(values), 2)]


def _vec_cells(obs: np.ndarray, sig: np.ndarray, scale: float) -> tuple[list, list]:
    """Cells of a vector per row (None where every entry is NaN) and of its σ."""
    vals: list[Any] = [None] * len(obs)
    sigs: list[Any] = [None] * len(obs)
    for i in np.flatnonzero(~np.all(np.isnan(obs), axis=1)).tolist():
        vals[i] = json_numbers(obs[i] / scale)
        sigs[i] = json_numbers(sig[i] / scale)
    return vals, sigs


def tables_from_block(block: Block, units: Units, columnar: bool) -> dict[str, Any]:
    """The four tables of ``block`` as JSON nodes in ``units`` (inverse of the reader)."""
    L, A, I = units.m_per_length, units.rad_per_angle, units.mm_per_image
    Y = I * units.y_sign
    cam, im, pt, ob = block.cameras, block.images, block.points, block.observations
    cameras = {
        "id": list(cam.ids),
        "c": json_numbers(cam.c / I),
        "x0": json_numbers(cam.x0 / I),
        "y0": json_numbers(cam.y0 / Y),
        "format": _pairs(json_numbers(np.ravel(cam.format_mm / I))),
    }
    if any(cam.model):
        cameras.update(camera_model_cells(cam.model, units))
    x0obs, x0sig = _vec_cells(im.X0_obs, im.X0_sigma, L)
    aobs, asig = _vec_cells(im.angles_obs, im.angles_sigma, A)
    images = {
        "id": list(im.ids),
        "camera": [cam.ids[c] for c in im.camera],
        "X0": json_numbers(im.X0[:, 0] / L),
        "Y0": json_numbers(im.X0[:, 1] / L),
        "Z0": json_numbers(im.X0[:, 2] / L),
        "omega": json_numbers(im.angles[:, 0] / A),
        "phi": json_numbers(im.angles[:, 1] / A),
        "kappa": json_numbers(im.angles[:, 2] / A),
        "strip": [None if s < 0 else int(s) for s in im.strip],
        "X0_obs": x0obs,
        "X0_obs_sigma": x0sig,
        "angles_obs": aobs,
        "angles_obs_sigma": asig,
    }
    xyz = np.where((pt.role > 0)[:, None], pt.xyz_known, pt.xyz)
    # σ of tie (unknown) and check (not used) points has no meaning
    sig_cells: list[Any] = [None] * len(pt.role)
    for i in np.flatnonzero(pt.role == CONTROL).tolist():
        vals = json_numbers(pt.sigma[i] / L)
        sig_cells[i] = vals[0] if len(set(vals)) == 1 else vals
    points = {
        "id": list(pt.ids),
        "role": [ROLES[r] for r in pt.role.tolist()],
        "X": json_numbers(xyz[:, 0] / L),
        "Y": json_numbers(xyz[:, 1] / L),
        "Z": json_numbers(xyz[:, 2] / L),
        "sigma": sig_cells,
    }
    sv = json_numbers(np.asarray(ob.sigma, float).reshape(-1, 2) / I)  # (σx, σy) per row
    sx, sy = sv[0::2], sv[1::2]
    osig = sx if sx == sy else [a if a == b else [a, b] for a, b in zip(sx, sy)]
    observations = {
        "image": _ids_at(im.ids, ob.image),
        "point": _ids_at(pt.ids, ob.point),
        "x": json_numbers(ob.xy[:, 0] / I),
        "y": json_numbers(ob.xy[:, 1] / Y),
        "sigma": osig,
    }
    return {
        "cameras": write_table(cameras, columnar),
        "images": write_table(images, columnar),
        "points": write_table(points, columnar),
        "observations": write_table(observations, columnar),
    }
