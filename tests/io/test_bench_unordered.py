"""Smoke test of benchmarks/bench_unordered.py: generator + COLMAP import + perturbation.

No timing is asserted; this only checks that the benchmark's data are what it claims.
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pycolmap")

from orientviz.block import CONTROL  # noqa: E402
from orientviz.bundle import bundle_adjust  # noqa: E402
from orientviz.rotation import matrix_from_opk, rotvec_from_matrix  # noqa: E402

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_unordered.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_unordered", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("tracks", ["random", "visibility"])
def test_generated_network_imports_and_adjusts(bench, tracks, tmp_path):
    rng = np.random.default_rng(3)
    control = bench.generate(tmp_path, 10, tracks, rng)
    block = bench.read_block(tmp_path, control)
    assert block.n_images == 10
    assert len(set(control)) == bench.N_CONTROL
    assert np.count_nonzero(block.points.role == CONTROL) == bench.N_CONTROL
    per_point = np.bincount(block.observations.point, minlength=block.points.xyz.shape[0])
    if tracks == "visibility":
        assert np.all(per_point == 10)
    else:
        assert np.all(per_point == 8)
    res = bundle_adjust(block, precision=False)
    assert res.converged
    # 0.7 px noise imported with σ = 0.7 px: σ0 ≈ 1 (redundancy > 1000)
    assert abs(res.sigma0 - 1.0) < 0.1


def test_perturbation_is_20_degrees_and_one_unit(bench, tmp_path):
    rng = np.random.default_rng(4)
    control = bench.generate(tmp_path, 10, "random", rng)
    good = bench.read_block(tmp_path, control)
    poor = bench.read_block(tmp_path, control)
    bench.perturb(poor, rng)
    shift = np.linalg.norm(poor.images.X0 - good.images.X0, axis=1)
    np.testing.assert_allclose(shift, 1.0, rtol=1e-9)
    Rg = matrix_from_opk(*good.images.angles.T, good.sequence)
    Rp = matrix_from_opk(*poor.images.angles.T, poor.sequence)
    angle = np.degrees(np.linalg.norm(rotvec_from_matrix(Rp @ np.swapaxes(Rg, 1, 2)), axis=1))
    np.testing.assert_allclose(angle, 20.0, rtol=1e-6)
    ctrl = poor.points.role == CONTROL
    np.testing.assert_array_equal(poor.points.xyz[ctrl], good.points.xyz[ctrl])
    assert np.all(np.isfinite(poor.points.xyz))
    assert not np.allclose(poor.points.xyz[~ctrl], good.points.xyz[~ctrl])
