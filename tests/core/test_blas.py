"""orientviz.blas: BLAS held to n threads inside the context, restored after it."""

import contextlib

import numpy as np
import scipy.linalg  # noqa: F401  its BLAS is loaded, as in every solve
from threadpoolctl import threadpool_info, threadpool_limits

from orientviz.blas import blas_threads


def _blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_the_limit_holds_inside_and_is_restored(monkeypatch):
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    with threadpool_limits(limits=2, user_api="blas"):  # the tests' processes run on one
        before = _blas_threads()
        assert before and all(n == 2 for n in before), before
        with blas_threads(1):
            assert _blas_threads() == [1] * len(before)
            np.ones((50, 50)) @ np.ones((50, 50))
        assert _blas_threads() == before


def test_none_and_an_environment_already_at_one_do_nothing(monkeypatch):
    assert isinstance(blas_threads(None), contextlib.nullcontext)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    assert isinstance(blas_threads(1), contextlib.nullcontext)
    monkeypatch.delenv("OPENBLAS_NUM_THREADS")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert not isinstance(blas_threads(1), contextlib.nullcontext)
