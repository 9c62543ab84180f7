"""The virtual plotter: turn the dials, watch the y-parallaxes, let the desk computer pass.

:class:`VirtualPlotter` holds the logic (no ipywidgets, no matplotlib: tests call its
methods with slider values and look at the returned :class:`PlotterView`);
:func:`plotter_app` wires sliders for by, bz (mm) and ω, φ, κ (centesimal minutes), a
"one pass" button, the scheme and formula menus and the pass log to it, and redraws
the parallax field with :func:`orientviz.plot.relative.plot_parallax_field` (redrawn by
blitting: on the ipympl canvas, or into an Agg buffer shown as PNG in an Image widget).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..orientation.plotter import FORMULAS, AnalogPlotter, Readings, config_with, true_pair
from ..orientation.schemes import get_scheme
from ..plot.relative import blit_parallax_field, parallax_field_png, plot_parallax_field
from ..plot.style import subplots
from ..units import RHO_C

F64 = NDArray[np.float64]

#: Scheme menu: name → label.
SCHEME_CHOICES = {
    "gruber6": "Gruber, 6 points",
    "kovarik9": "Hallert/Kovarik, 9 points",
    "schmid3": "Schmid, 15 points",
}
#: Formula menu: name → label.
FORMULA_CHOICES = {
    "exact": "exact linearisation (least squares)",
    "kovarik9": "Kovarik 9-point closed form",
    "flat": "flat terrain (Hallert)",
    "preorient": "pre-orientation, round constants",
}


@dataclass
class PlotterView:
    """What the widget shows after an action.

    Attributes
    ----------
    X, Y, p : ndarray, shape (ny, nx)
        Parallax field: plan grid (machine mm) and p_y (mm).
    readings : Readings
        Noise-free readings at the current scheme's points.
    dials : dict
        ``by``, ``bz`` (mm), ``omega``, ``phi``, ``kappa`` (c) — slider values.
    error : dict
        The same, dials minus truth.
    log : list of str
        One line per pass.
    rms : float
        RMS parallax over the field, mm.
    """

    X: F64
    Y: F64
    p: F64
    readings: Readings
    dials: dict
    error: dict
    log: list[str]
    rms: float


def _as_dict(v: F64) -> dict:
    return {
        "by": float(v[0]),
        "bz": float(v[1]),
        "omega": float(v[2] * RHO_C),
        "phi": float(v[3] * RHO_C),
        "kappa": float(v[4] * RHO_C),
    }


class VirtualPlotter:
    """The logic behind the virtual plotter widget.

    Parameters
    ----------
    relief : float
        Relative relief of the random terrain.
    seed : int
        Seed of terrain, true orientation and reading noise.
    scheme : str
        Key of :data:`SCHEME_CHOICES`.
    formula : str
        Key of :data:`FORMULA_CHOICES`.
    sigma_by : float
        Reading noise of a pass, machine mm.
    grid : (int, int)
        Arrows along X and Y.
    """

    def __init__(
        self,
        relief: float = 0.10,
        seed: int = 0,
        scheme: str = "kovarik9",
        formula: str = "kovarik9",
        sigma_by: float = 0.005,
        grid: tuple[int, int] = (11, 9),
    ) -> None:
        self.grid = grid
        self.scheme = scheme
        self.formula = formula
        self.reset(relief, seed, sigma_by)

    # ---------------------------------------------------------------- actions
    def reset(
        self, relief: float | None = None, seed: int | None = None, sigma_by: float | None = None
    ) -> PlotterView:
        """New terrain and true orientation; dials at zero, log cleared."""
        self.relief = self.__dict__.get("relief", 0.1) if relief is None else float(relief)
        self.seed = self.__dict__.get("seed", 0) if seed is None else int(seed)
        self.sigma_by = (
            self.__dict__.get("sigma_by", 0.005) if sigma_by is None else float(sigma_by)
        )
        rng = np.random.default_rng(self.seed)
        cfg = config_with(relief=self.relief, sigma_by=self.sigma_by, sigma_z=4 * self.sigma_by)
        self.plotter = AnalogPlotter(true_pair(cfg, rng=rng), self.scheme, rng=rng)
        self.log: list[str] = []
        return self.view()

    def set_dials(
        self, by: float, bz: float, omega: float, phi: float, kappa: float
    ) -> PlotterView:
        """Set the dials from slider values: by, bz in mm; ω, φ, κ in centesimal minutes."""
        self.plotter.settings = np.array([by, bz, omega / RHO_C, phi / RHO_C, kappa / RHO_C], float)
        return self.view()

    def set_scheme(self, scheme: str) -> PlotterView:
        """Choose the point scheme read by a pass (a key of :data:`SCHEME_CHOICES`)."""
        self.plotter.scheme = get_scheme(scheme)
        self.scheme = scheme
        return self.view()

    def set_formula(self, formula: str) -> PlotterView:
        """Choose the formula of the desk computer (a key of :data:`FORMULA_CHOICES`)."""
        if formula not in FORMULAS:
            raise InputError(f"unknown formula {formula!r}; known: {', '.join(FORMULAS)}")
        self.formula = formula
        return self.view()

    def one_pass(self) -> PlotterView:
        """One numerical pass: read by and z, compute, apply; appends to the log."""
        rec = self.plotter.run_pass(self.formula)
        err = self.plotter.error
        self.log.append(
            f"pass {len(self.log) + 1} ({self.formula}, {self.plotter.scheme.name}): "
            f"rms p_y read {rec.rms_parallax * 1000:.0f} µm, largest rotation correction "
            f"{rec.max_rotation_c:.2f} c → remaining error {np.abs(err[2:]).max() * RHO_C:.2f} c"
        )
        return self.view()

    # ---------------------------------------------------------------- state
    def view(self) -> PlotterView:
        """The current field, readings, dials and log."""
        X, Y, p = self.plotter.parallax_field(*self.grid)
        r = self.plotter.read(noise=False)  # the pass itself reads with noise
        return PlotterView(
            X, Y, p, r,
            _as_dict(self.plotter.settings),
            _as_dict(self.plotter.error),
            list(self.log),
            float(np.sqrt(np.mean(p**2))),
        )  # fmt: skip


def _field_figure(figsize: tuple[float, float] = (7.0, 5.0)):
    """Figure and axes for the parallax field; ``live`` if the backend is a widget canvas.

    With ipympl (``%matplotlib widget``) the pyplot figure's canvas is itself a widget
    and is redrawn by blitting. Otherwise the figure gets a plain Agg canvas outside
    pyplot (nothing is displayed automatically) and is shown as PNG in an Image widget.
    """
    import matplotlib as mpl

    live = any(k in mpl.get_backend().lower() for k in ("ipympl", "widget"))
    if live:
        import matplotlib.pyplot as plt

        with plt.ioff():
            fig, ax = subplots(figsize=figsize, layout="none")
        return fig, ax, True
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="none")  # fixed layout: no relayout on updates
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot(), False


def plotter_app(relief: float = 0.10, seed: int = 0):
    """The ipywidgets app around :class:`VirtualPlotter`; returns the widget box."""
    import ipywidgets as W

    vp = VirtualPlotter(relief=relief, seed=seed)
    v0 = vp.view()
    sliders = {
        "by": W.FloatSlider(
            min=-5, max=5, step=0.01, description="by [mm]", continuous_update=False
        ),
        "bz": W.FloatSlider(
            min=-5, max=5, step=0.01, description="bz [mm]", continuous_update=False
        ),
        "omega": W.FloatSlider(
            min=-300, max=300, step=0.5, description="ω [c]", continuous_update=False
        ),
        "phi": W.FloatSlider(
            min=-300, max=300, step=0.5, description="φ [c]", continuous_update=False
        ),
        "kappa": W.FloatSlider(
            min=-300, max=300, step=0.5, description="κ [c]", continuous_update=False
        ),
    }
    scheme = W.Dropdown(
        options=[(v, k) for k, v in SCHEME_CHOICES.items()], value="kovarik9", description="scheme"
    )
    formula = W.Dropdown(
        options=[(v, k) for k, v in FORMULA_CHOICES.items()],
        value="kovarik9",
        description="formula",
    )
    button = W.Button(description="one pass (desk computer)")
    log = W.Textarea(value="", layout=W.Layout(width="95%", height="120px"), disabled=True)
    status = W.HTML()
    fig, ax, live = _field_figure()
    plot_parallax_field(v0, ax=ax)
    if live:  # ipympl: the canvas is a widget; redraw = blit
        out = fig.canvas
    else:  # inline: an Image widget fed with the blitted Agg buffer (no savefig)
        out = W.Image(format="png")
    busy = {"on": False}

    def show(v):
        if live:
            blit_parallax_field(ax, v)
        else:
            out.value = parallax_field_png(ax, v)
        log.value = "\n".join(v.log)
        status.value = f"rms parallax over the model: <b>{v.rms * 1000:.0f} µm</b>"

    def on_slider(_):
        if busy["on"]:
            return
        show(vp.set_dials(*(s.value for s in sliders.values())))

    def on_pass(_):
        v = vp.one_pass()
        busy["on"] = True
        try:
            for k, s in sliders.items():
                s.value = v.dials[k]
        finally:
            busy["on"] = False
        show(v)

    for s in sliders.values():
        s.observe(on_slider, names="value")
    scheme.observe(lambda ch: show(vp.set_scheme(ch["new"])), names="value")
    formula.observe(lambda ch: show(vp.set_formula(ch["new"])), names="value")
    button.on_click(on_pass)
    show(v0)
    controls = W.VBox([*sliders.values(), scheme, formula, button, status])
    box = W.VBox([W.HBox([controls, out]), log])
    box.figure = fig  # for tests and for saving a snapshot
    return box
