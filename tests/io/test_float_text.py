"""The bulk writer of float columns (io.float_text) writes the text ``json.dumps`` writes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from orientviz.io.float_text import MIN_BULK, float_column_json
from orientviz.io.jsonio import dumps_json


def _same(values: list[float]) -> None:
    assert float_column_json(values) == json.dumps(values, allow_nan=False)


@pytest.mark.parametrize("digits", [1, 3, 6, 12, 15, 17])
def test_rounded_values_in_every_decade(digits):
    """Values with few or many significant digits from 1e-12 to 1e19, both signs."""
    rng = np.random.default_rng(digits)
    for decade in range(-12, 20):
        x = rng.uniform(-1.0, 1.0, 300) * 10.0**decade
        _same([float(f"{v:.{digits}g}") for v in x])


def test_boundaries_zeros_and_whole_numbers():
    """Powers of ten and their neighbours (the edges of fixed notation), signed zeros,
    whole numbers (".0"), 2**53, subnormal and largest doubles."""
    edges = [0.0, -0.0, 1.0, -1.0, 0.5, 0.1, 0.3, 1 / 3, 2.0**53, 5e-324, 1.7976931348623157e308]
    for k in range(-10, 23):
        p = 10.0**k
        edges += [p, -p, np.nextafter(p, 0.0), np.nextafter(p, np.inf)]
        edges += [float(f"{p * (1 - 1e-15):.15g}"), float(f"{p * (1 + 1e-14):.15g}")]
    _same([float(v) for v in edges] * 3)
    _same([123456789012345.0, 999999999999999.0, 1e15, 1e16, 1e-4, 1e-5] * 20)


def test_constant_columns():
    for v in (1.0, -0.0, 0.0, 2.5e-7, 1e300):
        _same([v] * 100)
    _same([0.0] * 50 + [-0.0] * 50)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=MIN_BULK, max_size=300))
def test_any_finite_floats(values):
    _same(values)


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.floats(min_value=-1e6, max_value=1e6, allow_nan=False).map(lambda v: float(f"{v:.15g}")),
        min_size=MIN_BULK,
        max_size=300,
    )
)
def test_values_written_with_15_digits(values):
    """What the problem writer's columns hold (io.tables.json_numbers)."""
    _same(values)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), float("-inf")])
def test_not_finite_is_refused_as_json_dumps_refuses_it(bad):
    with pytest.raises(ValueError, match="not JSON compliant"):
        float_column_json([1.5] * 100 + [bad])


def test_document_text_unchanged():
    """dumps_json of a document with long float columns: json.dumps's text per line."""
    rng = np.random.default_rng(7)
    doc = {
        "points": {
            "id": [f"p{i}" for i in range(500)],
            "X": [float(f"{v:.15g}") for v in rng.normal(0, 1e3, 500)],
            "Y": rng.normal(0, 1, 500).tolist(),
            "sigma": [1.0] * 500,
        }
    }
    lines = dumps_json(doc).splitlines()
    for key, line in zip(doc["points"], lines[2:6]):
        assert line == f'  "{key}": ' + json.dumps(doc["points"][key], ensure_ascii=False) + (
            "," if key != "sigma" else ""
        )
