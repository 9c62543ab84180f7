"""The example problems shipped with orientviz (``orientviz/datasets/examples``).

>>> from orientviz.io.datasets import list_datasets, load_dataset
>>> "block_strip" in list_datasets()
True

Each dataset is an ``orientviz/1`` problem file listed in ``MANIFEST.json`` with its
source, units, frame and licence (:func:`dataset_info`).
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import InputError
from .problem import Problem, load_problem

PACKAGE = "orientviz.datasets"
FOLDER = "examples"


def _folder():
    return resources.files(PACKAGE).joinpath(FOLDER)


@lru_cache(maxsize=1)
def _manifest() -> dict[str, dict[str, Any]]:
    text = _folder().joinpath("MANIFEST.json").read_text(encoding="utf-8")
    return {d["name"]: d for d in json.loads(text)["datasets"]}


def list_datasets() -> list[str]:
    """Names of the shipped example problems, sorted."""
    return sorted(_manifest())


def dataset_info(name: str) -> dict[str, Any]:
    """The manifest entry of ``name``: file, kind, form, description, source, units, frame, licence."""
    try:
        return dict(_manifest()[name])
    except KeyError:
        raise InputError(
            f"unknown dataset {name!r} (available: {', '.join(list_datasets())})"
        ) from None


def dataset_path(name: str) -> Path:
    """Path of the problem file of dataset ``name`` (inside the installed package)."""
    info = dataset_info(name)
    return Path(str(_folder().joinpath(info["file"])))


def load_dataset(name: str) -> Problem:
    """Load dataset ``name`` as a :class:`~orientviz.io.problem.Problem`."""
    return load_problem(dataset_path(name))
