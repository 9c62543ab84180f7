"""A solve whose precision failed is still told that its model does not fit (exit 4)."""

from __future__ import annotations

import json

import numpy as np

from orientviz.bundle.loop import _finish
from orientviz.cli import main
from orientviz.io.datasets import dataset_path


def _distorted(tmp_path):
    """block_strip with radial distortion the model lacks (k1 = 2e-6 mm⁻²): σ0 ≫ 1."""
    d = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    for o in d["observations"]:
        r2 = o["x"] ** 2 + o["y"] ** 2
        o["x"] += 2e-6 * o["x"] * r2
        o["y"] += 2e-6 * o["y"] * r2
    path = tmp_path / "distorted.json"
    path.write_text(json.dumps(d), encoding="utf-8")
    return path


def _without_precision(monkeypatch):
    """The precision fails at the converged state, as it can with points near infinity."""

    def fail(*_args, **_kw):
        raise np.linalg.LinAlgError("leading minor not positive definite")

    monkeypatch.setattr(_finish, "bundle_precision", fail)
    monkeypatch.setattr(_finish, "_far_points", lambda prob, st: np.array([0]))


def test_a_misfit_is_told_without_redundancy_numbers(tmp_path, capsys, monkeypatch):
    """No precision, so no Baarda w: the verdict uses the average redundancy number."""
    path = _distorted(tmp_path)
    assert main(["solve", str(path)]) == 4  # with Baarda's w
    assert "average redundancy" not in capsys.readouterr().err
    _without_precision(monkeypatch)
    assert main(["solve", str(path)]) == 4
    err = capsys.readouterr().err
    assert "does not fit the data" in err and "average redundancy number r/n = " in err
    assert "lens distortion" in err and "One gross error" not in err
    # a block that fits stays quiet without its redundancy numbers too
    assert main(["solve", str(dataset_path("block_strip"))]) == 0
    assert "does not fit" not in capsys.readouterr().err
