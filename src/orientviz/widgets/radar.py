"""Sliders for the ten parameters of a radar panorama image.

:class:`RadarSliders` holds the state and does all the work (testable without a
browser): the ten parameters in slider units (m, 10⁻⁶ for the scale, gon for angles),
the image of a Geier surface under them, its difference from the true image, and an
adjustment of a chosen task starting from the slider values. :func:`radar_app` wraps it
in ipywidgets; the sliders use ``continuous_update=False`` because a task solves.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError
from ..plot.radar import plot_image
from ..plot.style import subplots
from ..radar import geier1973 as G
from ..radar.orientation import adjust_image
from ..radar.ppi import PARAMS, RadarImage, project
from ..units import from_rad, to_rad

#: Slider ranges as (offset below, offset above, step) about the true value, slider units.
RANGES: dict[str, tuple[float, float, float]] = {
    "x0": (-200.0, 200.0, 1.0),
    "y0": (-200.0, 200.0, 1.0),
    "h": (-2000.0, 2000.0, 10.0),
    "m": (-5000.0, 5000.0, 10.0),  # in 10⁻⁶
    "X0": (-2000.0, 2000.0, 10.0),
    "Y0": (-2000.0, 2000.0, 10.0),
    "Z0": (-2000.0, 2000.0, 10.0),
    "phi": (-2.0, 2.0, 0.01),  # gon
    "omega": (-2.0, 2.0, 0.01),
    "kappa": (-2.0, 2.0, 0.01),
}
UNITS = {"x0": "m", "y0": "m", "h": "m", "m": "1e-6", "X0": "m", "Y0": "m", "Z0": "m",
         "phi": "gon", "omega": "gon", "kappa": "gon"}  # fmt: skip
#: Tasks the app can run: name → free parameters.
TASKS: dict[str, tuple[str, ...]] = {
    "calibration": ("x0", "y0", "h", "m", "kappa"),
    "exterior": ("X0", "Y0", "Z0", "phi", "omega", "kappa"),
    "all ten": PARAMS,
}


def _to_slider(name: str, v: float) -> float:
    if name == "m":
        return v * 1e6
    if name in ("phi", "omega", "kappa"):
        return float(from_rad(v, "gon"))
    return v


def _from_slider(name: str, v: float) -> float:
    if name == "m":
        return v * 1e-6
    if name in ("phi", "omega", "kappa"):
        return float(to_rad(v, "gon"))
    return v


@dataclass
class RadarSliders:
    """State of the radar lesson's sliders.

    Parameters
    ----------
    surface : str
        Geier surface key (:data:`orientviz.radar.geier1973.SURFACES`).
    image : {1, 2, 3}
        Which Fig. 7 image is the truth the observations come from.
    """

    surface: str = "fig7"
    image: int = 2
    values: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.image not in (1, 2, 3):
            raise InputError(f"expected image 1, 2 or 3, got {self.image}")
        self.truth = G.images()[self.image]
        self.points = G.points(self.surface)
        self.observed = G.image_coordinates(self.surface, self.image)
        if not self.values:
            self.reset()

    def reset(self) -> None:
        """Sliders back to the true values."""
        tv = self.truth.vector()
        self.values = {n: _to_slider(n, tv[i]) for i, n in enumerate(PARAMS)}

    def set(self, name: str, value: float) -> None:
        """Set one parameter in slider units (m, 10⁻⁶, gon)."""
        if name not in PARAMS:
            raise InputError(f"unknown parameter {name!r}; expected one of {PARAMS}")
        self.values[name] = float(value)

    def current(self) -> RadarImage:
        """The image the sliders describe."""
        p = [_from_slider(n, self.values[n]) for n in PARAMS]
        return RadarImage.from_vector(p, self.truth.sequence)

    def image_coordinates(self) -> np.ndarray:
        """Image coordinates (m) of the 25 points under the slider values."""
        return project(self.points, self.current())

    def discrepancies(self) -> np.ndarray:
        """Slider image minus the observed (rounded) image, m (25, 2)."""
        return self.image_coordinates() - self.observed

    def solve(self, task: str = "exterior", **engine: Any):
        """Adjust ``task``'s parameters starting from the slider values.

        Returns the :class:`~orientviz.adjust.result.Adjustment`; the sliders move to
        the estimate.
        """
        if task not in TASKS:
            raise InputError(f"unknown task {task!r}; expected one of {', '.join(TASKS)}")
        res = adjust_image(
            self.points, self.observed, self.current(), TASKS[task], task=task, **engine
        )
        est = res.image.vector()
        for i, n in enumerate(PARAMS):
            self.values[n] = _to_slider(n, est[i])
        return res

    def slider_spec(self) -> dict[str, tuple[float, float, float, float]]:
        """name → (min, max, step, value) in slider units, about the true values."""
        tv = self.truth.vector()
        out = {}
        for i, n in enumerate(PARAMS):
            lo, hi, step = RANGES[n]
            t = _to_slider(n, tv[i])
            out[n] = (t + lo, t + hi, step, self.values[n])
        return out


def arrow_scale(xy: np.ndarray, d: np.ndarray, share: float = 0.12) -> float:
    """A round exaggeration (1, 2 or 5 × 10^k) that draws the longest arrow at ``share`` of the image.

    Parameters
    ----------
    xy : ndarray, shape (n, 2)
        Image coordinates (image m).
    d : ndarray, shape (n, 2)
        Discrepancies (image m).
    share : float
        Length of the longest arrow as a share of the image's extent.

    Returns
    -------
    float
        The factor (1 when there are no discrepancies).
    """
    longest = float(np.max(np.linalg.norm(d, axis=1), initial=0.0))
    extent = float(np.max(np.ptp(xy, axis=0))) if len(xy) else 0.0
    if longest <= 0 or extent <= 0:
        return 1.0
    target = share * extent / longest
    k = 10.0 ** np.floor(np.log10(target))
    return float(max(f * k for f in (1.0, 2.0, 5.0) if f * k <= target))


def radar_app(state: RadarSliders | None = None):  # pragma: no cover - needs a kernel
    """An ipywidgets app: ten sliders, the image with discrepancy arrows, a solve button."""
    import ipywidgets as w
    import matplotlib.pyplot as plt

    state = state or RadarSliders()
    out = w.Output()
    sliders = {}
    for n, (lo, hi, step, val) in state.slider_spec().items():
        sliders[n] = w.FloatSlider(
            value=val, min=lo, max=hi, step=step, description=f"{n} [{UNITS[n]}]",
            continuous_update=False, readout_format=".4g",
        )  # fmt: skip
    task = w.Dropdown(options=list(TASKS), value="exterior", description="task")
    button = w.Button(description="adjust")
    info = w.HTML()

    def redraw(*_):
        with out:
            out.clear_output(wait=True)
            fig, ax = subplots(figsize=(6, 5))
            d = state.discrepancies()
            xy = state.image_coordinates()
            scale = arrow_scale(xy, d)
            plot_image(xy, state.current(), residuals=d, scale=scale, ax=ax, labels=False)
            ax.set_title(
                f"slider image vs observed: rms {np.sqrt((d**2).mean()):.2f} m (arrows × {scale:g})",
                fontsize=10,
            )
            plt.show()

    def on_slide(change):
        state.set(change["owner"].description.split()[0], change["new"])
        redraw()

    def on_solve(_):
        res = state.solve(task.value)
        for n, s in sliders.items():
            s.unobserve(on_slide, "value")
            s.value = state.values[n]
            s.observe(on_slide, "value")
        info.value = f"<code>{res.summary()}</code>"
        redraw()

    for s in sliders.values():
        s.observe(on_slide, "value")
    button.on_click(on_solve)
    redraw()
    return w.HBox([w.VBox([*sliders.values(), task, button, info]), out])
