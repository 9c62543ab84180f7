"""The rank diagnosis: its cheap condition bound and the singular/regular decision."""

import numpy as np
import pytest

from orientviz.adjust.rank import (
    RANK_TOLERANCE,
    null_space_of_normal,
    raise_if_singular,
    scaled_condition_bound,
)
from orientviz.errors import NotDeterminableError


def _normal(rng, u: int, cond: float) -> np.ndarray:
    """A symmetric positive definite u×u matrix of about this scaled condition number,
    with rows and columns of very different sizes (as parameters in m and rad)."""
    Q, _ = np.linalg.qr(rng.standard_normal((u, u)))
    N = (Q * np.geomspace(1.0, 1.0 / cond, u)) @ Q.T
    s = np.exp(rng.uniform(-5, 5, u))
    return (N + N.T) / 2 * np.outer(s, s)


def _scaled_cond(N: np.ndarray) -> float:
    d = np.sqrt(np.diag(N))
    return float(np.linalg.cond(N / np.outer(d, d)))


@pytest.mark.parametrize("u", [1, 2, 3, 6, 20, 81])
def test_the_bound_lies_between_the_condition_number_and_u_to_the_1_5(u):
    rng = np.random.default_rng(u)
    for cond in (1.0, 1e3, 1e7):
        N = _normal(rng, u, cond)
        c, bound = _scaled_cond(N), scaled_condition_bound(N)
        assert c * (1 - 1e-9) <= bound <= u**1.5 * c * (1 + 1e-9)


def test_the_bound_is_infinite_when_cholesky_fails():
    assert scaled_condition_bound(np.array([[1.0, 2.0], [2.0, 1.0]])) == np.inf
    assert scaled_condition_bound(np.zeros((3, 3))) == np.inf


def test_singular_or_not_as_the_eigenvalues_say_near_the_tolerance():
    """raise_if_singular skips the eigenvalues when the bound proves a regular matrix: the
    decision must stay the eigenvalue rule's, also just either side of the tolerance."""
    rng = np.random.default_rng(7)
    decided = {True: 0, False: 0}
    for _ in range(400):
        u = int(rng.choice([2, 3, 6, 12]))
        N = _normal(rng, u, 10 ** rng.uniform(-1.5, 1.5) / RANK_TOLERANCE)
        singular = null_space_of_normal(N).shape[1] > 0
        names = [f"p{i}" for i in range(u)]
        if singular:
            with pytest.raises(NotDeterminableError):
                raise_if_singular(N, names)
        else:
            raise_if_singular(N, names)
        decided[singular] += 1
    assert min(decided.values()) > 50  # both sides of the tolerance were tried
