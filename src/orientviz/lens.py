"""Lens models: interior orientation and distortion as the user's software writes them.

Two directions meet users:

* **backward** (photogrammetry: DBAT, PhotoModeler, Australis): the distortion is a
  function of the *measured* image point; the corrected point must equal the pinhole
  projection. With measured coordinates m (mm, x right, y up, in the sensor frame),
  principal point (px, py) (here in that y-up frame; DBAT and PhotoModeler print py
  downwards) and z = A · (m − (px, py)) ::

      x̄ = z + z (K1 r² + K2 r⁴ + K3 r⁶) + (P1 (r² + 2 z_x²) + 2 P2 z_x z_y,
                                           P2 (r² + 2 z_y²) + 2 P1 z_x z_y),
      A = [[1 + as, sk], [0, 1]],   r² = z_x² + z_y²,

  and the observation equation is x̄ = −c · X_c,xy / X_c,z: DBAT's "model 3"
  (``res_euler_brown_1``: the affinity before the distortion), with K and P in the sign
  DBAT's report and PhotoModeler print (:func:`backward_ideal`). Every parameter, c and
  the principal point included, enters the equation itself: nothing is evaluated at
  observed coordinates where an unknown would scale it.
* **forward** (computer vision: OpenCV, COLMAP's OPENCV camera): the distortion acts on
  the *ideal* normalised point x_n = X_c,xy / X_c,z (OpenCV's camera looks along +z,
  y down) and the pixel follows: ``u = fx · x_d + cx``, ``v = fy · y_d + cy``,
  x_d = x_n (1 + k1 r² + k2 r⁴ + k3 r⁶) + (2 p1 x y + p2 (r² + 2x²),
  p1 (r² + 2y²) + 2 p2 x y) (:func:`forward_pixels`).

:func:`forward_from_backward` converts a backward model into the forward one that
reproduces it best over the image (least squares on a grid) and reports the largest
remaining difference in pixels. Units: mm in the image plane, px for pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

F64 = NDArray[np.float64]

#: Parameters of the backward model in their order (units: mm, mm, mm, 1, mm⁻², mm⁻⁴,
#: mm⁻⁶, mm⁻¹, mm⁻¹, 1). DBAT prints K1-K3 as mm^(-3), mm^(-5), mm^(-7) and P as mm^(-3).
BACKWARD = ("c", "px", "py", "as", "K1", "K2", "K3", "P1", "P2", "sk")
#: Parameters of the forward (OpenCV) model, px.
FORWARD = ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "p1", "p2")


@dataclass
class BackwardLens:
    """A camera in the backward (photogrammetric) model; see the module docstring."""

    c: float
    px: float
    py: float
    K: tuple[float, float, float] = (0.0, 0.0, 0.0)
    P: tuple[float, float] = (0.0, 0.0)
    aspect: float = 0.0  # "as": A = [[1 + as, sk], [0, 1]]
    skew: float = 0.0
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_vector(cls, p: ArrayLike) -> BackwardLens:
        v = np.asarray(p, dtype=float)
        return cls(
            v[0], v[1], v[2], tuple(v[4:7]), tuple(v[7:9]), v[3], v[9] if v.size > 9 else 0.0
        )

    def vector(self) -> F64:
        return np.array([self.c, self.px, self.py, self.aspect, *self.K, *self.P, self.skew])


def _affine(m: F64, lens: BackwardLens) -> tuple[F64, F64, F64, F64]:
    """x, y relative to the principal point and z = A · (x, y)."""
    x = m[:, 0] - lens.px
    y = m[:, 1] - lens.py
    return x, y, (1.0 + lens.aspect) * x + lens.skew * y, y


def backward_ideal(measured: ArrayLike, lens: BackwardLens) -> F64:
    """The corrected ("ideal") image point x̄ of measured points (n, 2) mm, see above."""
    m = np.asarray(measured, dtype=float)
    _, _, zx, zy = _affine(m, lens)
    r2 = zx * zx + zy * zy
    radial = lens.K[0] * r2 + lens.K[1] * r2 * r2 + lens.K[2] * r2 * r2 * r2
    p1, p2 = lens.P
    return np.column_stack(
        [
            zx + zx * radial + p1 * (r2 + 2 * zx * zx) + 2 * p2 * zx * zy,
            zy + zy * radial + p2 * (r2 + 2 * zy * zy) + 2 * p1 * zx * zy,
        ]
    )


def backward_ideal_jacobian(measured: ArrayLike, lens: BackwardLens) -> F64:
    """∂x̄/∂(px, py, as, K1, K2, K3, P1, P2, sk), shape (n, 2, 9), analytic (py: y up)."""
    m = np.asarray(measured, dtype=float)
    x, y, zx, zy = _affine(m, lens)
    r2 = zx * zx + zy * zy
    K1, K2, K3 = lens.K
    p1, p2 = lens.P
    a, s = 1.0 + lens.aspect, lens.skew
    radial = K1 * r2 + K2 * r2**2 + K3 * r2**3
    g = 2.0 * (K1 + 2 * K2 * r2 + 3 * K3 * r2**2)  # ∂radial/∂z = g · z
    # ∂x̄/∂z (2 × 2)
    a11 = 1 + radial + g * zx * zx + 6 * p1 * zx + 2 * p2 * zy
    a12 = g * zx * zy + 2 * p1 * zy + 2 * p2 * zx
    a21 = g * zx * zy + 2 * p2 * zx + 2 * p1 * zy
    a22 = 1 + radial + g * zy * zy + 6 * p2 * zy + 2 * p1 * zx
    n = m.shape[0]
    dz = np.zeros((n, 2, 9))  # ∂z/∂(px, py, as, …, sk)
    dz[:, 0, 0] = -a
    dz[:, 0, 1] = -s
    dz[:, 1, 1] = -1.0
    dz[:, 0, 2] = x
    dz[:, 0, 8] = y
    J = np.empty((n, 2, 9))
    J[:, 0] = a11[:, None] * dz[:, 0] + a12[:, None] * dz[:, 1]
    J[:, 1] = a21[:, None] * dz[:, 0] + a22[:, None] * dz[:, 1]
    J[:, 0, 3:6] = np.stack([zx * r2, zx * r2**2, zx * r2**3], axis=1)
    J[:, 1, 3:6] = np.stack([zy * r2, zy * r2**2, zy * r2**3], axis=1)
    J[:, 0, 6:8] = np.stack([r2 + 2 * zx * zx, 2 * zx * zy], axis=1)
    J[:, 1, 6:8] = np.stack([2 * zx * zy, r2 + 2 * zy * zy], axis=1)
    return J


def forward_pixels(xn: ArrayLike, f: ArrayLike) -> F64:
    """OpenCV's pixels of ideal normalised points ``xn`` (n, 2) (x right, y down) for the
    forward parameters ``f`` = (fx, fy, cx, cy, k1, k2, k3, p1, p2) px."""
    fx, fy, cx, cy, k1, k2, k3, p1, p2 = np.asarray(f, dtype=float)
    xn = np.asarray(xn, dtype=float)
    x, y = xn[:, 0], xn[:, 1]
    r2 = x * x + y * y
    rad = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.column_stack([fx * xd + cx, fy * yd + cy])


@dataclass
class Conversion:
    """A forward model fitted to a backward one: parameters (px), largest and RMS
    difference over the grid (px)."""

    forward: F64
    max_px: float
    rms_px: float


def forward_from_backward(
    lens: BackwardLens, pixel_mm: float, image_px: tuple[int, int], *, n: int = 41
) -> Conversion:
    """The OpenCV model that reproduces ``lens`` best over the image (least squares).

    Measured pixels on an n × n grid are corrected by the backward model to the ideal
    normalised points x̄ / c (OpenCV frame: y down); the nine forward parameters are fitted
    by Gauss-Newton so that they map those points back onto the measured pixels.
    """
    w, h = image_px
    u, v = np.meshgrid(np.linspace(0, w, n), np.linspace(0, h, n))
    pix = np.column_stack([u.ravel(), v.ravel()])
    measured = np.column_stack([pix[:, 0] * pixel_mm, -pix[:, 1] * pixel_mm])
    ideal = backward_ideal(measured, lens)
    xn = np.column_stack([ideal[:, 0], -ideal[:, 1]]) / lens.c
    f = np.array([lens.c / pixel_mm, lens.c / pixel_mm, lens.px / pixel_mm, lens.py / pixel_mm,
                  0, 0, 0, 0, 0], dtype=float)  # fmt: skip
    for _ in range(20):
        r = (forward_pixels(xn, f) - pix).ravel()
        J = np.empty((r.size, 9))
        for k in range(9):
            step = 1e-6 * max(abs(f[k]), 1e-3)
            g = f.copy()
            g[k] += step
            J[:, k] = ((forward_pixels(xn, g) - pix).ravel() - r) / step
        dx = np.linalg.lstsq(J, -r, rcond=None)[0]
        f += dx
        if np.all(np.abs(dx) <= 1e-12 * np.maximum(np.abs(f), 1.0)):
            break
    d = np.linalg.norm(forward_pixels(xn, f) - pix, axis=1)
    return Conversion(f, float(d.max()), float(np.sqrt(np.mean(d**2))))
