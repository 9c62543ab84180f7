"""Small helpers of the lessons-b checkers (until the shared ``_common`` exists)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def call(fn: Callable[..., Any] | None, *args: Any, **kwargs: Any) -> Any:
    """Call the student's function; an unfilled blank becomes "not written yet"."""
    if fn is None or fn is Ellipsis:
        raise AssertionError("not written yet: fill in the blank first")
    try:
        return fn(*args, **kwargs)
    except NotImplementedError:
        raise AssertionError("not written yet: replace `raise NotImplementedError`") from None


def as_array(value: Any, shape: tuple[int, ...] | None, what: str) -> np.ndarray:
    """The answer as a float array of the expected shape, or an AssertionError that says so."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise AssertionError(f"{what}: expected numbers, got {type(value).__name__}") from None
    if shape is not None and a.shape != shape:
        raise AssertionError(f"{what}: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise AssertionError(f"{what}: contains NaN or inf")
    return a


def rel_err(a: Any, b: Any) -> float:
    """Largest absolute difference relative to the size of ``b`` (never divides by ~0)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def ok(message: str) -> None:
    """Report success the same way in every lesson."""
    print("✓ " + message)
