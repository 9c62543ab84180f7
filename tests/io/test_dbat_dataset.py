"""DBAT's aerial block shipped as a dataset: conversion, licence, check points both ways."""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from orientviz.block import CHECK, CONTROL, TIE
from orientviz.datasets import make_dbat
from orientviz.io.datasets import dataset_info, dataset_path, load_dataset
from orientviz.io.kinds.block import approximate, solve, with_check_rays
from orientviz.io.problem import loads_problem
from orientviz.reproduce.dbat_files import read_camcal

FOLDER = dataset_path("dbat_sxb").parent


def _fake_checkout(tmp_path: Path) -> Path:
    """A DBAT checkout laid out as on GitHub, from the original files shipped beside the data."""
    root = tmp_path / "dbat"
    for name in make_dbat.SXB_FILES:
        target = root / make_dbat.SXB / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(FOLDER / "sxb" / Path(name).name, target)
    for name in make_dbat.CAMCAL_FILES:
        target = root / make_dbat.CAMCAL / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(FOLDER / "camcal" / Path(name).name, target)
    report = root / make_dbat.CAMCAL_REPORT
    report.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(FOLDER / "camcal" / "camcal-dbatreport.txt", report)
    for name in make_dbat.ROMA_FILES:  # DBAT's measurements are shipped gzipped
        target = root / make_dbat.ROMA / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shipped = FOLDER / "roma" / Path(name).name
        if not shipped.exists():
            target.write_bytes(
                gzip.decompress((FOLDER / "roma" / (shipped.name + ".gz")).read_bytes())
            )
        else:
            shutil.copyfile(shipped, target)
    shutil.copyfile(FOLDER / "LICENSE.txt", root / "LICENSE.txt")
    return root


def test_the_shipped_problem_is_what_the_script_makes_of_dbats_files(tmp_path):
    out = tmp_path / "out"
    assert make_dbat.main([str(_fake_checkout(tmp_path)), "-o", str(out)]) == 0
    for name in (
        "dbat_sxb.json",
        "dbat_camcal.json",
        "MANIFEST.json",
        "CITATION.md",
        "LICENSE.txt",
        "roma/markpts.txt.gz",
        "roma/report.txt",
    ):
        assert (out / name).read_bytes() == (FOLDER / name).read_bytes(), name
    shipped = sorted(p.relative_to(FOLDER) for p in FOLDER.rglob("*") if p.is_file())
    made = sorted(p.relative_to(out) for p in out.rglob("*") if p.is_file())
    assert made == shipped  # nothing shipped that the script does not make


def test_the_camera_calibration_demo_reads_as_dbat_describes_it():
    d = read_camcal(FOLDER / "camcal")
    assert d["image_px"] == [2272, 1704] and len(d["images"]) == 21
    assert len(d["marks"]) == 2074 and len(d["control"]) == 4  # 4148 image coordinates
    assert d["pixel_mm"] == pytest.approx(5.43764 / 1704)
    assert {m[4] for m in d["marks"]} == {0.1}  # σ 0.1 px


def test_the_script_refuses_a_folder_that_is_not_dbat(tmp_path, capsys):
    assert make_dbat.main([str(tmp_path)]) == 2
    assert "not a DBAT checkout" in capsys.readouterr().err


def test_licence_and_citation_ship_beside_the_data():
    info = dataset_info("dbat_sxb")
    assert "BSD" in info["licence"] and info["citation"] == "CITATION.md"
    licence = (FOLDER / "LICENSE.txt").read_text(encoding="utf-8")
    assert "Redistribution and use in source and binary forms" in licence
    assert "Börlin" in licence
    citation = (FOLDER / "CITATION.md").read_text(encoding="utf-8")
    assert "10.5194/isprs-archives-XLII-2-W17-69-2019" in citation
    assert not list(FOLDER.rglob("*.m")), "DBAT's code is never shipped, only its data"
    size = sum(f.stat().st_size for f in FOLDER.rglob("*") if f.is_file())
    assert size < 2_000_000


def test_the_block_has_dbats_counts_and_conventions():
    block = load_dataset("dbat_sxb").data
    assert block.n_images == 5 and len(block.observations) == 1196  # 2392 image coordinates
    roles = np.bincount(block.points.role, minlength=3)
    assert roles[CONTROL] == 14 and roles[CHECK] == 2 and roles[TIE] == 365
    chk = [block.points.ids[i] for i in np.flatnonzero(block.points.role == CHECK)]
    assert sorted(chk) == ["351", "410"]
    # pixel → mm: x = col · 0.006, y = −row · 0.006; the first marked point of image 8811
    i = block.image_index("8811")
    k = np.flatnonzero(
        (block.observations.image == i) & (block.observations.point == block.point_index("317"))
    )
    assert np.allclose(block.observations.xy[k], [[5007.6667 * 0.006, -7275.6667 * 0.006]])
    assert np.isclose(block.cameras.y0[0], -38.811) and np.isclose(block.cameras.c[0], 123.9392)
    sig = np.unique(block.observations.sigma)
    assert np.allclose(sig, [0.003, 0.006])  # 0.5 px marked, 1.0 px "smart" points


def test_approximations_start_a_block_whose_control_point_has_one_ray():
    block = load_dataset("dbat_sxb").data
    one = block.point_index("403")
    assert block.rays_per_point()[one] == 1 and block.points.role[one] == CONTROL
    start = approximate(block)
    assert np.all(np.isfinite(start.images.X0)) and np.all(np.isfinite(start.points.xyz))
    assert np.allclose(start.points.xyz[one], block.points.xyz_known[one])


def _variant(mode: str | None):
    doc = json.loads(dataset_path("dbat_sxb").read_text(encoding="utf-8"))
    if mode is None:
        doc["options"].pop("check_points")
    else:
        doc["options"]["check_points"] = mode
    return loads_problem(json.dumps(doc), "dbat_sxb.json")


def test_check_points_both_ways():
    rays = solve(_variant("rays"), "bundle")
    indep = solve(_variant(None), "bundle")
    a, b = rays.adjustment, indep.adjustment
    assert a.redundancy == 1261  # DBAT's count: check rays in, check coordinates out
    assert b.redundancy == 1261 - (2 * 7 - 6)  # 7 check rays and 2 check points out
    assert "keep their image rays" in " ".join(rays.notes)
    assert "independent" in " ".join(indep.notes)
    # with rays kept the check points get a-posteriori σ from the adjustment itself
    ids = list(rays.point_ids)
    k = ids.index("410")
    assert np.all(np.isfinite(rays.xyz_sigma[k])) and np.all(rays.xyz_sigma[k] > 0)
    assert not np.allclose(rays.xyz[k], indep.xyz[k], atol=1e-4)


def test_check_rays_copy_leaves_the_input_alone():
    block = load_dataset("dbat_sxb").data
    before = block.points.role.copy()
    out = with_check_rays(block)
    assert np.array_equal(block.points.role, before)
    assert not np.any(out.points.role == CHECK)


def test_an_unknown_check_mode_is_refused():
    with pytest.raises(Exception, match="check_points"):
        _variant("sometimes")
