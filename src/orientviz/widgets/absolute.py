"""Absolute-orientation widget: control layout and noise → precision and residuals.

Logic in :func:`absolute_state` (testable without a browser); :func:`absolute_app`
wires a layout menu, a noise slider, a seed and a rigid/similarity switch to it.
"""

from __future__ import annotations

import numpy as np

from ..adjust import Adjustment
from ..orientation.absolute import similarity_transform
from ..orientation.examples import LAYOUTS, SimilarityExample, similarity_example
from ..plot.style import subplots
from ..plot.transform import plot_transform_residuals
from ..units import RHO_CC
from ._app import control_app


def absolute_state(
    layout: str = "corners", sigma_cm: float = 5.0, seed: int = 1, rigid: bool = False
) -> tuple[SimilarityExample, Adjustment]:
    """Simulate a model with control in ``layout`` and adjust it.

    Parameters
    ----------
    layout : str
        A key of :data:`orientviz.orientation.examples.LAYOUTS`.
    sigma_cm : float
        Noise (and a-priori σ) of the control coordinates, cm.
    seed : int
        Seed of the noise.
    rigid : bool
        6 parameters (scale fixed at 1 — wrong on purpose here, the model has scale 10)
        instead of 7.

    Returns
    -------
    (SimilarityExample, Adjustment)
    """
    ex = similarity_example(layout, sigma_cm / 100.0, rng=np.random.default_rng(seed))
    res = similarity_transform(
        ex.source, ex.target, sigma_target=sigma_cm / 100.0, rigid=rigid, point_ids=ex.ids
    )
    return ex, res


def precision_table(res: Adjustment) -> str:
    """Estimated parameters with a-priori standard deviations (σ0 = 1), in m, cc and ppm."""
    s = res.std(a_posteriori=False)
    rows = []
    for i, name in enumerate(res.names[:7]):
        if name in ("omega", "phi", "kappa"):
            rows.append(
                f"{name:6s} {res.x[i] * RHO_CC / 10000:12.5f} gon  ± {s[i] * RHO_CC:7.1f} cc"
            )
        elif name == "scale":
            rows.append(f"{name:6s} {res.x[i]:12.6f}      ± {s[i] * 1e6 / res.x[i]:7.1f} ppm")
        else:
            rows.append(f"{name:6s} {res.x[i]:12.3f} m    ± {s[i] * 100:7.2f} cm")
    rows.append(f"σ̂0 = {res.sigma0:.2f}, redundancy {res.redundancy}")
    return "\n".join(rows)


def _residual_figure(state: tuple[SimilarityExample, Adjustment]):

    fig, ax = subplots(figsize=(6, 5.5))
    plot_transform_residuals(state[1], ax=ax)
    return fig


def absolute_app():
    """ipywidgets app around :func:`absolute_state`; returns the widget box."""
    import ipywidgets as W

    layout = W.Dropdown(options=[(v, k) for k, v in LAYOUTS.items()], description="control")
    sigma = W.FloatSlider(value=5.0, min=0.5, max=30.0, step=0.5, description="σ [cm]",
                          continuous_update=False)  # fmt: skip
    seed = W.IntSlider(value=1, min=0, max=50, description="seed", continuous_update=False)
    rigid = W.Checkbox(value=False, description="rigid (scale fixed = 1)")
    return control_app(
        [layout, sigma, seed, rigid],
        absolute_state,
        lambda state: precision_table(state[1]),
        _residual_figure,
    )
