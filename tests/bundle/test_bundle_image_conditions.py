"""An image whose rays give fewer than 6 conditions is named before the iterations.

Found on the Gruber-only variant of benchmarks/bench_gross.py: with 10 check points
(their rays do not enter the adjustment) some strip-end images keep only two
intersected points and one two-ray point — 2 + 2 + 1 = 5 conditions for 6 unknowns.
The bundle used to converge and then fail with a raw LinAlgError in the precision step
(seed 20) or report standard deviations of kilometres (seed 13).
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle.loop import _adjust as bundle_mod
from orientviz.bundle.problem import image_condition_deficit, point_setup


def _gruber_block(seed: int):
    # the benchmark's Gruber-only variant: tie points only at the Gruber positions
    return ov.simulate_block(4, 10, rng=seed, n_check=10, control="perimeter", extra=None).block


def _flagged(block) -> list[str]:
    deficit = image_condition_deficit(block, point_setup(block, "fixed"))
    return [block.images.ids[i] for i in np.flatnonzero(deficit)]


@pytest.mark.parametrize("seed", [13, 20])
def test_weak_image_is_named_before_the_iterations(seed):
    block = _gruber_block(seed)
    flagged = _flagged(block)
    assert flagged
    with pytest.raises(ov.NotDeterminableError) as exc:
        ov.bundle_adjust(block)
    assert [p.split(".")[0] for p in exc.value.parameters] == flagged
    assert exc.value.defect >= 1


@pytest.mark.parametrize("seed", [13, 20])
def test_the_count_names_a_real_null_space(monkeypatch, seed):
    # without the count the iterations converge on the singular system (rounding keeps
    # the factorisation going); what follows depends on rounding (BLAS threads, the
    # order of the kernel's products): either the precision step meets the singular
    # reduced matrix — then it must raise NotDeterminableError naming the same image
    # from the matrix's null space, never a LinAlgError — or the check of the damped
    # start meets it (the result is not converged and says why), or it passes and gives
    # that image a position standard deviation far beyond the size of the block
    block = _gruber_block(seed)
    flagged = _flagged(block)
    monkeypatch.setattr(bundle_mod, "check_datum", lambda b, s: None)
    try:
        adj = ov.bundle_adjust(block)
    except ov.NotDeterminableError as exc:
        assert {p.split(".")[0] for p in exc.parameters} == set(flagged)
        return
    if not adj.converged:
        assert "normal equations are not positive definite" in adj.reason
        assert "exterior" not in adj.cofactor_groups  # no precision from a singular system
        return
    sd = np.sqrt(np.einsum("mii->mi", adj.cofactor_groups["exterior"])[:, :3]) * adj.sigma0
    i = list(block.images.ids).index(flagged[0])
    extent = np.ptp(adj.exterior[:, :3], axis=0).max()
    assert sd[i].max() > extent
    assert np.delete(sd, i, axis=0).max() < 0.01 * extent


@pytest.mark.parametrize("seed", [1, 2])
def test_healthy_blocks_pass_the_count(seed):
    for block in (_gruber_block(seed), ov.simulate_block(4, 10, rng=seed).block):
        assert not _flagged(block)
        assert ov.bundle_adjust(block).converged
