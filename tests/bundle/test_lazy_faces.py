"""The bundle's (and the block's) package faces load names on first use (faces.lazy_names).

A name on a face is the very object of the module that defines it, whether it was
loaded eagerly or on first use; an import command loads no solver and no solution
types, and a plain solve (no self-calibration set, no auxiliary data, no check points,
no cleaning) imports none of the modules it does not run.
"""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from orientviz.rotation import matrix_from_rotvec

FACES = [
    "orientviz.block",
    "orientviz.bundle",
    "orientviz.bundle.model",
    "orientviz.bundle.precision",
    "orientviz.bundle.problem",
]

#: Modules (prefixes) an import command never runs.
NOT_IN_AN_IMPORT = [
    "orientviz.adjust",
    "orientviz.block._result",
    "orientviz.bundle",
    "orientviz.io.control",
    "orientviz.io.solution",
    "scipy",
]

#: Modules a plain solve of an imported BAL problem never runs.
NOT_IN_A_PLAIN_SOLVE = [
    "orientviz.adjust.gross",
    "orientviz.adjust.gross2d",
    "orientviz.bundle._alternation",
    "orientviz.bundle._cleaning",
    "orientviz.bundle._reference_data",
    "orientviz.bundle._selfcal",
    "orientviz.bundle.model._additional",
    "orientviz.bundle.precision._reliability",
    "orientviz.bundle.problem._auxiliary",
    "orientviz.bundle.reference",
    "orientviz.orientation.intersection",
]


def _lazy_table(face) -> dict[str, str]:
    return getattr(face, "_FACE", None) or getattr(face, "_LAZY", {})


@pytest.mark.parametrize("name", FACES)
def test_every_name_on_a_face_is_its_modules_object(name):
    face = importlib.import_module(name)
    lazy = _lazy_table(face)
    assert lazy, f"{name} has no names loaded on first use"
    assert set(lazy) <= set(face.__all__)
    assert sorted(dir(face)) == sorted(face.__all__)
    for public in face.__all__:
        value = getattr(face, public)
        if public in lazy:
            home = importlib.import_module(lazy[public], name)
            assert getattr(home, public) is value, f"{name}.{public}"
        assert value is getattr(face, public)  # kept in the face once loaded
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        face.no_such_name  # noqa: B018


def test_names_imported_from_a_face_are_the_defining_modules_objects():
    from orientviz.bundle import RayReliability, ap_set, clean_block
    from orientviz.bundle._cleaning import clean_block as cleaning_clean_block
    from orientviz.bundle.model._additional import ap_set as additional_ap_set
    from orientviz.bundle.precision._reliability import RayReliability as reliability_class

    assert ap_set is additional_ap_set
    assert clean_block is cleaning_clean_block
    assert RayReliability is reliability_class


def _bal_file(path) -> None:
    """A BAL file of four cameras around 60 points, exact pixels (P = R X + t, x = −f P/P_z)."""
    rng = np.random.default_rng(7)
    pts = rng.uniform([-400, -400, 0], [400, 400, 300], (60, 3))
    X0 = np.array([[-300, -50, 1500], [300, 0, 1450], [0, 300, 1550], [0, -300, 1500.0]])
    rot = rng.normal(0, 0.05, (4, 3))
    lines = [f"4 {len(pts)} {4 * len(pts)}"]
    for c in range(4):
        R = matrix_from_rotvec(rot[c])
        for p, X in enumerate(pts):
            P = R @ (X - X0[c])
            x, y = -1000.0 * P[:2] / P[2]
            lines.append(f"{c} {p} {x:.6f} {y:.6f}")
    for c in range(4):
        t = -matrix_from_rotvec(rot[c]) @ X0[c]
        lines += [repr(float(v)) for v in (*rot[c], *t, 1000.0, 0.0, 0.0)]
    lines += [repr(float(v)) for v in pts.ravel()]
    path.write_text("\n".join(lines) + "\n")


def test_import_and_a_plain_solve_import_no_module_they_do_not_run(tmp_path):
    """``import-bal`` then ``solve --free`` in a fresh interpreter: the import loads no
    solver, no solution types and no control reader; the solve no self-calibration sets,
    cleaning, gross-error tests, reliability, auxiliary data, the reference iteration or
    the forward intersection (none of them runs here)."""
    _bal_file(tmp_path / "p.bal")
    script = (
        "import io, contextlib, json, sys\n"
        "from orientviz.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):\n"
        "    a = main(['import-bal', sys.argv[1], '-o', sys.argv[2]])\n"
        "    imported = sorted(sys.modules)\n"
        "    b = main(['solve', sys.argv[2], '--free', '--json'])\n"
        "print(json.dumps({'codes': [a, b], 'import': imported, 'modules': sorted(sys.modules)}))\n"
    )
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    run = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path / "p.bal"), str(tmp_path / "p.json")],
        capture_output=True, text=True, env=env, check=True,
    )  # fmt: skip
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["codes"] == [0, 0]
    assert "orientviz.io.bal" in got["import"]
    assert [m for m in got["import"] if m.startswith(tuple(NOT_IN_AN_IMPORT))] == []
    assert "orientviz.bundle.loop._adjust" in got["modules"]  # it did solve
    assert [m for m in NOT_IN_A_PLAIN_SOLVE if m in got["modules"]] == []
