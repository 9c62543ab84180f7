"""Shipped example problems: manifest, package data, loader, reproducible generator."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.datasets import dataset_info, dataset_path, list_datasets
from orientviz.io.problem import dumps_problem

tomllib = pytest.importorskip("tomllib")  # Python ≥ 3.11
ROOT = Path(__file__).resolve().parents[2]
EXPECTED = {
    "similarity_example": "similarity",
    "resection_example": "resection",
    "intersection_example": "intersection",
    "block_strip": "block",
    "block_compact": "block",
}


def test_manifest_lists_every_example_with_source_units_frame_licence():
    assert set(EXPECTED) <= set(list_datasets())
    for name, kind in EXPECTED.items():
        assert dataset_info(name)["kind"] == kind
    for name in list_datasets():  # the other folders' datasets (pair, radar, …) too
        info = dataset_info(name)
        for key in ("source", "units", "frame", "licence", "description", "form", "kind"):
            assert info[key], f"{name}: empty {key}"
        assert ov.load_dataset(name).kind == info["kind"]


def test_one_compact_and_several_readable_blocks():
    forms = {n: dataset_info(n)["form"] for n in EXPECTED}
    assert forms["block_compact"] == "columnar" and forms["block_strip"] == "readable"
    assert ov.load_dataset("block_compact").columnar and not ov.load_dataset("block_strip").columnar


def test_files_are_found_through_importlib_resources():
    folder = resources.files("orientviz.datasets").joinpath("examples")
    assert folder.joinpath("MANIFEST.json").is_file()
    for name in EXPECTED:
        res = folder.joinpath(f"{name}.json")
        assert res.is_file()
        assert json.loads(res.read_text(encoding="utf-8"))["format"] == "orientviz/1"
        assert Path(str(res)) == dataset_path(name)
    schemas = resources.files("orientviz.io").joinpath("schema")
    for kind in set(EXPECTED.values()) | {"envelope", "common", "frame"}:
        assert schemas.joinpath(f"{kind}.json").is_file()


def test_package_data_patterns_cover_the_files():
    """pyproject's package-data globs match every data file, so wheels carry them."""
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = conf["tool"]["setuptools"]["package-data"]["orientviz"]
    pkg = ROOT / "src" / "orientviz"
    matched = {p for pattern in patterns for p in pkg.glob(pattern) if p.is_file()}
    data = list((pkg / "datasets" / "examples").glob("*.json")) + list(
        (pkg / "io" / "schema").glob("*.json")
    )
    assert data and all(p in matched for p in data)


def test_unknown_dataset():
    with pytest.raises(ov.InputError, match="unknown dataset 'nope' \\(available: "):
        dataset_path("nope")


def test_generator_is_deterministic_and_reproduces_the_small_examples(tmp_path):
    """The seeded generator rewrites the non-block examples byte for byte.

    (The block examples come from ``orientviz.simulate``, owned elsewhere; for them
    only the structure is compared, so that a change of the simulator does not break this.)
    """
    from orientviz.datasets.make_examples import main

    main(tmp_path)
    for name in EXPECTED:
        new = (tmp_path / f"{name}.json").read_text(encoding="utf-8")
        old = dataset_path(name).read_text(encoding="utf-8")
        if EXPECTED[name] != "block":
            assert new == old
        else:
            a, b = json.loads(new), json.loads(old)
            assert a.keys() == b.keys() and a["units"] == b["units"]


def test_examples_stay_small():
    for name in EXPECTED:
        assert dataset_path(name).stat().st_size < 50_000


def test_loaded_examples_are_consistent_blocks():
    for name in ("block_strip", "block_compact", "resection_example", "intersection_example"):
        b = ov.load_dataset(name).data
        assert b.n_observations > 0
        assert np.all(b.observations.sigma > 0)
        # written σ round-trips through the file unit (mm) exactly
        assert json.loads(dumps_problem(ov.load_dataset(name)))["units"]["image"] == "mm"
