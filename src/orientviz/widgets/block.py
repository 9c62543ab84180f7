"""Block widget: overlap, control layout and method → errors of the adjusted block.

Logic in :func:`block_state` (testable without a browser); :func:`block_app` wires
sliders and menus to it (``continuous_update=False``: every change runs an adjustment).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..block import TIE
from ..bundle import bundle_adjust
from ..errors import OrientvizError
from ..plot.block import plot_block_layout, plot_error_vectors
from ..plot.style import subplots
from ..polynomial import polynomial_adjust
from ..simulate import SimulatedBlock, simulate_block
from ..stereo_models import independent_models

METHODS = {
    "independent models (7 p.)": "rigorous",
    "independent models (PAT-M)": "pat-m",
    "polynomial (3rd degree)": "polynomial",
    "bundle": "bundle",
}


@dataclass
class BlockState:
    """A simulated block, the adjusted coordinates and their errors."""

    sim: SimulatedBlock
    method: str
    xyz: np.ndarray
    rms: np.ndarray  # RMS error X, Y, Z (m) of the tie points
    sigma0: float
    seconds: float
    weak: tuple[str, ...] = ()  # the method's own words on weakly determined parts

    def summary(self) -> str:
        s = self.sim.spec
        text = (
            f"{self.method}: {s['strips']} × {s['images_per_strip']} images, q = "
            f"{100 * s['side_overlap']:.0f} %, control {s['control']}\n"
            f"RMS error of the tie points: X {self.rms[0]:.3f} m, Y {self.rms[1]:.3f} m, "
            f"Z {self.rms[2]:.3f} m  (σ̂0 = {self.sigma0:.2f}, {self.seconds:.2f} s)"
        )
        return "\n".join([text, *(f"weak: {w}" for w in self.weak)])


def block_state(
    strips: int = 3,
    images_per_strip: int = 8,
    *,
    side_overlap: float = 0.2,
    control: str = "perimeter",
    spacing: int = 4,
    method: str = "rigorous",
    seed: int = 1,
) -> BlockState:
    """Simulate a block (5 µm image noise) and adjust it with one method.

    Parameters
    ----------
    strips, images_per_strip : int
        Block size.
    side_overlap : float
        0.2 or 0.6.
    control : str
        Control layout of :func:`~orientviz.simulate.simulate_block`.
    spacing : int
        Control (and chain) spacing in bases.
    method : {"rigorous", "pat-m", "polynomial", "bundle"}
        Adjustment method.
    seed : int
        Seed of the simulation.

    Returns
    -------
    BlockState
    """
    sim = simulate_block(
        strips, images_per_strip, rng=np.random.default_rng(seed), extra=None,
        side_overlap=side_overlap, control=control, control_spacing=spacing, chain_spacing=spacing,
    )  # fmt: skip
    t = time.perf_counter()
    if method in ("rigorous", "pat-m"):
        res = independent_models(sim.block, method=method)
        xyz = res.points
    elif method == "polynomial":
        res = polynomial_adjust(sim.block, degree_xy=3, degree_z=3)
        xyz = res.points
    elif method == "bundle":
        res = bundle_adjust(sim.block, precision=False)
        xyz = res.x[res.groups["points"]].reshape(-1, 3)
    else:
        raise ValueError(f"expected a method out of {sorted(METHODS.values())}, got {method!r}")
    dt = time.perf_counter() - t
    tie = sim.block.points.role == TIE
    e = (xyz - sim.truth.points.xyz)[tie]
    rms = np.sqrt(np.nanmean(e**2, axis=0))
    weak = tuple(getattr(res, "weak", ()))
    return BlockState(sim, method, xyz, rms, float(res.sigma0), dt, weak)


def block_app():
    """ipywidgets app around :func:`block_state`; returns the widget box."""
    import ipywidgets as W
    import matplotlib.pyplot as plt
    from IPython.display import display

    cu = {"continuous_update": False}
    strips = W.IntSlider(value=3, min=1, max=6, description="strips", **cu)
    images = W.IntSlider(value=8, min=3, max=16, description="images/strip", **cu)
    q = W.Dropdown(options=[("20 %", 0.2), ("60 %", 0.6)], value=0.2, description="side overlap")
    control = W.Dropdown(options=["perimeter", "chains", "full", "corners"], description="control")
    spacing = W.IntSlider(value=4, min=1, max=8, description="spacing [b]", **cu)
    method = W.Dropdown(options=list(METHODS.items()), description="method")
    out, text = W.Output(), W.Output()

    def redraw(*_):
        with text:
            text.clear_output(wait=True)
            try:
                st = block_state(strips.value, images.value, side_overlap=q.value,
                                 control=control.value, spacing=spacing.value, method=method.value)  # fmt: skip
            except OrientvizError as exc:
                print(f"not possible: {exc}")
                return
            print(st.summary())
        with out:
            out.clear_output(wait=True)
            fig, axs = subplots(1, 2, figsize=(12, 4.5))
            plot_block_layout(st.sim, ax=axs[0], show_footprints=False)
            ctrl = st.sim.block.points.role != TIE
            plot_error_vectors(st.xyz, st.sim.truth.points.xyz, ax=axs[1], control=ctrl)
            display(fig)
            plt.close(fig)

    for w in (strips, images, q, control, spacing, method):
        w.observe(redraw, names="value")
    redraw()
    return W.HBox([W.VBox([strips, images, q, control, spacing, method, text]), out])
