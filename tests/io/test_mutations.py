"""Random mutations of valid problem files never raise anything but orientviz's errors.

Loading must end in a Problem or an InputError (the adjustment errors are allowed too);
``orientviz solve`` must end with exit code 0, 2 or 3 and never raise.
"""

from __future__ import annotations

import argparse
import json
import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from orientviz.errors import AdjustmentError, InputError
from orientviz.io.datasets import dataset_path, list_datasets
from orientviz.io.problem import loads_problem

NAMES = list_datasets()
TEXTS = {n: dataset_path(n).read_text(encoding="utf-8") for n in NAMES}

REPLACEMENTS = [
    None, True, 0, -1, 1e308, -0.0, "NaN", "", "x", [], {}, [1.0], [None, None, None],
    {"id": "p"}, 3.5, "tie", "control", 10**400, -1e308, "9" * 20, [[[[]]]],
]  # fmt: skip


def _paths(node, prefix=()):
    """Every (path to a value) in a document."""
    out = [prefix]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _paths(v, prefix + (i,))
    return out


def _get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def _ids(doc):
    """Paths of all id-like string fields (id, image, point, camera)."""
    return [
        p
        for p in _paths(doc)
        if p and p[-1] in ("id", "image", "point", "camera") and isinstance(_get(doc, p), str)
    ] + [
        p + (i,)
        for p in _paths(doc)
        if p and p[-1] in ("id", "image", "point", "camera") and isinstance(_get(doc, p), list)
        for i in range(len(_get(doc, p)))
    ]


@st.composite
def mutated(draw):
    name = draw(st.sampled_from(NAMES))
    text = TEXTS[name]
    doc = json.loads(text)
    how = draw(
        st.sampled_from(
            ["delete", "replace", "nan", "truncate", "dup_id", "drop_row", "insert", "many"]
        )
    )
    rounds = draw(st.integers(2, 4)) if how == "many" else 1
    for _ in range(rounds):
        kind = (
            draw(st.sampled_from(["delete", "replace", "dup_id", "drop_row"]))
            if how == "many"
            else how
        )
        paths = [p for p in _paths(doc) if p]
        if kind == "delete":
            p = draw(st.sampled_from(paths))
            parent = _get(doc, p[:-1])
            del parent[p[-1]]
        elif kind == "replace":
            p = draw(st.sampled_from(paths))
            _get(doc, p[:-1])[p[-1]] = draw(st.sampled_from(REPLACEMENTS))
        elif kind == "dup_id":
            ids = _ids(doc)
            if len(ids) >= 2:
                a, b = draw(st.sampled_from(ids)), draw(st.sampled_from(ids))
                _get(doc, a[:-1])[a[-1]] = _get(doc, b)
        elif kind == "drop_row":
            lists = [p for p in paths if isinstance(_get(doc, p), list) and _get(doc, p)]
            p = draw(st.sampled_from(lists))
            lst = _get(doc, p)
            del lst[draw(st.integers(0, len(lst) - 1))]
        elif kind == "insert":
            dicts = [p for p in [()] + paths if isinstance(_get(doc, p), dict)]
            p = draw(st.sampled_from(dicts))
            _get(doc, p)[draw(st.sampled_from(["extra", "X", "sigma", "role", "x0"]))] = draw(
                st.sampled_from(REPLACEMENTS)
            )
    if how == "nan":
        nums = [p for p in _paths(doc) if isinstance(_get(doc, p), float) and p]
        p = draw(st.sampled_from(nums))
        _get(doc, p[:-1])[p[-1]] = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        return json.dumps(doc)  # writes NaN / Infinity tokens
    if how == "truncate":
        return text[: draw(st.integers(0, len(text) - 1))]
    return json.dumps(doc)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_files_raise_only_orientviz_errors(text):
    try:
        loads_problem(text, "mutated.json")
    except InputError as exc:
        line = str(exc)
        assert line.startswith("mutated.json: ") and "\n" not in line
    except AdjustmentError:
        pass


@settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(text=mutated())
def test_solve_on_mutated_files_never_raises(text, tmp_path_factory, capsys):
    from orientviz.report.solve import run_from_cli

    path = tmp_path_factory.mktemp("mut") / "mutated.json"
    path.write_text(text, encoding="utf-8")
    args = argparse.Namespace(file=str(path), method=None, json=True)
    code = run_from_cli(args)
    out, err = capsys.readouterr()
    assert code in (0, 2, 3, 4)  # 4: the model does not fit the data (report printed)
    assert "Traceback" not in err
    if code in (2, 4):
        assert err.count("\n") == 1 and str(path) in err
    if code in (0, 4):
        assert json.loads(out)["converged"] is True
