"""import-csv: image measurements from a CSV table, the documented path for PhotoModeler/DBAT tables."""

from __future__ import annotations

import json

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.errors import InputError
from orientviz.io.datasets import dataset_path
from orientviz.io.kinds.block import solve
from orientviz.io.measurements import block_from_measurements, read_measurements
from orientviz.io.problem import load_problem, loads_problem

SXB = dataset_path("dbat_sxb").parent / "sxb"


def _dbat_tables(tmp_path):
    """DBAT's own sxb files rewritten as the two CSV tables of the documented path."""
    names = dict(line.split(", ") for line in (SXB / "images.txt").read_text().splitlines()[1:])
    rows = ["image,point,x,y,sigma"]
    for f, s in (("markpts.txt", 0.5), ("smartpts.txt", 1.0)):
        for line in (SXB / f).read_text().splitlines()[1:]:
            pid, im, x, y = (v.strip() for v in line.split(","))
            rows.append(f"{names[im].split('/')[-1][:-4]},{pid},{x},{y},{s}")
    (tmp_path / "marks.csv").write_text("\n".join(rows) + "\n")
    ctrl = ["id,X,Y,Z,sX,sY,sZ,role"]
    for line in (SXB / "sxb-control.txt").read_text().splitlines()[1:]:
        pid, _, X, Y, Z, sx, sy, sz = (v.strip() for v in line.split(","))
        role = "check" if pid in ("351", "410") else "control"
        ctrl.append(f"{pid},{X},{Y},{Z},{sx},{sy},{sz},{role}")
    (tmp_path / "control.csv").write_text("\n".join(ctrl) + "\n")


def test_the_csv_path_gives_the_shipped_block(tmp_path):
    _dbat_tables(tmp_path)
    out = tmp_path / "block.json"
    code = main(["import-csv", str(tmp_path / "marks.csv"), "--c", "123.9392",
                 "--pixel-size", "0.006", "--principal-point", "26.577", "38.811",
                 "--format", "53.148", "77.976", "--control", str(tmp_path / "control.csv"),
                 "-o", str(out)])  # fmt: skip
    assert code == 0
    mine = load_problem(out)
    shipped = json.loads(dataset_path("dbat_sxb").read_text())
    shipped["options"].pop("check_points")  # the importer's default: independent checks
    ref = loads_problem(json.dumps(shipped), "ref.json")
    a, b = solve(mine, "bundle").adjustment, solve(ref, "bundle").adjustment
    assert a.redundancy == b.redundancy and a.sigma0 == pytest.approx(b.sigma0, rel=1e-9)
    assert mine.data.cameras.y0[0] == pytest.approx(-38.811)


def test_mm_units_keep_the_frame(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("image,point,x,y\na,1,1.5,-2.0\nb,1,0.5,2.0\n")
    block = block_from_measurements(read_measurements(p), c=100.0, units="mm", sigma=0.003)
    assert np.allclose(block.observations.xy, [[1.5, -2.0], [0.5, 2.0]])
    assert np.allclose(block.observations.sigma, 0.003)
    assert np.all(np.isnan(block.images.X0))


@pytest.mark.parametrize(
    "text, words, line",
    [
        ("image,point,x\na,1,2\n", "missing y", 1),
        ("image,point,x,y\na,1,2,abc\n", "expected a number", 2),
        ("image,point,x,y\na,1,2,3\na,1,4,5\n", "measured twice", 3),
        ("image,point,x,y,sigma\na,1,2,3,-1\n", "expected > 0", 2),
        ("image,point,x,y\n,1,2,3\n", "empty image or point id", 2),
    ],
)
def test_broken_tables_name_file_and_line(tmp_path, text, words, line):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputError) as info:
        read_measurements(p)
    assert words in str(info.value) and f"line {line}" in str(info.value)
