"""The shared app loop of the lesson widgets (widgets/_app.py), without a browser."""

from __future__ import annotations

import pytest

import orientviz as ov

W = pytest.importorskip("ipywidgets")
pytest.importorskip("matplotlib")


def _spy_app():
    import matplotlib.pyplot as plt

    from orientviz.widgets._app import control_app

    calls = {"compute": [], "describe": [], "draw": []}

    def compute(a, b):
        calls["compute"].append((a, b))
        if a < 0:
            raise ov.NotDeterminableError("negative a", parameters=["a"])
        return a * b

    def describe(state):
        calls["describe"].append(state)
        return f"state {state}"

    def draw(state):
        calls["draw"].append(state)
        return plt.figure()

    a = W.FloatSlider(value=1.0, min=-5, max=5)
    b = W.IntSlider(value=3, min=0, max=9)
    return control_app([a, b], compute, describe, draw), a, b, calls


def test_every_change_recomputes_with_the_current_values():
    app, a, b, calls = _spy_app()
    assert calls["compute"] == [(1.0, 3)] and calls["draw"] == [3.0]
    a.value = 2.0
    b.value = 4
    assert calls["compute"][1:] == [(2.0, 3), (2.0, 4)]
    assert calls["describe"][1:] == [6.0, 8.0] and calls["draw"][1:] == [6.0, 8.0]
    controls, figure = app.children
    assert list(controls.children[:2]) == [a, b] and isinstance(figure, W.Output)


def test_not_determinable_is_reported_and_not_drawn(capsys):
    app, a, _, calls = _spy_app()
    capsys.readouterr()
    a.value = -1.0
    assert calls["compute"][-1] == (-1.0, 3)
    assert calls["draw"] == [3.0]  # nothing drawn for the failed state
    assert "not determinable: negative a" in capsys.readouterr().out


@pytest.mark.parametrize("which", ["absolute", "resection"])
def test_lesson_apps_use_the_loop(which):
    from orientviz.widgets.absolute import absolute_app
    from orientviz.widgets.resection import resection_app

    app = absolute_app() if which == "absolute" else resection_app()
    controls = app.children[0].children[:-1]
    assert len(controls) == 4 and callable(app.redraw)
    controls[-2].value = controls[-2].value + 1  # seed (absolute) or σ (resection): redraws
