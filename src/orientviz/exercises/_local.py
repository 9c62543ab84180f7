"""Small helpers of lessons 01, 03, 06, 09, 10 (until the shared _common.py is used)."""

from __future__ import annotations

import numpy as np


def call(fn, *args):
    """Call the student's function; an unfilled blank is "not written yet"."""
    try:
        out = fn(*args)
    except NotImplementedError:
        raise AssertionError("not written yet: replace `raise NotImplementedError` by your code") from None
    if out is None:
        raise AssertionError("not written yet: the function returns None (did you forget `return`?)")
    return out


def _close(a, b, rtol, atol) -> bool:
    try:
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.shape == b.shape and bool(np.allclose(a, b, rtol=rtol, atol=atol))


def diagnose(got, want, wrong: dict, *, rtol: float = 0.0, atol: float = 0.0, what: str = "the answer") -> None:
    """Pass if ``got`` ≈ ``want``; else name the plausible mistake it matches, if any."""
    if _close(got, want, rtol, atol):
        return
    for label, value in wrong.items():
        if _close(got, value, rtol, atol):
            raise AssertionError(f"{what}: {label}")
    g = np.asarray(got, dtype=float) if np.ndim(got) or np.isscalar(got) else got
    raise AssertionError(f"{what}: expected {np.round(np.asarray(want, float), 9).tolist()}, got {np.round(g, 9).tolist()}")


def ok(message: str) -> None:
    """Print the success line of a check."""
    print("✓ " + message)
