"""The virtual plotter widget's logic, without a browser, and its figures."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.units import RHO_C
from orientviz.widgets.plotter import FORMULA_CHOICES, SCHEME_CHOICES, VirtualPlotter


def test_dials_at_the_truth_clear_the_field():
    vp = VirtualPlotter(relief=0.1, seed=1)
    e = vp.plotter.pair.elements
    v = vp.set_dials(e[0], e[1], e[2] * RHO_C, e[3] * RHO_C, e[4] * RHO_C)
    assert v.rms < 1e-9
    assert max(abs(x) for x in v.error.values()) < 1e-9
    # slider units: mm and centesimal minutes
    assert v.dials["omega"] == pytest.approx(e[2] * RHO_C)


def test_turning_omega_changes_edge_parallaxes_most():
    vp = VirtualPlotter(relief=0.0, seed=2)
    e = vp.plotter.pair.elements
    base = vp.set_dials(e[0], e[1], e[2] * RHO_C, e[3] * RHO_C, e[4] * RHO_C)
    v = vp.set_dials(e[0], e[1], e[2] * RHO_C + 10, e[3] * RHO_C, e[4] * RHO_C)
    dp = v.readings.parallax - base.readings.parallax
    r = v.readings
    edge = np.abs(r.Y) > 0
    # 10 c of ω: p = −Z(1 + k²)dω at the edges, −Z dω on the base line (Z ≈ −366 mm)
    assert np.all(np.abs(dp[edge]) > np.abs(dp[~edge]).max())


def test_passes_converge_and_log():
    vp = VirtualPlotter(relief=0.1, seed=3)
    start = vp.view().rms
    for _ in range(3):
        v = vp.one_pass()
    assert len(v.log) == 3 and v.log[0].startswith("pass 1")
    assert v.rms < start / 100
    assert max(abs(v.error[k]) for k in ("omega", "phi", "kappa")) < 2.0


@pytest.mark.parametrize("scheme", list(SCHEME_CHOICES))
@pytest.mark.parametrize("formula", list(FORMULA_CHOICES))
def test_every_scheme_and_formula_or_a_clear_error(scheme, formula):
    vp = VirtualPlotter(seed=4)
    vp.set_scheme(scheme)
    vp.set_formula(formula)
    if formula == "kovarik9" and scheme != "kovarik9":
        with pytest.raises(ov.InputError, match="9-point"):
            vp.one_pass()
        return
    v = vp.one_pass()
    assert v.readings.scheme.name == scheme
    assert len(v.readings.parallax) == vp.plotter.scheme.n


def test_unknown_formula():
    with pytest.raises(ov.InputError):
        VirtualPlotter().set_formula("guess")


def test_reset_clears_log_and_dials():
    vp = VirtualPlotter(seed=5)
    vp.one_pass()
    v = vp.reset(relief=0.2, seed=6)
    assert v.log == [] and all(x == 0 for x in v.dials.values())


def test_figures(tmp_path):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    from orientviz.plot import relative as pr

    vp = VirtualPlotter(seed=7)
    fig = pr.plot_parallax_field(vp.view())
    ax = fig.axes[0]
    q = ax._orientviz_parallax["quiver"]
    before = np.array(q.V).copy()
    pr.update_parallax_field(ax, vp.one_pass())
    assert not np.allclose(before, q.V)
    assert "rms" in ax._orientviz_parallax["info"].get_text() and "µm" in ax.get_title()
    # the blitted redraw changes the arrows too
    pr.blit_parallax_field(ax, vp.one_pass())
    assert ax._orientviz_parallax["quiver"].get_animated()
    fig.savefig(tmp_path / "field.png")
    fig2 = pr.plot_pass_log(vp.plotter.history)
    assert fig2.axes[0].get_yscale() == "log"


def test_app_builds():
    pytest.importorskip("ipywidgets")
    pytest.importorskip("matplotlib").use("Agg")
    from orientviz.widgets.plotter import plotter_app

    box = plotter_app(seed=1)
    assert box.children
    image = box.children[0].children[1]  # inline backend: the field as a PNG Image widget
    assert image.format == "png" and bytes(image.value[:8]) == b"\x89PNG\r\n\x1a\n"
    slider = box.children[0].children[0].children[2]  # ω
    before = bytes(image.value)
    slider.value = 40.0
    assert bytes(image.value) != before


def _full_draw_rgba(view):
    from orientviz.plot import relative as pr
    from orientviz.widgets.plotter import _field_figure

    fig, ax, _ = _field_figure()
    pr.plot_parallax_field(view, ax=ax)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba()).copy()


def test_blitted_png_equals_a_full_draw():
    """The fast inline redraw shows exactly the pixels a fresh figure would."""
    pytest.importorskip("matplotlib").use("Agg")
    PIL = pytest.importorskip("PIL.Image")
    import io

    from orientviz.plot import relative as pr
    from orientviz.widgets.plotter import _field_figure

    vp = VirtualPlotter(seed=8)
    fig, ax, live = _field_figure()
    assert not live
    pr.plot_parallax_field(vp.view(), ax=ax)
    first = pr.parallax_field_png(ax, vp.view())
    for v in (vp.one_pass(), vp.set_dials(0.5, -0.3, 20.0, -15.0, 8.0), vp.set_scheme("schmid3")):
        png = pr.parallax_field_png(ax, v)
        shown = np.asarray(PIL.open(io.BytesIO(png)))
        np.testing.assert_array_equal(shown, _full_draw_rgba(v))
    assert png != first
    assert len(ax._orientviz_parallax["labels"]) == 15  # scheme change: new labels


def test_parallax_field_cache_matches_direct_computation():
    vp = VirtualPlotter(seed=9)
    vp.set_dials(0.2, 0.1, 30.0, -20.0, 10.0)
    X, Y, p = vp.plotter.parallax_field(5, 4)
    P = np.column_stack([X.ravel(), Y.ravel(), vp.plotter.pair.height(X, Y).ravel()])
    direct, _ = vp.plotter.parallax_at(P)
    np.testing.assert_allclose(p.ravel(), direct, rtol=0, atol=1e-12)
    vp.set_dials(0.0, 0.0, 0.0, 0.0, 0.0)  # same cached grid, new dials: new parallaxes
    assert not np.allclose(vp.plotter.parallax_field(5, 4)[2], p)
