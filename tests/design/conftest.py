"""Fixtures shared by the design tests."""

from __future__ import annotations

import pytest
from threadpoolctl import threadpool_limits


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    """BLAS on one thread: the designs are many small dense products."""
    with threadpool_limits(1, "blas"):
        yield
