"""The example problems shipped with orientviz (``orientviz/datasets/examples``).

>>> from orientviz.io.datasets import list_datasets, load_dataset
>>> "block_strip" in list_datasets()
True

Each dataset is an ``orientviz/1`` problem file in a folder of ``orientviz/datasets``
(``examples/``, ``pair/``, ``geier1973/``, …) whose ``MANIFEST.json`` gives its source,
units, frame and licence (:func:`dataset_info`).
"""

from __future__ import annotations

import json
import os
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import InputError
from .problem import Problem, load_problem

PACKAGE = "orientviz.datasets"
#: Manifest entries must say these (filled from a folder manifest if an entry lacks them).
FIELDS = ("source", "units", "frame", "licence")


def _entries(folder) -> list[dict[str, Any]]:
    """The problem files of one dataset folder, from its ``MANIFEST.json``.

    A manifest ``{"format": "orientviz-datasets/1", "datasets": [...]}`` lists its
    problem files; any other manifest describes the whole folder, and every
    ``orientviz/1`` file in it becomes a dataset named after its file.
    """
    meta = json.loads(folder.joinpath("MANIFEST.json").read_text(encoding="utf-8"))
    if isinstance(meta, dict) and isinstance(meta.get("datasets"), list):
        return [dict(e, folder=folder.name) for e in meta["datasets"]]
    out = []
    for item in sorted(folder.iterdir(), key=lambda r: r.name):
        if not item.name.endswith(".json") or item.name == "MANIFEST.json":
            continue
        try:
            doc = json.loads(item.read_text(encoding="utf-8"))
        except ValueError:
            continue
        if not (isinstance(doc, dict) and doc.get("format") == "orientviz/1"):
            continue
        entry = {k: meta.get(k, "") for k in FIELDS} if isinstance(meta, dict) else {}
        entry.update(
            name=item.name[: -len(".json")], file=item.name, kind=doc.get("kind", ""),
            form="readable", description=doc.get("description", ""), units=doc.get("units"),
            folder=folder.name,
        )  # fmt: skip
        out.append(entry)
    return out


@lru_cache(maxsize=1)
def _manifest() -> dict[str, dict[str, Any]]:
    root = resources.files(PACKAGE)
    found: dict[str, dict[str, Any]] = {}
    for folder in sorted((f for f in root.iterdir() if f.is_dir()), key=lambda r: r.name):
        if not folder.joinpath("MANIFEST.json").is_file():
            continue
        for entry in _entries(folder):
            found.setdefault(entry["name"], entry)  # first folder wins (names are unique)
    return found


def list_datasets() -> list[str]:
    """Names of the shipped example problems, sorted."""
    return sorted(_manifest())


def dataset_info(name: str) -> dict[str, Any]:
    """The manifest entry of ``name``: folder, file, kind, form, description, source, units,
    frame, licence (and what else the manifest says, e.g. ``truth``)."""
    try:
        return dict(_manifest()[name])
    except KeyError:
        raise InputError(
            f"unknown dataset {name!r} (available: {', '.join(list_datasets())})"
        ) from None


def dataset_path(name: str) -> Path:
    """Path of the problem file of dataset ``name`` (inside the installed package)."""
    info = dataset_info(name)
    return Path(str(resources.files(PACKAGE).joinpath(info["folder"], info["file"])))


def load_dataset(name: str) -> Problem:
    """Load dataset ``name`` as a :class:`~orientviz.io.problem.Problem`."""
    return load_problem(dataset_path(name))


def resolve_name(name: str) -> str:
    """A path as given, or the file of a shipped dataset if no such path exists.

    Raises
    ------
    InputError
        When ``name`` is no file, no shipped dataset and does not look like a path
        (no separator, no ``.json``): the message lists the shipped datasets.
    """
    if os.path.exists(name):
        return name
    if name in list_datasets():
        return str(dataset_path(name))
    if os.sep not in name and not name.endswith(".json"):
        raise InputError(
            f"no such file, and no shipped example of that name ({', '.join(list_datasets())})",
            name,
        )
    return name
