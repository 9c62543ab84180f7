"""Rotation widget: sliders for ω, φ, κ move the image of a house on a ground grid.

The logic is :func:`rotation_state` (pure numpy, testable without a browser); the app
:func:`rotation_app` only wires ipywidgets sliders to it and redraws with
:func:`orientviz.plot.image.plot_image`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..camera import project
from ..orientation.examples import ground_grid, house
from ..plot.image import plot_image
from ..plot.style import subplots
from ..rotation import GIMBAL_TOLERANCE, check_sequence, matrix_from_opk, opk_from_matrix
from ..units import from_rad, to_rad

F64 = NDArray[np.float64]


@dataclass
class RotationState:
    """What the rotation widget shows for one slider setting.

    Attributes
    ----------
    R : ndarray, shape (3, 3)
        Rotation image → object.
    sequence : str
        Sequence of the slider angles ("opk" or "pok").
    angles_other : ndarray, shape (3,)
        The same R as ω, φ, κ of the *other* sequence, in ``unit``.
    unit : str
        Angle unit of the sliders.
    gimbal_lock : bool
        The secondary angle is at ±100 gon: only the sum/difference of the others counts.
    xy : ndarray, shape (n, 2)
        Image coordinates (mm) of the scene points; NaN behind the camera.
    edges : ndarray of int, shape (k, 2)
        Wireframe edges (house first, then grid).
    n_house_edges : int
    """

    R: F64
    sequence: str
    angles_other: F64
    unit: str
    gimbal_lock: bool
    xy: F64
    edges: NDArray[np.int64]
    n_house_edges: int


def rotation_state(
    omega: float,
    phi: float,
    kappa: float,
    *,
    unit: str = "gon",
    sequence: str = "opk",
    height: float = 150.0,
    c: float = 152.7,
) -> RotationState:
    """Project a house (40 × 60 × 32 m) and a 120 m ground grid seen from ``height`` m.

    Parameters
    ----------
    omega, phi, kappa : float
        Angles in ``unit``, rotation sequence ``sequence`` (R = R_ω R_φ R_κ for "opk",
        R = R_φ R_ω R_κ for "pok"), R turning image vectors into the object frame.
    unit : {"gon", "deg", "rad", "c", "cc"}, default "gon"
    sequence : {"opk", "pok"}, default "opk"
    height : float, default 150
        Height of the projection centre above the ground, m (above the house centre).
    c : float, default 152.7
        Principal distance, mm.

    Returns
    -------
    RotationState
    """
    seq = check_sequence(sequence)
    ang = np.array([to_rad(a, unit) for a in (omega, phi, kappa)])
    R = matrix_from_opk(*ang, seq)
    other = "pok" if seq == "opk" else "opk"
    a_other = np.array([from_rad(float(a), unit) for a in opk_from_matrix(R, other)])
    secondary = ang[1] if seq == "opk" else ang[0]
    locked = bool(abs(np.cos(secondary)) < max(GIMBAL_TOLERANCE, 1e-6))
    hp, he = house()
    gp, ge = ground_grid(60.0, 7)
    pts = np.vstack([hp, gp])
    edges = np.vstack([he, ge + hp.shape[0]])
    X0 = np.array([0.0, 0.0, height])
    w = (pts - X0) @ R[:, 2]
    xy = project(pts, X0, R, c)
    xy[w >= -1e-9] = np.nan  # behind the camera (or in its plane)
    return RotationState(R, seq, a_other, unit, locked, xy, edges, he.shape[0])


def describe(state: RotationState) -> str:
    """A few lines of text: R, and the angles of the other sequence."""
    other = "φ-ω-κ" if state.sequence == "opk" else "ω-φ-κ"
    a = state.angles_other
    lines = ["R (image → object) =", np.array2string(state.R, precision=4, suppress_small=True)]
    lines.append(f"same R in {other}: ω = {a[0]:.4f}, φ = {a[1]:.4f}, κ = {a[2]:.4f} {state.unit}")
    if state.gimbal_lock:
        primary = "ω" if state.sequence == "opk" else "φ"
        lines.append(
            f"gimbal lock: the secondary angle is ±100 gon — {primary} and κ turn about one axis, only {primary} ± κ is defined"
        )
    return "\n".join(lines)


def rotation_app(sequence: str = "opk"):
    """ipywidgets app: three sliders (gon) and a sequence toggle; returns the widget box."""
    import ipywidgets as W
    import matplotlib.pyplot as plt
    from IPython.display import display

    style = dict(min=-200.0, max=200.0, step=0.5, continuous_update=False)
    sliders = {
        "omega": W.FloatSlider(value=0.0, description="ω [gon]", **style),
        "phi": W.FloatSlider(value=0.0, description="φ [gon]", **style),
        "kappa": W.FloatSlider(value=0.0, description="κ [gon]", **style),
    }
    seq = W.ToggleButtons(options=[("ω-φ-κ", "opk"), ("φ-ω-κ", "pok")], value=sequence)
    out, text = W.Output(), W.Output()

    def redraw(*_):
        st = rotation_state(*(s.value for s in sliders.values()), sequence=seq.value)
        with out:
            out.clear_output(wait=True)
            fig, ax = subplots(figsize=(5, 5))
            plot_image(st.xy, edges=st.edges, ax=ax, title="image of a house (c = 152.7 mm)")
            display(fig)
            plt.close(fig)
        with text:
            text.clear_output(wait=True)
            print(describe(st))

    for s in list(sliders.values()) + [seq]:
        s.observe(redraw, names="value")
    redraw()
    return W.HBox([W.VBox(list(sliders.values()) + [seq, text]), out])
