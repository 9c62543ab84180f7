"""A simulated camera calibration: convergent, rolled images of a 3-D target field.

What a close-range self-calibration needs and an aerial block lacks: images from many
directions, turned about their axes (κ in steps of 90°), of a target field with depth.
The true camera is one of the exact models of :mod:`orientviz.bundle.model._lens` (backward or
forward), so :func:`orientviz.bundle.bundle_adjust` with a
:class:`~orientviz.bundle.LensModel` can recover it, and studies of bias and precision
have a truth to compare with. Scale: the field is ``field_m`` wide; the cameras stand
where it fills about 80 % of the format's shorter side, so a 7 mm phone camera and a
150 mm aerial camera give the same image geometry in units of their format.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..bundle.model import BACKWARD_NAMES, FORWARD_NAMES, evaluate_lens, normalised_block
from ..errors import InputError
from ..rotation import opk_from_matrix

F64 = NDArray[np.float64]

__all__ = ["SimulatedCalibration", "simulate_calibration"]


@dataclass
class SimulatedCalibration:
    """A simulated calibration block and its truth.

    Attributes
    ----------
    block : Block
        Start values (exterior and points perturbed by ``start_error``, the camera at
        its nominal c and principal point, no distortion) and noisy observations (mm).
    kind : str
        Lens model of the truth (``"backward"`` or ``"forward"``).
    camera : dict of str to float
        True parameters (names of :data:`orientviz.bundle.model._lens.BACKWARD_NAMES` or
        ``FORWARD_NAMES``, physical units).
    exterior : ndarray, shape (m, 6)
        True X0, Y0, Z0 (m), ω, φ, κ (rad).
    points : ndarray, shape (p, 3)
        True object points, m.
    """

    block: Block
    kind: str
    camera: dict[str, float]
    exterior: F64
    points: F64


def _look_at(X0: F64, target: F64, roll: float) -> F64:
    """R (image → object) of a camera at X0 looking at target, turned by roll (rad)."""
    d = target - X0
    z = -d / np.linalg.norm(d)  # the image's z axis points back, away from the object
    up = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    cr, sr = np.cos(roll), np.sin(roll)
    return np.column_stack([cr * x + sr * y, -sr * x + cr * y, z])


def _measured(kind: str, th: F64, nrm: F64) -> F64:
    """Image points whose model prediction equals them (noise-free observations)."""
    f = evaluate_lens(kind, np.tile(th, (nrm.shape[0], 1)), nrm, np.zeros_like(nrm), False)[0]
    if kind == "forward":
        return f
    m = th[1:3] + th[0] * nrm  # backward: solve x̄(m) = c·n (∂x̄/∂m ≈ I)
    for _ in range(60):
        g = evaluate_lens(kind, np.tile(th, (m.shape[0], 1)), nrm, m, False)[0] - m
        m = m + g
        if np.max(np.abs(g), initial=0.0) < 1e-13:
            break
    return m


def simulate_calibration(
    rng: np.random.Generator,
    *,
    c: float = 7.3,
    format_mm: tuple[float, float] = (7.2, 5.4),
    kind: str = "backward",
    camera: dict[str, float] | None = None,
    n_images: int = 12,
    grid: int = 9,
    sigma_mm: float = 0.0003,
    field_m: float = 1.0,
    depth: float = 0.2,
    start_error: tuple[float, float, float] = (0.01, 0.01, 0.005),
    n_control: int = 5,
) -> SimulatedCalibration:
    """Simulate a calibration of one camera on a target field.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness (noise, start errors, target heights).
    c : float
        True principal distance, mm (also the nominal one unless ``camera`` says "c").
    format_mm : (float, float)
        Sensor width and height, mm; the principal point is at its centre (x right, y up
        from the centre).
    kind : {"backward", "forward"}
        Lens model of the truth.
    camera : dict, optional
        True parameters beyond the nominal camera (e.g. ``{"K1": 4e-3, "c": 7.31}``);
        the block's camera keeps the nominal c = ``c`` and principal point (0, 0).
    n_images : int
        Images on a cone 45° about the field's normal, κ turned by 90° from one to the next.
    grid : int
        Targets per side of the square field; every second one is raised by up to
        ``depth`` × ``field_m``.
    sigma_mm : float
        σ of the image coordinates, mm (white noise).
    field_m, depth : float
        Field width (m) and relative depth of the raised targets.
    start_error : (float, float, float)
        σ of the start errors of projection centres (× the camera distance), angles
        (rad) and points (× ``field_m``).
    n_control : int
        Targets held fixed (the four corners and the centre, raised: ≤ 5).
    """
    if kind not in ("backward", "forward"):
        raise InputError(f"simulate_calibration: kind expected backward or forward, got {kind!r}")
    names = BACKWARD_NAMES if kind == "backward" else FORWARD_NAMES
    camera = dict(camera or {})
    bad = [k for k in camera if k not in names]
    if bad:
        raise InputError(f"simulate_calibration: unknown camera parameter {bad[0]!r}")
    th = np.array([camera.get(k, {"c": c}.get(k, 0.0)) for k in names])
    g = np.linspace(-field_m / 2, field_m / 2, grid)
    gx, gy = np.meshgrid(g, g)
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(grid * grid)])
    raised = (np.arange(grid * grid) % 2) == 1
    pts[raised, 2] = rng.uniform(0.2, 1.0, raised.sum()) * depth * field_m
    corners = [0, grid - 1, grid * (grid - 1), grid * grid - 1, (grid * grid) // 2]
    pts[corners[4], 2] = depth * field_m  # the centre raised: the control has depth
    dist = 1.25 * c * field_m / min(format_mm)  # the field fills ~80 % of the format
    eo = np.zeros((n_images, 6))
    for i in range(n_images):
        az = 2 * np.pi * i / n_images
        X0 = dist * np.array([np.sin(np.pi / 4) * np.cos(az), np.sin(np.pi / 4) * np.sin(az),
                              np.cos(np.pi / 4)])  # fmt: skip
        R = _look_at(X0, np.zeros(3), (i % 4) * np.pi / 2)
        eo[i, :3] = X0
        eo[i, 3:] = opk_from_matrix(R)
    im, pt = np.meshgrid(np.arange(n_images), np.arange(pts.shape[0]), indexing="ij")
    im, pt = im.ravel(), pt.ravel()
    nrm = normalised_block(eo[:, :3], eo[:, 3:], im, pts[pt], "opk", False)[0]
    xy = _measured(kind, th, nrm)
    inside = np.all(np.abs(xy) <= np.asarray(format_mm) / 2, axis=1)
    im, pt, xy = im[inside], pt[inside], xy[inside]
    xy = xy + rng.normal(0.0, sigma_mm, xy.shape)
    role = np.zeros(pts.shape[0], np.int64)
    role[corners[: max(0, min(n_control, 5))]] = 1
    se, sa, sp = start_error
    start_pts = pts + np.where(role[:, None] == 1, 0.0, rng.normal(0, sp * field_m, pts.shape))
    block = Block.from_arrays(
        camera_c=[c], camera_x0=[0.0], camera_y0=[0.0], camera_format_mm=format_mm,
        image_camera=np.zeros(n_images, np.int64),
        X0=eo[:, :3] + rng.normal(0, se * dist, (n_images, 3)),
        angles=eo[:, 3:] + rng.normal(0, sa, (n_images, 3)), xyz=start_pts, obs_image=im,
        obs_point=pt, obs_xy=xy, obs_sigma=sigma_mm, role=role, xyz_known=np.where(
            role[:, None] == 1, pts, np.nan), meta={"name": "simulated calibration"},
    )  # fmt: skip
    return SimulatedCalibration(block, kind, dict(zip(names, th.tolist())), eo, pts)
