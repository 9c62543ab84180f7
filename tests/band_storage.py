"""Test helper: a dense symmetric band matrix in LAPACK's lower band storage."""

from __future__ import annotations

import numpy as np


def lower_band(S: np.ndarray, kd: int) -> np.ndarray:
    """Rows d = 0…kd hold the d-th subdiagonal of S (n × n), left-aligned, zero-padded
    (the layout of ``scipy.linalg.cholesky_banded(ab, lower=True)``)."""
    n = S.shape[0]
    ab = np.zeros((kd + 1, n))
    for d in range(kd + 1):
        ab[d, : n - d] = np.diagonal(S, -d)
    return ab
