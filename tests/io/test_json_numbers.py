"""The numbers written to problem files: ``json_numbers`` equals ``json_number`` bit for bit.

:func:`orientviz.io.tables.json_numbers` rounds most values to 15 significant digits
without text (a scaled significand and one division); the result must be exactly the
float that the text ``"%.15g"`` reads back as (:func:`~orientviz.io.tables.json_number`),
the sign of zero included, for values near rounding ties, near powers of ten, far out
of the fast path's range and from unit conversions.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.io.tables import json_number, json_numbers


def _bits(values: list) -> list:
    return [None if v is None else np.float64(v).view(np.int64).item() for v in values]


def _values(rng: np.random.Generator, n: int) -> np.ndarray:
    spread = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-12, 18, n)
    # 16-digit decimals ending in 5 (ties of the 15th digit) and their neighbours
    tie = rng.integers(10**14, 10**15, n // 4) * 10 + 5
    tie = tie / 1e15 * 10.0 ** rng.integers(-10, 8, n // 4)
    ties = np.concatenate([tie, np.nextafter(tie, np.inf), np.nextafter(tie, -np.inf)])
    p10 = 10.0 ** np.arange(-20, 20)
    edges = np.concatenate(
        [p10, np.nextafter(p10, 0), np.nextafter(p10, np.inf), [9.999999999999995e14],
         [999999999999999.5, 99999999999999.95, 5e-324, 1e308, 0.0, -0.0]]
    )  # fmt: skip
    converted = rng.normal(0, 1000, n // 4).round(3) * 0.001 / 0.001  # mm ↔ m noise
    return np.concatenate([spread, ties, edges, converted, rng.integers(-(10**9), 10**9, 99)])


@pytest.mark.parametrize("seed", [1, 2])
def test_json_numbers_equal_the_text_round_trip(seed):
    values = _values(np.random.default_rng(seed), 20000)
    assert _bits(json_numbers(values)) == _bits([json_number(v) for v in values])


def test_non_finite_values_become_none_and_other_digits_use_the_text():
    values = np.array([np.nan, 1.0 / 3.0, np.inf, -np.inf, -0.0, 2.0 / 3.0])
    assert [json_numbers(values)[i] for i in (0, 2, 3)] == [None, None, None]
    for digits in (6, 15, 17):
        got = json_numbers(values, digits)
        assert _bits(got) == _bits([json_number(v, digits) for v in values])
    assert json_numbers(np.zeros(0)) == []
    assert str(json_numbers(values)[4]) == "-0.0"
