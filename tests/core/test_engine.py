import numpy as np
import pytest

import orientviz as ov
from orientviz.adjust import gauss_newton

T = np.linspace(0, 1, 30)


def _model(x):
    e = np.exp(x[1] * T)
    return x[0] * e + x[2], np.column_stack([e, x[0] * T * e, np.ones_like(T)])


def _data(seed=1, sigma=0.01):
    rng = np.random.default_rng(seed)
    return 2.0 * np.exp(-1.0 * T) + 0.5 + rng.normal(0, sigma, T.size)


@pytest.mark.parametrize("damping", ["none", "lm"])
def test_noise_free_is_exact(damping):
    l = 2.0 * np.exp(-1.0 * T) + 0.5
    r = gauss_newton(_model, [1.5, -0.8, 0.3], l, 0.01, damping=damping)
    assert r.converged
    np.testing.assert_allclose(r.x, [2.0, -1.0, 0.5], atol=1e-9)
    assert r.sigma0 < 1e-6


def test_precision_quantities_are_consistent():
    r = gauss_newton(_model, [1.5, -0.8, 0.3], _data(), 0.01, names=["a", "b", "c"])
    assert r.redundancy == 27
    assert r.redundancy_numbers.sum() == pytest.approx(27.0, abs=1e-8)
    # sigma0 from residuals equals sqrt(v'Pv / r)
    assert r.sigma0 == pytest.approx(np.sqrt(np.sum((r.residuals / 0.01) ** 2) / 27))
    C = r.correlations()
    np.testing.assert_allclose(np.diag(C), 1.0)
    assert r.history[0].index == 0 and r.iterations == len(r.history) - 1


def test_sigma0_matches_noise_over_many_runs():
    # the mean of sigma0^2 over repetitions estimates the a-priori variance factor 1
    s2 = [
        gauss_newton(_model, [1.5, -0.8, 0.3], _data(seed), 0.01).sigma0 ** 2 for seed in range(200)
    ]
    # std of the mean of chi2_27/27 over 200 runs is sqrt(2/27/200) = 0.019
    assert abs(np.mean(s2) - 1.0) < 4 * 0.019


def test_rank_defect_names_parameters():
    def m2(x):
        f, J = _model(x[:3])
        return f + x[3], np.column_stack([J, np.ones_like(T)])

    with pytest.raises(ov.NotDeterminableError) as info:
        gauss_newton(m2, [1.0, -0.5, 0.0, 0.0], _data(), 0.01, names=["a", "b", "c", "d"])
    assert set(info.value.parameters) == {"c", "d"}
    assert info.value.defect == 1


def test_fixed_parameter_and_non_convergence_is_a_result():
    r = gauss_newton(
        _model, [1.0, -0.5, 0.0], _data(), 0.01, fixed=[False, False, True], max_iter=2
    )
    assert r.x[2] == 0.0
    assert not r.converged and "maximum" in r.reason


def test_lm_converges_where_gauss_newton_diverges():
    l = 2.0 * np.exp(-1.0 * T) + 0.5
    gn = gauss_newton(_model, [1.0, -0.5, 0.0], l, 0.01)
    assert not gn.converged
    lm = gauss_newton(_model, [1.0, -0.5, 0.0], l, 0.01, damping="lm")
    assert lm.converged
    np.testing.assert_allclose(lm.x, [2.0, -1.0, 0.5], atol=1e-8)


def test_extend_types_a_result_without_a_bag():
    """A task's own results are typed fields of a subclass; the engine's fields are shared."""
    import dataclasses

    from orientviz.orientation.relative import RelativeResult

    r = gauss_newton(_model, [1.5, -0.8, 0.3], _data(), 0.01)
    assert "extra" not in {f.name for f in dataclasses.fields(r)}
    t = r.extend(RelativeResult, kind="independent", base=92.0)
    assert isinstance(t, ov.Adjustment) and (t.kind, t.base, t.points) == (
        "independent",
        92.0,
        None,
    )
    assert t.x is r.x and t.history is r.history and t.sigma0 == r.sigma0
    with pytest.raises(TypeError):
        r.extend(RelativeResult, no_such_field=1)
