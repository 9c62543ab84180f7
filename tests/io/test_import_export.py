"""Control files, result tables, export (JSON, CSV, COLMAP) and the import/export CLI."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CHECK, CONTROL
from orientviz.cli import main
from orientviz.datasets.debug_example import make_debug_example
from orientviz.io.control import ControlPoints, apply_control, read_control, write_control
from orientviz.report import image_table, point_table, read_csv_table
from orientviz.report.export import export_results


@pytest.fixture(scope="module")
def adjusted():
    sim = ov.simulate_block(2, 4, rng=3)
    return sim.block, ov.bundle_adjust(sim.block)


def test_tables_agree_with_the_adjustment(adjusted):
    block, adj = adjusted
    n = block.n_observations
    v = adj.residuals[: 2 * n].reshape(n, 2) * 1000
    w = np.abs(adj.normalized_residuals[: 2 * n].reshape(n, 2))
    std = adj.std()
    t = image_table(block, adj, angle_unit="rad")
    for i in (0, block.n_images - 1):
        sel = block.observations.image == i
        assert t["n_obs"][i] == sel.sum()
        assert t["rms_vx"][i] == pytest.approx(np.sqrt(np.mean(v[sel, 0] ** 2)))
        assert t["max_w"][i] == pytest.approx(np.nanmax(w[sel]))
        ext = adj.groups["exterior"]
        assert t["kappa"][i] == pytest.approx(adj.x[ext][6 * i + 5])
        assert t["sZ0"][i] == pytest.approx(std[ext][6 * i + 2])
    p = point_table(block, adj)
    j = int(np.argmax(block.rays_per_point()))
    sel = block.observations.point == j
    assert p["n_rays"][j] == sel.sum()
    assert p["rms_vy"][j] == pytest.approx(np.sqrt(np.mean(v[sel, 1] ** 2)))
    assert p["sZ"][j] == pytest.approx(std[adj.groups["points"]][3 * j + 2])
    top = p.sorted_by("max_w", top=3)
    assert len(top) == 3 and top["max_w"][0] == pytest.approx(np.nanmax(p["max_w"]))


def test_table_without_adjustment_shows_misclosures(adjusted):
    block, _ = adjusted
    t = image_table(block)
    e = block.residuals()[block.observations.image == 0] * 1000
    assert t["rms_vx"][0] == pytest.approx(np.sqrt(np.mean(e[:, 0] ** 2)))
    assert np.all(np.isnan(t["sX0"])) and np.all(np.isnan(t["max_w"]))


def test_export_round_trip(adjusted, tmp_path):
    block, adj = adjusted
    out = export_results(block, adj, tmp_path)
    ext = adj.x[adj.groups["exterior"]].reshape(-1, 6)
    again = ov.load_problem(out["json"]).data
    np.testing.assert_allclose(again.images.X0, ext[:, :3], atol=1e-6)
    col = ov.read_colmap(out["colmap"])
    np.testing.assert_allclose(col.images.X0, ext[:, :3], atol=1e-5)
    assert list(col.images.ids) == list(block.images.ids)
    assert list(col.points.ids) == [str(j + 1) for j in range(block.n_points)]
    csv = read_csv_table(out["points_csv"])
    assert csv["id"] == list(block.points.ids)
    xyz = adj.x[adj.groups["points"]].reshape(-1, 3)
    np.testing.assert_allclose(np.array(csv["Z[m]"], float), xyz[:, 2], rtol=1e-15)
    with pytest.raises(ov.InputError, match="unknown export format"):
        export_results(block, adj, tmp_path, formats=["xlsx"])


def test_control_file_round_trip_and_errors(tmp_path):
    cp = ControlPoints(
        ["5", "9"], np.array([[1.0, 2.0, 3.0], [4.0, 5.0, np.nan]]),
        np.array([[0.0, 0, 0], [0.02, 0.02, 0]]), np.array([CONTROL, CHECK], np.int8),
    )  # fmt: skip
    path = tmp_path / "c.csv"
    write_control(path, cp)
    back = read_control(path)
    assert back.ids == ["5", "9"] and back.role.tolist() == [CONTROL, CHECK]
    np.testing.assert_array_equal(back.xyz, cp.xyz)
    block = ov.simulate_block(1, 3, rng=2, control="none").block
    block.points.ids = [str(j + 1) for j in range(block.n_points)]
    b = apply_control(block, back)
    assert b.points.role[4] == CONTROL and b.points.role[8] == CHECK
    assert np.isnan(b.points.sigma[8, 2]) and b.points.xyz_known[8, 2] == block.points.xyz[8, 2]
    lines = path.read_text().splitlines()
    for bad, words in (("1,2,x,3,0,0,0,control", "expected a number"),
                       ("7,1,2,3,0,0,-1,control", "σ ≥ 0"),
                       ("7,1,2,3,0,0,0,ground", "role"),
                       ("5,1,2,3,0,0,0,control", "duplicate"),
                       ("7,1,2", "cells"),
                       ("7,,,,0,0,0,control", "no coordinate")):  # fmt: skip
        path.write_text("\n".join([*lines, bad]) + "\n")
        with pytest.raises(ov.InputError, match=rf"c.csv: line 4: .*{words}"):
            read_control(path)
    path.write_text("\n".join([lines[0], "99999,1,2,3,0,0,0,control"]) + "\n")
    with pytest.raises(ov.InputError, match=r"c.csv: line 2: point '99999' is not in the block"):
        apply_control(block, read_control(path))


def test_debug_example_carries_its_faults(tmp_path):
    ex = make_debug_example(tmp_path, rng=5, strips=2, images_per_strip=4, blunders=2)
    b = ov.read_colmap(ex.colmap)
    truth = ex.truth
    i = b.image_index(ex.bad_image)
    assert np.linalg.norm(b.images.X0[i] - truth.images.X0[i]) > 100
    # the true geometry reprojects the blunders off by their size, the other rays by noise
    t = b.copy()
    t.images.X0, t.images.angles, t.points.xyz = (
        truth.images.X0,
        truth.images.angles,
        truth.points.xyz,
    )
    e = np.linalg.norm(t.residuals(), axis=1)
    labels = [
        f"{b.images.ids[k]}/{b.points.ids[p]}"
        for k, p in zip(b.observations.image, b.observations.point)
    ]
    idx = [labels.index(f"{a}/{p}") for a, p in ex.blunders]
    np.testing.assert_allclose(e[idx], ex.blunder_sizes_mm, atol=0.03)
    assert np.median(np.delete(e, idx)) < 0.01
    assert read_control(ex.control).ids  # control keyed by POINT3D_ID of the model
    apply_control(b, read_control(ex.control))


def test_cli_import_with_control_then_export(tmp_path, capsys):
    ex = make_debug_example(tmp_path / "ex", rng=5, strips=2, images_per_strip=4, blunders=0)
    out = tmp_path / "b.json"
    assert (
        main(
            [
                "import-colmap",
                str(ex.colmap),
                "--control",
                str(ex.control),
                "--sigma-px",
                "0.5",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    problem = ov.load_problem(out)
    block = problem.data
    assert problem.units.length == "m"  # control gives the model its scale (no "model" units)
    assert np.sum(block.points.role == CONTROL) == len(read_control(ex.control).ids)
    assert np.allclose(block.observations.sigma, 0.005)
    # the misplaced image stops the export as it stops `solve`: the bundle does not
    # converge (3) or converges to a model that does not fit (4, σ0 in the thousands);
    # either way nothing is written
    code = main(["export", str(out), "-d", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert (code == 3 and "did not converge" in err) or (code == 4 and "does not fit" in err), (
        code,
        err,
    )
    assert not (tmp_path / "r").exists() or not any((tmp_path / "r").iterdir())
    assert (
        main(["export", str(out), "-d", str(tmp_path / "r"), "--no-adjust", "--format", "csv"]) == 0
    )
    assert (tmp_path / "r" / "images.csv").exists() and not (tmp_path / "r" / "colmap").exists()
    assert (
        main(
            [
                "import-bal",
                str(ex.bal),
                "--control",
                str(tmp_path / "nope.csv"),
                "-o",
                str(tmp_path / "c.json"),
            ]
        )
        == 2
    )
    assert "nope.csv" in capsys.readouterr().err
