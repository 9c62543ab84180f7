"""io.columns: answers about a long column kept inside one load or write, fresh outside."""

from __future__ import annotations

import numpy as np

from orientviz.io.columns import (
    MIN_SHARED,
    float_values,
    item_types,
    shared_columns,
    str_lengths,
)


def test_answers_equal_inside_and_outside():
    col = [float(i) / 7 for i in range(200)]
    outside = (item_types(col), float_values(col))
    with shared_columns():
        inside = (item_types(col), float_values(col))
    assert outside[0] == inside[0] == {float}
    assert np.array_equal(outside[1], inside[1])
    ids = [f"p{i}" * (i % 3 + 1) for i in range(100)]
    with shared_columns():
        kept = str_lengths(ids)
        assert str_lengths(ids) is kept
    assert kept.tolist() == [len(s) for s in ids] == str_lengths(ids).tolist()


def test_kept_inside_one_block_only():
    col = [1.5] * 100 + [2]
    with shared_columns():
        first = float_values(col)
        assert float_values(col) is first  # worked out once
        assert not first.flags.writeable  # callers copy to change it
        assert item_types(col) == {float, int}
    a, b = float_values(col), float_values(col)
    assert a is not b and a.flags.writeable  # outside: afresh each call
    col[0] = "x"  # a list changed between two loads is seen as it is now
    with shared_columns():
        assert item_types(col) == {float, int, str}


def test_short_lists_and_nesting():
    short = [1.0] * (MIN_SHARED - 1)
    long = [1.0] * MIN_SHARED
    with shared_columns():
        assert float_values(short) is not float_values(short)
        kept = float_values(long)
        with shared_columns():  # an inner block shares the outer one's answers
            assert float_values(long) is kept
        assert float_values(long) is kept


def test_a_writers_floats_are_known_as_the_list_would_answer():
    """json_numbers records its list's item types and values: the answers equal those
    worked out from the list itself (None where a value is not finite, -0.0 kept)."""
    from orientviz.io.tables import json_numbers

    rng = np.random.default_rng(3)
    arrays = [
        rng.normal(size=300) * 1e3,
        np.r_[rng.normal(size=150), np.nan, np.inf, -np.inf, -0.0, 0.0, 1e300, 1e-300],
        np.full(100, np.nan),
    ]
    for arr in arrays:
        with shared_columns():
            col = json_numbers(arr)
            known_types, known_values = item_types(col), float_values(col)
        assert known_types == frozenset(map(type, col))
        fresh = np.array(col, dtype=float)
        assert np.array_equal(known_values, fresh, equal_nan=True)
        assert np.array_equal(np.signbit(known_values), np.signbit(fresh))
