"""Messages and labels in the user's words (issue #14 point 7).

No output of ``orientviz solve`` and no error message of the bundle names an internal
parameter (``img24.Z0``), an internal index (``pseudo[21]``, ``obs[3]``, ``control[2]``)
or an orientviz-made name where the user gave an id.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import BundleOptions
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
from orientviz.cli import main
from orientviz.errors import parameter_words
from orientviz.io.datasets import dataset_path

#: ``<id>.X0`` … ``<id>.kappa``: an image's internal parameter name
INTERNAL_IMAGE = re.compile(r"\S\.(X0|Y0|Z0|omega|phi|kappa)\b")
#: ``name[12]``: an internal index
INDEX = re.compile(r"[A-Za-z_]\[\d+\]")


def leaks(text: str) -> list[str]:
    return INTERNAL_IMAGE.findall(text) + INDEX.findall(text)


def test_parameter_words_group_by_the_users_ids():
    names = ["img24.Z0", "img24.omega", "p7.X", "strip3.height.tilt across the strip", "a.b.kappa"]
    text = parameter_words(names)
    assert (
        text == "image img24 (Z0, ω), point p7 (X), strip 3 (tilt across the strip), image a.b (κ)"
    )
    assert not leaks(text)


#: a polynomial's internal names: ``strip3.height.p2`` or its old rendering ``polynomial p2``
POLYNOMIAL_INTERNAL = re.compile(r"\bstrip\d+\.\w|polynomial p\d+")


def _polynomial_file(tmp_path, name: str, edit) -> str:
    """block_strip with its strip numbered 7 (not the internal 0), edited by ``edit``."""
    doc = json.loads(Path(dataset_path("block_strip")).read_text())
    for image in doc["images"]:
        image["strip"] = 7
    edit(doc)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(doc))
    return str(path)


def _no_control(doc):
    for p in doc["points"]:
        if p.get("role") == "control":
            p["role"] = "tie"


def _no_strips(doc):
    for image in doc["images"]:
        del image["strip"]


@pytest.mark.parametrize(
    "case, edit, code, words",
    [
        # 4 height control points cannot fix a degree-2 height polynomial (5 terms)
        ("height", lambda doc: None, 3, ("strip 7 (", "tilt across the strip", "degree_z")),
        ("no-control", _no_control, 3, ("strip 7 (", "shift X", "degree_xy")),
        ("no-strips", _no_strips, 2, ("strip number", "images[].strip")),
    ],
)
def test_polynomial_failures_name_the_users_strips(tmp_path, capsys, case, edit, code, words):
    path = _polynomial_file(tmp_path, case, edit)
    assert main(["solve", path, "--method", "polynomial"]) == code
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert all(w in err for w in words), err
    assert not leaks(err) and not POLYNOMIAL_INTERNAL.search(err), err


def test_singular_reduced_system_message_names_images_by_id():
    sim = ov.simulate_block(2, 4, rng=3, extra=8, control="perimeter")
    block = sim.block
    prob = BundleProblem(block, point_setup(block, "fixed"), options=BundleOptions(solver="banded"))
    st = BundleState(block.images.X0.copy(), block.images.angles.copy(),
                     block.points.xyz.copy(), np.zeros(0))  # fmt: skip
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    ne.blocks[:, 5, :] = 0.0  # nothing determines κ of the images any more
    ne.blocks[:, :, 5] = 0.0
    with pytest.raises(ov.NotDeterminableError) as info:
        prob.solve(ne, prob.names()[: 6 * prob.m])
    msg = str(info.value)
    assert not leaks(msg), msg
    assert any(f"image {i} (κ)" in msg for i in block.images.ids), msg


def _weighted_block_with_oddities(tmp_path) -> str:
    """block_strip with weighted control, one control point seen in no image and one with
    a σ = 0 coordinate (the cases in which the pseudo-observations once fell back to
    indices), and a gross error so that labels are printed as flagged."""
    doc = json.loads(Path(dataset_path("block_strip")).read_text())
    doc.setdefault("options", {})["control"] = "weighted"
    ctrl = [p for p in doc["points"] if p.get("role") == "control"]
    for p in ctrl:
        p["sigma"] = [0.01, 0.01, 0.02]
    ctrl[0]["sigma"] = [0.01, 0.01, 0.0]
    ties = {p["id"] for p in doc["points"] if p.get("role", "tie") == "tie"}
    rays = Counter(o["point"] for o in doc["observations"] if o["point"] in ties)
    best = rays.most_common(1)[0][0]  # the best-determined tie point: a gross error shows
    next(o for o in doc["observations"] if o["point"] == best)["x"] += 0.120
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(doc))
    return str(path)


def test_no_internal_names_in_any_output(tmp_path, capsys):
    path = _weighted_block_with_oddities(tmp_path)
    assert main(["solve", path, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    labels = [f["label"] for f in out["flagged"]]
    assert labels and not leaks(" ".join(labels)), labels
    problem = ov.load_problem(path)
    solution = ov.solve_problem(problem)
    all_labels = solution.adjustment.obs_labels
    assert not leaks("\n".join(all_labels))
    # every control coordinate is a pseudo-observation (σ = 0 ones held by a tiny σ),
    # labelled by its point id in the file's order
    doc = json.loads(Path(path).read_text())
    ctrl = [p["id"] for p in doc["points"] if p.get("role") == "control"]
    assert all_labels[solution.adjustment.obs_slices["control"]] == [
        f"{i}/{c}" for i in ctrl for c in "XYZ"
    ]
    report = tmp_path / "r.txt"
    assert main(["solve", path, "--report", str(report)]) == 0
    text = capsys.readouterr().out + report.read_text()
    assert not leaks(text), leaks(text)[:5]


def test_a_diverging_block_names_what_moved_most(tmp_path, capsys):
    """One image started 800 m and 30 gon off and only 2 iterations allowed: the report
    names images and points by their ids, largest move first, with the moves."""
    doc = json.loads(Path(dataset_path("block_strip")).read_text())
    doc["images"][1]["X0"] += 800.0
    doc["images"][1]["omega"] += 30.0
    path = tmp_path / "far.json"
    path.write_text(json.dumps(doc))
    assert main(["solve", str(path), "--max-iter", "2"]) == 3
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("NOT CONVERGED — moved most"))
    assert not leaks(line)
    problem = ov.load_problem(str(path))
    block = problem.data
    named = re.findall(r"(\S+) \(([\d.]+) m", line)
    ids = [i for i, _ in named]
    assert set(ids) <= set(block.images.ids) | set(block.points.ids) and ids
    # largest move first
    images = [(i, float(v)) for i, v in named if i in set(block.images.ids)]
    assert [v for _, v in images] == sorted((v for _, v in images), reverse=True)
