"""The one Gauss-Newton/LM loop (orientviz.adjust.iterate): damping, stopping, the hook."""

import numpy as np
import pytest

from orientviz.adjust import Damping, Evaluation, Step, StopRule, gauss_newton, iterate
from orientviz.errors import NotDeterminableError


class Exp:
    """l = exp(a t) at t = 0, 1, 2, 3 for a = 0.7 (from a0 = 0 the first Gauss-Newton step overshoots)."""

    def __init__(self):
        self.t = np.arange(4.0)
        self.l = np.exp(0.7 * self.t)
        self.solves = []

    def evaluate(self, a, jacobian):
        f = np.exp(a * self.t)
        r = self.l - f
        return Evaluation(float(r @ r), bool(np.all(np.isfinite(f))), (r, self.t * f))

    def solve(self, a, ev, lam, iteration):
        self.solves.append((iteration, lam))
        r, J = ev.data
        N = float(J @ J)
        if N == 0:
            raise NotDeterminableError("a not determinable", parameters=["a"])
        d = float(J @ r) / (N * (1 + lam))
        return Step(abs(d) * np.sqrt(N), np.array([d]), d)

    def apply(self, a, step):
        return a + step.data

    def snapshot(self, a):
        return np.array([a])


def test_fallback_damping_rejects_a_step_that_increases_the_cost_and_converges():
    p = Exp()
    run = iterate(p, 0.0, redundancy=3, damping=Damping("fallback"), stop=StopRule(1e-10))
    assert run.converged and run.state == pytest.approx(0.7, abs=1e-9)
    costs = [h.cost for h in run.history]
    assert all(b <= a * (1 + 1e-12) + 1e-12 for a, b in zip(costs, costs[1:]))
    # the first undamped step overshoots (cost up): it was retried damped
    assert p.solves[0] == (1, 0.0) and p.solves[1][1] >= 1e-4
    assert run.history[1].damping > 0


def test_pure_gauss_newton_takes_every_step_and_records_each_in_the_hook():
    p = Exp()
    seen = []
    run = iterate(p, 0.9, redundancy=3, damping=Damping("none"), stop=StopRule(1e-10),
                  callback=seen.append)  # fmt: skip
    assert run.converged and run.state == pytest.approx(0.7, abs=1e-9)
    assert [r.index for r in seen] == list(range(1, len(run.history)))
    assert all(lam == 0.0 for _, lam in p.solves)


def test_singular_first_system_raises_and_a_custom_rule_stops():
    class Flat(Exp):
        def evaluate(self, a, jacobian):
            ev = super().evaluate(a, jacobian)
            return Evaluation(ev.cost, True, (ev.data[0], 0 * ev.data[1]))

    with pytest.raises(NotDeterminableError):
        iterate(Flat(), 1.0, redundancy=3)
    run = iterate(Exp(), 0.9, redundancy=3, stop=StopRule(custom=lambda prev, cur: cur.index == 2))
    assert run.converged and len(run.history) == 3 and "custom" in run.reason


def test_gauss_newton_runs_the_loop_with_its_hook():
    t = np.arange(4.0)
    seen = []
    adj = gauss_newton(lambda x: (np.exp(x[0] * t), (t * np.exp(x[0] * t))[:, None]), [0.9],
                       np.exp(0.7 * t), callback=seen.append, tol=1e-10)  # fmt: skip
    assert adj.converged and adj.x[0] == pytest.approx(0.7, abs=1e-9)
    assert [r.index for r in seen] == [h.index for h in adj.history[1:]]


def test_trust_damping_keeps_lambda_positive_shrinks_by_3_and_grows_by_doubling_factors():
    p = Exp()
    run = iterate(p, 0.0, redundancy=3, damping=Damping("trust", lambda0=1e-4),
                  stop=StopRule(1e-10), max_iter=200)  # fmt: skip
    assert run.converged and run.state == pytest.approx(0.7, abs=1e-9)
    lams = [lam for _, lam in p.solves]
    assert min(lams) > 0  # never a pure Gauss-Newton step
    costs = [h.cost for h in run.history]
    assert all(b <= a for a, b in zip(costs, costs[1:]))
    for (it_a, a), (it_b, b) in zip(p.solves, p.solves[1:]):
        ratio = b / a
        if it_b == it_a:  # the same iteration again: the step was rejected, λ × 2, 4, 8 …
            assert ratio in (2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0)
        else:  # accepted: the next iteration starts from λ / 3
            assert ratio == pytest.approx(1 / 3) or b == pytest.approx(1e-16)


def test_relative_cost_decrease_stops_when_below_ftol():
    p = Exp()
    run = iterate(p, 0.0, redundancy=3, damping=Damping("trust", lambda0=1e3),
                  stop=StopRule(1e-14, ftol=1e-2), max_iter=500)  # fmt: skip
    assert run.converged and "decreased by less than 0.01" in run.reason
    c = [h.cost for h in run.history]
    assert c[-2] - c[-1] <= 1e-2 * c[-2]  # the stopping step
    assert all(a - b > 1e-2 * a for a, b in zip(c[:-2], c[1:-1]))  # none before it
    # the same run without ftol goes on to the corrections' rule
    q = Exp()
    longer = iterate(q, 0.0, redundancy=3, damping=Damping("trust", lambda0=1e3),
                     stop=StopRule(1e-14), max_iter=500)  # fmt: skip
    assert len(longer.history) > len(run.history)
