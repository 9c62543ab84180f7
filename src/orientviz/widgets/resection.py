"""Resection and intersection widgets: precision against geometry.

Logic in :func:`resection_state` and :func:`intersection_state` (testable without a
browser); the apps only wire sliders to them.
"""

from __future__ import annotations

import numpy as np

from ..adjust import Adjustment
from ..camera import project
from ..orientation.examples import ResectionExample, resection_example
from ..orientation.intersection import Intersection, intersect_points
from ..orientation.resection import resection
from ..plot.image import plot_correlations, plot_image
from ..plot.style import subplots
from ..rotation import matrix_from_opk
from ._app import control_app


def resection_state(
    n: int = 8, relief: float = 80.0, sigma_um: float = 5.0, seed: int = 1
) -> tuple[ResectionExample, Adjustment]:
    """Simulate a near-vertical image over n control points and resect it.

    Parameters
    ----------
    n : int
        Number of control points.
    relief : float
        Height range of the control, m.
    sigma_um : float
        Noise and a-priori σ of the image coordinates, µm.
    seed : int

    Returns
    -------
    (ResectionExample, Adjustment)
    """
    ex = resection_example(n, relief=relief, sigma=sigma_um / 1000, rng=np.random.default_rng(seed))
    return ex, resection(ex.image_points, ex.object_points, ex.c, sigma=sigma_um / 1000)


def intersection_state(
    base_height: float, *, height: float = 1500.0, c: float = 152.7, sigma_um: float = 5.0
) -> Intersection:
    """Precision of a point intersected from a vertical pair with base/height ratio B/H.

    Parameters
    ----------
    base_height : float
        B/H, e.g. 0.6 for 60 % overlap with a wide-angle camera.
    height : float
        Flying height above the point, m.
    c : float
        Principal distance, mm.
    sigma_um : float
        σ of the image coordinates, µm.

    Returns
    -------
    Intersection
        For three ground points: under the left image, in the middle, under the right.
    """
    B = base_height * height
    X0 = np.array([[-B / 2, 0.0, height], [B / 2, 0.0, height]])
    R = matrix_from_opk(np.zeros(2), np.zeros(2), np.zeros(2))
    X = np.array([[-B / 2, 0.0, 0.0], [0.0, 0.0, 0.0], [B / 2, 0.0, 0.0]])
    img, pt = np.repeat([0, 1], 3), np.tile([0, 1, 2], 2)

    xy = project(X[pt], X0[img], R[img], c)
    return intersect_points(xy, img, pt, X0, R, c, sigma=sigma_um / 1000)


def _describe_resection(state: tuple[ResectionExample, Adjustment]) -> str:
    res = state[1]
    s = res.std(a_posteriori=False)
    return (
        f"σ X0, Y0, Z0 = {s[0]:.3f}, {s[1]:.3f}, {s[2]:.3f} m (a priori)\n"
        f"σ̂0 = {res.sigma0:.2f}, redundancy {res.redundancy}"
    )


def _resection_figure(state: tuple[ResectionExample, Adjustment]):

    ex, res = state
    fig, (a1, a2) = subplots(1, 2, figsize=(7.0, 3.6))  # the book column: no down-scaling
    plot_image(ex.image_points, residuals=res.residuals_xy, ax=a1,
               title="control points and residuals")  # fmt: skip
    plot_correlations(res, ax=a2)
    fig.tight_layout()
    return fig


def resection_app():
    """ipywidgets app around :func:`resection_state`; returns the widget box."""
    import ipywidgets as W

    # from 4 points: with 3 the resection has up to four solutions and no redundancy, and the σ
    # printed would belong to whichever solution was found (lesson 04, "three points")
    n = W.IntSlider(value=8, min=4, max=40, description="points", continuous_update=False)
    relief = W.FloatSlider(value=80.0, min=0.0, max=600.0, step=10.0, description="relief [m]",
                           continuous_update=False)  # fmt: skip
    sig = W.FloatSlider(value=5.0, min=1.0, max=30.0, description="σ [µm]", continuous_update=False)
    seed = W.IntSlider(value=1, min=0, max=50, description="seed", continuous_update=False)
    return control_app(
        [n, relief, sig, seed], resection_state, _describe_resection, _resection_figure
    )


def intersection_app():
    """ipywidgets app: a B/H slider → σ of points intersected from a vertical pair."""
    import ipywidgets as W

    bh = W.FloatSlider(value=0.6, min=0.05, max=1.5, step=0.05, description="B/H",
                       continuous_update=False)  # fmt: skip
    sig = W.FloatSlider(value=5.0, min=1.0, max=30.0, description="σ [µm]", continuous_update=False)
    out = W.Output()

    def redraw(*_):
        res = intersection_state(bh.value, sigma_um=sig.value)
        s = res.std()
        with out:
            out.clear_output(wait=True)
            for name, row in zip(("under left image", "midway", "under right image"), s):
                print(f"{name:18s} σX = {row[0]:.3f}  σY = {row[1]:.3f}  σZ = {row[2]:.3f} m")

    for w in (bh, sig):
        w.observe(redraw, names="value")
    redraw()
    return W.VBox([bh, sig, out])
