"""Versioned JSON problem files (``"format": "orientviz/1"``): load, write, round-trip.

A problem file is one JSON object::

    {
      "format": "orientviz/1",
      "kind": "block",                        # see orientviz.io.registry.available_kinds()
      "name": "demo block",                   # optional
      "description": "...",                   # optional
      "units": {"length": "m", "image": "mm", "angle": "gon"},
      "sequence": "opk",                      # rotation sequence of every angle in the file
      "options": {...},                       # optional, kind-specific solver options
      ... kind-specific tables ...
    }

Units are explicit and converted at load: object lengths ``"m"``/``"mm"``, image
coordinates ``"mm"``/``"um"``, angles ``"rad"``/``"deg"``/``"gon"``/``"c"``/``"cc"``.
Inside orientviz everything is m, mm and rad; the writer converts back to the units
stored in :attr:`Problem.units`. Every σ is in the unit of the value it belongs to.

Tables can be written in a readable per-row form or a compact columnar form
(:mod:`orientviz.io.tables`). Every failure is an :class:`~orientviz.errors.InputError`
whose one line names the file, the place and the problem.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..rotation import check_sequence
from ..units import MODEL_UNIT, RHO, length_name
from .columns import shared_columns
from .jsonio import _json_type, dumps_json, parse_json, read_json_file, validate, write_atomic
from .reduce import reduce_document
from .registry import get_kind

#: The format string this version reads and writes.
FORMAT = "orientviz/1"
#: Object-space length units → metres per unit.
LENGTH_UNITS: dict[str, float] = {
    "m": 1.0, "mm": 1e-3, "ft": 0.3048, "us-ft": 1200.0 / 3937.0, MODEL_UNIT: 1.0,
}  # fmt: skip
#: Image-coordinate units → millimetres per unit.
IMAGE_UNITS: dict[str, float] = {"mm": 1.0, "um": 1e-3}
#: Kinds that read image coordinates in pixels (``units.image = "px"``).
PIXEL_KINDS = ("block", "resection", "intersection")
#: Top-level keys handled by the envelope (all others belong to the kind).
ENVELOPE_KEYS = ("format", "kind", "name", "description", "units", "sequence", "options")


@dataclass(frozen=True)
class Units:
    """The units a problem file is written in.

    Attributes
    ----------
    length : {"m", "mm", "ft", "us-ft", "model"}
        Object-space coordinates and their σ (``ft``: the international foot, 0.3048 m;
        ``us-ft``: the US survey foot, 1200/3937 m; ``model``: the arbitrary scale of a
        reconstruction without control, read 1 : 1 inside and named "model units" in
        reports, :data:`orientviz.units.MODEL_UNIT`).
    angle : {"rad", "deg", "gon", "c", "cc"}
        Orientation angles and their σ. A file may say ``"dms"``: its angles are then
        strings of degrees, minutes and seconds (``"-1°02'03.5\""``, ``"-1 02 03.5"``)
        or numbers of decimal degrees, read as ``"deg"`` (:func:`dms_document`).
    image : {"mm", "um", "px"}
        Image coordinates and their σ (kinds with images), and the cameras' c, principal
        point and format. ``"px"``: pixels of the pixel frame (origin at the upper-left
        corner, x right, y *down*, as OpenCV and COLMAP), read as x·p, −y·p mm in the
        photogrammetric image frame (y up); kinds block, resection and intersection.
    pixel_size : float or None
        p, mm per pixel (with ``image="px"``).
    """

    length: str = "m"
    angle: str = "gon"
    image: str = "mm"
    pixel_size: float | None = None

    @property
    def length_name(self) -> str:
        """The length unit as texts name it ("model units" for ``"model"``)."""
        return length_name(self.length)

    @property
    def m_per_length(self) -> float:
        """Metres per file length unit (multiply file values by this at load)."""
        return LENGTH_UNITS[self.length]

    @property
    def rad_per_angle(self) -> float:
        """Radians per file angle unit."""
        return 1.0 / RHO[self.angle]

    @property
    def mm_per_image(self) -> float:
        """Millimetres per file image unit."""
        if self.image == "px":
            return float(self.pixel_size)
        return IMAGE_UNITS[self.image]

    @property
    def y_sign(self) -> float:
        """−1 where the file's image y points down (pixels), else 1."""
        return -1.0 if self.image == "px" else 1.0

    def as_dict(self) -> dict[str, str | float]:
        out: dict[str, str | float] = {
            "length": self.length,
            "image": self.image,
            "angle": self.angle,
        }
        if self.image == "px":
            out["pixel_size"] = float(self.pixel_size)
        return out


@dataclass
class Problem:
    """A loaded problem: the kind's data in internal units plus what the file said.

    Attributes
    ----------
    kind : str
        ``"block"``, ``"resection"``, ``"intersection"``, ``"similarity"``, …
    data : object
        The kind's data (a :class:`~orientviz.block.Block` for the frame kinds, a
        :class:`~orientviz.io.kinds.similarity.SimilarityData` for similarity), in m,
        mm and rad.
    units : Units
        Units of the file; results are reported and files written in them.
    sequence : {"opk", "pok"}
        Rotation sequence of all angles.
    name, description : str
        Free text from the file.
    options : dict
        Kind-specific solver options as written in the file.
    source : str or None
        The file it came from.
    columnar : bool
        Whether the file used the compact form (the writer keeps it by default).
    """

    kind: str
    data: Any
    units: Units = field(default_factory=Units)
    sequence: str = "opk"
    name: str = ""
    description: str = ""
    options: dict[str, Any] = field(default_factory=dict)
    source: str | None = None
    columnar: bool = False


def _has_columns(node: Any) -> bool:
    """True if ``node`` is or contains a table in the columnar form (object of arrays)."""
    if not isinstance(node, dict) or not node:
        return False
    if all(isinstance(v, list) and not any(isinstance(e, dict) for e in v) for v in node.values()):
        return True
    return any(_has_columns(v) for v in node.values())


def problem_from_document(doc: Any, source: str = "<document>") -> Problem:
    """Validate a parsed document and build the :class:`Problem`.

    Parameters
    ----------
    doc : object
        The parsed JSON (see :func:`~orientviz.io.jsonio.parse_json`).
    source : str
        Name of the file, for messages.
    """
    if not isinstance(doc, dict):
        raise InputError(
            f'expected a JSON object with "format": "{FORMAT}", got {_json_type(doc)}',
            source,
            "document",
        )
    fmt = doc.get("format")
    if fmt is None:
        raise InputError(f"missing field 'format' (expected {FORMAT!r})", source, "document")
    if fmt != FORMAT:
        raise InputError(
            f"unsupported format {fmt!r}: this version of orientviz reads {FORMAT!r}",
            source,
            "format",
        )
    doc = dms_document(doc, source)
    reduced = reduce_document(doc)  # once for both schemas
    validate(doc, "envelope.json", source, reduced)
    kind = get_kind(doc["kind"], source)
    validate(doc, kind.schema, source, reduced)
    u = doc["units"]
    units = Units(length=u["length"], angle=u["angle"], image=u.get("image", "mm"),
                  pixel_size=u.get("pixel_size"))  # fmt: skip
    if units.image == "px" and units.pixel_size is None:
        raise InputError('image "px" needs the pixel size in mm (e.g. "pixel_size": 0.0032)',
                         source, "units.pixel_size")  # fmt: skip
    if units.image != "px" and units.pixel_size is not None:
        raise InputError(f'pixel_size applies to image "px" only (image is {units.image!r})',
                         source, "units.pixel_size")  # fmt: skip
    if units.image == "px" and doc["kind"] not in PIXEL_KINDS:
        raise InputError(f'image "px" is read by the kinds {", ".join(PIXEL_KINDS)}; give mm or um',
                         source, "units.image")  # fmt: skip
    sequence = check_sequence(doc.get("sequence", "opk"))
    data = kind.load(doc, units, source)
    columnar = any(_has_columns(v) for k, v in doc.items() if k not in ENVELOPE_KEYS)
    if hasattr(data, "sequence") and data.sequence != sequence:
        data.sequence = sequence
    return Problem(
        kind=kind.name,
        data=data,
        units=units,
        sequence=sequence,
        name=str(doc.get("name", "")),
        description=str(doc.get("description", "")),
        options=dict(doc.get("options", {})),
        source=source,
        columnar=columnar,
    )


#: Keys whose values are orientation angles (any kind, readable or columnar tables).
ANGLE_KEYS = frozenset({"omega", "phi", "kappa", "phi1", "kappa1", "phi2", "omega2", "kappa2"})

_DMS = re.compile(
    r"""\s*([+-])?\s*(\d+(?:\.\d*)?)\s*(?:°|d|deg|\s)\s*"""
    r"""(?:(\d+(?:\.\d*)?)\s*(?:'|′|m|min|\s)?\s*)?"""
    r"""(?:(\d+(?:\.\d*)?)\s*(?:"|″|''|s|sec)?\s*)?"""
)


def parse_dms(text: str) -> float:
    """Decimal degrees of an angle written in degrees, minutes and seconds.

    Parameters
    ----------
    text : str
        ``"12°34'56.7\""``, ``"-0°05'00\""``, ``"12 34 56.7"``, ``"12d34m56.7s"``: the
        sign applies to the whole angle; minutes and seconds are below 60.

    Raises
    ------
    ValueError
        If ``text`` is not such an angle.
    """
    m = _DMS.fullmatch(text)
    if m is None or m.group(2) is None:
        raise ValueError(f"expected degrees-minutes-seconds such as \"12°34'56.7\\\"\" or "
                         f"\"12 34 56.7\", got {text!r}")  # fmt: skip
    d, mi, se = (float(g) if g else 0.0 for g in m.group(2, 3, 4))
    if mi >= 60 or se >= 60:
        raise ValueError(f"minutes and seconds must be below 60, got {text!r}")
    value = d + mi / 60.0 + se / 3600.0
    return -value if m.group(1) == "-" else value


def dms_document(doc: Any, source: str) -> Any:
    """A document with ``units.angle = "dms"`` turned into one in decimal degrees.

    Every string under an angle key (:data:`ANGLE_KEYS`: rows, columns, approximations)
    is read by :func:`parse_dms`; numbers are taken as decimal degrees. Other documents
    are returned unchanged.
    """
    if not (isinstance(doc, dict) and isinstance(doc.get("units"), dict)):
        return doc
    if doc["units"].get("angle") != "dms":
        return doc

    def convert(node: Any, path: str) -> Any:
        if isinstance(node, dict):
            out = {}
            for k, v in node.items():
                here = f"{path}.{k}" if path else str(k)
                if k in ANGLE_KEYS and isinstance(v, str):
                    out[k] = _dms(v, here)
                elif k in ANGLE_KEYS and isinstance(v, list):
                    out[k] = [_dms(x, f"{here}[{i}]") if isinstance(x, str) else x
                              for i, x in enumerate(v)]  # fmt: skip
                else:
                    out[k] = convert(v, here)
            return out
        if isinstance(node, list):
            return [convert(v, f"{path}[{i}]") for i, v in enumerate(node)]
        return node

    def _dms(text: str, place: str) -> float:
        try:
            return parse_dms(text)
        except ValueError as exc:
            raise InputError(str(exc), source, place) from None

    out = convert(doc, "")
    out["units"] = {**doc["units"], "angle": "deg"}
    return out


def loads_problem(text: str, source: str = "<string>") -> Problem:
    """Parse and load a problem from JSON text (see :func:`load_problem`)."""
    try:
        with shared_columns():
            return problem_from_document(parse_json(text, source), source)
    except RecursionError:
        raise InputError("nested too deeply for a problem file", source) from None


def load_problem(path: str | os.PathLike[str]) -> Problem:
    """Load a problem file.

    Parameters
    ----------
    path : str or path-like
        An ``orientviz/1`` JSON file.

    Returns
    -------
    Problem
        Data in internal units (m, mm, rad); ``units`` remembers the file's units.

    Raises
    ------
    InputError
        For every defect of the file; the message names the file, the place (a path such
        as ``observations[12].x``, or line and column of malformed JSON) and the problem.
    """
    try:
        with shared_columns():
            return problem_from_document(read_json_file(path), str(path))
    except RecursionError:
        raise InputError("nested too deeply for a problem file", str(path)) from None


def problem_to_document(problem: Problem, *, columnar: bool | None = None) -> dict[str, Any]:
    """The JSON document of a problem, in ``problem.units``.

    Parameters
    ----------
    problem : Problem
    columnar : bool, optional
        Compact columnar tables (True) or one object per row (False); default: the form
        the problem was read in.
    """
    kind = get_kind(problem.kind)
    col = problem.columnar if columnar is None else bool(columnar)
    doc: dict[str, Any] = {"format": FORMAT, "kind": kind.name}
    if problem.name:
        doc["name"] = problem.name
    if problem.description:
        doc["description"] = problem.description
    doc["units"] = problem.units.as_dict()
    doc["sequence"] = check_sequence(problem.sequence)
    if problem.options:
        doc["options"] = dict(problem.options)
    doc.update(kind.dump(problem.data, problem.units, col))
    return doc


def dumps_problem(problem: Problem, *, columnar: bool | None = None, indent: int | None = 1) -> str:
    """The problem as JSON text (validated against its schema before it is returned)."""
    with shared_columns():
        doc = problem_to_document(problem, columnar=columnar)
        validate(doc, get_kind(problem.kind).schema, "<written document>")
        return dumps_json(doc, indent=indent)


def save_problem(
    problem: Problem,
    path: str | os.PathLike[str],
    *,
    columnar: bool | None = None,
    indent: int | None = 1,
) -> Path:
    """Write a problem file atomically (temporary file + rename); return the path."""
    text = dumps_problem(problem, columnar=columnar, indent=indent)
    write_atomic(path, text)
    return Path(path)


def problem_from_block(
    block: Any,
    *,
    kind: str = "block",
    units: Units | None = None,
    name: str = "",
    description: str = "",
    options: dict[str, Any] | None = None,
    columnar: bool | None = None,
) -> Problem:
    """Wrap a :class:`~orientviz.block.Block` as a problem (default units m, mm, gon).

    ``columnar`` defaults to the compact form for blocks with more than 1000 observations.
    """
    if columnar is None:
        columnar = getattr(block, "n_observations", 0) > 1000
    return Problem(
        kind=kind,
        data=block,
        units=units or Units(),
        sequence=getattr(block, "sequence", "opk"),
        name=name or str(getattr(block, "meta", {}).get("name", "")),
        description=description,
        options=dict(options or {}),
        columnar=bool(columnar),
    )


def write_problem(
    problem: Problem | dict[str, Any],
    path: str | os.PathLike[str],
    *,
    columnar: bool | None = None,
    units: Units | None = None,
) -> Path:
    """Write a problem file atomically; accepts a :class:`Problem` or a plain dict.

    Parameters
    ----------
    problem : Problem or dict
        A :class:`Problem`, or ``{"kind": "block", "block": Block, "units": Units,
        "name": ..., "options": {...}}`` (what importers produce).
    path : str or path-like
        Target file; written through a temporary file and renamed.
    columnar : bool, optional
        Force the compact or the readable form.
    units : Units, optional
        Units to write in (overrides the problem's).
    """
    if isinstance(problem, dict):
        data = problem.get("block", problem.get("data"))
        if data is None:
            raise InputError("write_problem: expected a 'block' (or 'data') entry")
        problem = problem_from_block(
            data,
            kind=problem.get("kind", "block"),
            units=problem.get("units"),
            name=problem.get("name", ""),
            description=problem.get("description", ""),
            options=problem.get("options"),
        )
    if units is not None:
        problem = Problem(**{**problem.__dict__, "units": units})
    return save_problem(problem, path, columnar=columnar)
