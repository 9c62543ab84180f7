"""A single gross error in a small block is named as one, not as a model that does not fit."""

from __future__ import annotations

import json
import re

from orientviz.cli import main
from orientviz.io.datasets import dataset_path


def _strip(tmp_path, k: int, factor: float, coord: str = "x"):
    d = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    o = d["observations"][k]
    o[coord] += factor * o["sigma"]
    path = tmp_path / "strip.json"
    path.write_text(json.dumps(d), encoding="utf-8")
    return path, o


def test_one_blunder_is_named_with_its_point_image_and_remedy(tmp_path, capsys):
    path, o = _strip(tmp_path, 12, 100.0)  # control point g02_000 in image s00_001
    assert main(["solve", str(path)]) == 4
    err = capsys.readouterr().err
    assert "One gross error explains it" in err
    assert f"point '{o['point']}', x in image '{o['image']}'" in err
    assert "--robust cauchy" in err
    assert "lens distortion" not in err and "wrong unit" not in err
    sigma0 = float(re.search(r"without it sigma0 would be (\d+\.\d+)", err).group(1))
    assert sigma0 < 1.5


def test_the_remedy_works(tmp_path, capsys):
    path, _ = _strip(tmp_path, 12, 100.0)
    assert main(["solve", str(path), "--robust", "cauchy", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["global_test"]["result"] == "accepted"


def test_a_misfit_of_many_observations_keeps_the_model_causes(tmp_path, capsys):
    d = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    for o in d["observations"]:  # radial distortion missing from the model (k1 = 2e-6 mm⁻²)
        r2 = o["x"] ** 2 + o["y"] ** 2
        o["x"] += 2e-6 * o["x"] * r2
        o["y"] += 2e-6 * o["y"] * r2
    path = tmp_path / "distorted.json"
    path.write_text(json.dumps(d), encoding="utf-8")
    assert main(["solve", str(path)]) == 4
    err = capsys.readouterr().err
    assert "One gross error" not in err and "lens distortion" in err


def test_no_single_gross_error_is_named_when_w_squared_exceeds_vtpv():
    """w_i² ≤ vᵀPv = r σ̂0² holds for the linearised model; redundancy numbers that break
    it (nearly singular normal equations at a wrong minimum) name no observation."""
    from types import SimpleNamespace

    import numpy as np

    from orientviz.io.kinds.block import single_gross_error

    def adj(w_max):
        w = np.r_[w_max, np.full(99, 0.5)]
        return SimpleNamespace(normalized_residuals=w, redundancy=50, sigma0=30.0, obs_labels=None)

    omega = 50 * 30.0**2  # vᵀPv = 45 000
    named = single_gross_error(adj(np.sqrt(omega) * 0.9999), 50)
    assert named is not None and "observation no. 1" in named
    assert single_gross_error(adj(np.sqrt(omega) * 1.01), 50) is None
