"""Block.copy is a deep copy: equal to copy.deepcopy's, sharing no mutable part."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

import orientviz as ov


def _same(a, b, path="block"):
    assert type(a) is type(b), path
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), path
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}[{k!r}]")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    else:
        assert a == b, path


def test_copy_equals_deepcopy_and_shares_nothing_mutable():
    block = ov.simulate_block(2, 4, rng=np.random.default_rng(3)).block
    block.cameras.model = [{"model": "forward", "free": ["c"]}] * len(block.cameras.ids)
    block.meta["note"] = ["a"]
    out = block.copy()
    _same(out, copy.deepcopy(block))
    for table in ("cameras", "images", "points", "observations"):
        for f in dataclasses.fields(getattr(block, table)):
            value = getattr(getattr(block, table), f.name)
            if isinstance(value, (list, np.ndarray, dict)):
                assert getattr(getattr(out, table), f.name) is not value, f"{table}.{f.name}"
    assert out.cameras.model[0] is not block.cameras.model[0]
    assert out.meta["note"] is not block.meta["note"]
    out.points.ids[0] = "changed"
    assert block.points.ids[0] != "changed"
