"""Systematic image errors for simulated blocks (the simulator's ``systematic=`` hook).

Ackermann (1974, §25) reports that practical aerial images almost always carry
systematic image errors with maximal values around 10 µm, and model deformations of
similar size, often of a few types that stay constant for a camera-film combination:
affinity and trapezoid in planimetry, twist and bending in height (his Bild 6).

Every error model here is a callable ``model(xy_mm (n, 2), image_index (n,)) -> Δxy_mm
(n, 2)``: the error *added* to the true image coordinates (x along the flight direction,
mm, origin at the principal point). Magnitudes are given in µm at a reference point of
the format, so that realistic sizes are the default. Models can be summed (``a + b``),
applied to groups of images only (:class:`PerGroup`, e.g. one camera per strip, or
different film rolls), and varied per image (:func:`film_deformation`).

Model-level errors are expressed as the *image* errors that produce them in every
stereo model of a strip (base b along x, the left image's point at x, the right's at
x − b): an x-error Δx(x, y) changes the x-parallax by Δx(x, y) − Δx(x − b, y), which the
intersection turns into a height error ``Δh ≈ (H / b) · Δp_x`` (H flying height, b image
base). So

* ``Δx = a · x² · y`` gives ``Δp_x = 2ab · y · (x − b/2)``: a **twist** of the model
  about its centre (:func:`model_twist`);
* ``Δx = a · x · y²`` gives ``Δp_x = ab · y²``: a **bending** across the flight line
  (:func:`model_bending`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

F64 = NDArray[np.float64]

#: Half the usable format of a 23 × 23 cm camera (mm): the reference for magnitudes.
HALF_FORMAT_MM: float = 110.0

__all__ = [
    "HALF_FORMAT_MM",
    "ImageError",
    "PerGroup",
    "affinity",
    "decentering",
    "film_deformation",
    "magnitude_um",
    "model_bending",
    "model_twist",
    "radial",
    "trapezoid",
    "typical",
    "unflatness",
]


def _xy(xy: ArrayLike) -> F64:
    a = np.asarray(xy, dtype=float)
    if a.ndim != 2 or a.shape[1] != 2:
        raise InputError(f"image coordinates: expected shape (n, 2) mm, got {a.shape}")
    return a


class _Base:
    """Shared behaviour: summation."""

    def __call__(self, xy: ArrayLike, image_index: ArrayLike) -> F64:  # pragma: no cover
        raise NotImplementedError

    def __add__(self, other: _Base) -> Sum:
        return Sum([self, other])


@dataclass
class ImageError(_Base):
    """An error field that is the same in every image.

    Attributes
    ----------
    name : str
        Readable name, e.g. ``"affinity 8 µm"``.
    field : callable
        ``field(xy (n, 2) mm) -> Δxy (n, 2) mm``.
    """

    name: str
    field: Callable[[F64], F64]

    def __call__(self, xy: ArrayLike, image_index: ArrayLike | None = None) -> F64:
        """Δxy in mm at the image coordinates ``xy`` (mm) of any image."""
        return self.field(_xy(xy))


@dataclass
class Sum(_Base):
    """The sum of several error models."""

    parts: list
    label: str = ""

    @property
    def name(self) -> str:
        return self.label or " + ".join(p.name for p in self.parts)

    def __call__(self, xy: ArrayLike, image_index: ArrayLike) -> F64:
        xy = _xy(xy)
        out = np.zeros_like(xy)
        for p in self.parts:
            out += p(xy, image_index)
        return out

    def __add__(self, other: _Base) -> Sum:
        return Sum([*self.parts, other])


@dataclass
class PerGroup(_Base):
    """Different error models for groups of images (cameras, strips, film rolls).

    Parameters
    ----------
    models : sequence of callables
        One error model per group (``None`` = no error for that group).
    group : array_like of int, shape (m,)
        Group index of every image (−1 = no error).
    """

    models: Sequence
    group: ArrayLike

    def __post_init__(self) -> None:
        self.group = np.asarray(self.group, dtype=np.int64).reshape(-1)
        if self.group.size and self.group.max() >= len(self.models):
            raise InputError(
                f"PerGroup: group index {int(self.group.max())} but only "
                f"{len(self.models)} models given"
            )

    @property
    def name(self) -> str:
        return "per group: " + "; ".join(getattr(m, "name", "none") for m in self.models)

    def __call__(self, xy: ArrayLike, image_index: ArrayLike) -> F64:
        xy = _xy(xy)
        img = np.asarray(image_index, dtype=np.int64).reshape(-1)
        g = self.group[img]
        out = np.zeros_like(xy)
        for k, mdl in enumerate(self.models):
            sel = g == k
            if mdl is not None and sel.any():
                out[sel] = mdl(xy[sel], img[sel])
        return out


# --------------------------------------------------------------------------- the types
def affinity(scale_um: float = 6.0, shear_um: float = 3.0, ref_mm: float = HALF_FORMAT_MM):
    """Affine image deformation (film shrinkage differing in x and y, non-orthogonal axes).

    ``Δx = a · x``, ``Δy = s · x`` with ``a = scale_um / ref``, ``s = shear_um / ref``:
    the x scale differs from the y scale, and the y axis is sheared.

    Parameters
    ----------
    scale_um, shear_um : float
        Errors in µm at distance ``ref_mm`` from the centre.
    ref_mm : float
        Reference distance in mm (default 110 mm, the edge of the usable format).
    """
    a, s = scale_um * 1e-3 / ref_mm, shear_um * 1e-3 / ref_mm

    def f(xy: F64) -> F64:
        return np.column_stack([a * xy[:, 0], s * xy[:, 0]])

    return ImageError(f"affinity {scale_um:.3g}/{shear_um:.3g} µm", f)


def trapezoid(um: float = 5.0, ref_mm: float = HALF_FORMAT_MM, axis: str = "x"):
    """Trapezoidal (projective) image deformation, e.g. a film not pressed flat at one side.

    ``Δx = p x², Δy = p x y`` (``axis="x"``: the image gets wider towards +x) or
    ``Δx = p x y, Δy = p y²`` (``axis="y"``), with ``p = um / ref²``: the second-order
    terms of a small projective change of the image plane.

    To first order such an error equals a small tilt of the image, so the orientation
    absorbs it: a stereo model of two images with the same trapezoid error shows no
    deformation (:func:`orientviz.simulate.model_field` gives ~0). It matters
    when it differs between the images (:class:`PerGroup`, film rolls).
    """
    p = um * 1e-3 / ref_mm**2
    if axis not in ("x", "y"):
        raise InputError(f"trapezoid: expected axis 'x' or 'y', got {axis!r}")

    def f(xy: F64) -> F64:
        x, y = xy[:, 0], xy[:, 1]
        if axis == "x":
            return np.column_stack([p * x * x, p * x * y])
        return np.column_stack([p * x * y, p * y * y])

    return ImageError(f"trapezoid {um:.3g} µm ({axis})", f)


def radial(um: float = 7.0, ref_mm: float = 150.0, k2_fraction: float = -0.5):
    """Symmetric radial distortion ``Δr = k1 r³ + k2 r⁵`` (Brown's k1, k2).

    Parameters
    ----------
    um : float
        Radial error in µm at radius ``ref_mm`` (default 150 mm, near the format corner).
    ref_mm : float
        Reference radius in mm.
    k2_fraction : float
        Share of the k2 term at the reference radius (the −0.5 default gives the
        typical profile that rises and falls again towards the corner).
    """
    total = um * 1e-3
    k2 = k2_fraction * total / ref_mm**5
    k1 = (total - k2 * ref_mm**5) / ref_mm**3

    def f(xy: F64) -> F64:
        r2 = np.sum(xy * xy, axis=1)
        return xy * (k1 * r2 + k2 * r2 * r2)[:, None]

    return ImageError(f"radial {um:.3g} µm", f)


def decentering(um: float = 3.0, ref_mm: float = 150.0, angle_deg: float = 30.0):
    """Decentering distortion (Brown–Conrady p1, p2) of a lens slightly off its axis.

    ``Δx = p1 (r² + 2x²) + 2 p2 x y``, ``Δy = p2 (r² + 2y²) + 2 p1 x y`` with
    ``(p1, p2) = P (cos α, sin α)``, ``P = um / ref²`` (µm at radius ``ref_mm``, mm⁻¹ units).
    """
    P = um * 1e-3 / ref_mm**2
    p1, p2 = P * np.cos(np.radians(angle_deg)), P * np.sin(np.radians(angle_deg))

    def f(xy: F64) -> F64:
        x, y = xy[:, 0], xy[:, 1]
        r2 = x * x + y * y
        return np.column_stack(
            [p1 * (r2 + 2 * x * x) + 2 * p2 * x * y, p2 * (r2 + 2 * y * y) + 2 * p1 * x * y]
        )

    return ImageError(f"decentering {um:.3g} µm", f)


def model_twist(um: float = 8.0, base_mm: float = 92.0, ref_mm: float = HALF_FORMAT_MM):
    """The image error ``Δx = a x² y`` that twists every stereo model about its centre.

    The x-parallax error is ``2ab · y · (x − b/2)``. ``um`` is the parallax error in µm at
    the model corner (y = ref, x − b/2 = b/2), i.e. ``a = um / (b² · ref)``.

    Parameters
    ----------
    um : float
        x-parallax error at the model corner in µm (height error ≈ H/b · that).
    base_mm : float
        Image base b in mm (92 mm for 60 % forward overlap of a 23 cm format).
    ref_mm : float
        Half the model width across the flight line, mm.
    """
    a = um * 1e-3 / (base_mm**2 * ref_mm)

    def f(xy: F64) -> F64:
        x, y = xy[:, 0], xy[:, 1]
        return np.column_stack([a * x * x * y, np.zeros_like(x)])

    return ImageError(f"model twist {um:.3g} µm", f)


def model_bending(um: float = 8.0, base_mm: float = 92.0, ref_mm: float = HALF_FORMAT_MM):
    """The image error ``Δx = a x y²`` that bends every stereo model across the flight line.

    The x-parallax error is ``ab · y²`` (constant along the model): ``um`` µm at the model
    edge y = ±ref, i.e. ``a = um / (b · ref²)``.
    """
    a = um * 1e-3 / (base_mm * ref_mm**2)

    def f(xy: F64) -> F64:
        x, y = xy[:, 0], xy[:, 1]
        return np.column_stack([a * x * y * y, np.zeros_like(x)])

    return ImageError(f"model bending {um:.3g} µm", f)


def unflatness(um: float = 10.0, c: float = 152.0, shape: str = "trough", half_mm: float = 115.0):
    """Film unflatness: the film surface stands off the image plane by h(x, y).

    A point on film raised by h (towards the lens) is imaged displaced radially by
    ``Δ = (x, y) · h / c``. Shapes (h in µm of height, scaled so that the largest image
    displacement in the usable format is ``um`` µm):

    * ``"trough"`` — film bent along the transport direction x, ``h ∝ 1 − 2 (x/a)²``
      (a = half the format): x-dependent scale of y, which the two images of a model see
      differently — a **y-parallax** the orientation cannot remove;
    * ``"dome"`` — a bulge in the middle, ``h ∝ 1 − (x² + y²)/a²``.

    Parameters
    ----------
    um : float
        Largest displacement in µm over the usable format (±110 mm).
    c : float
        Principal distance in mm.
    shape : {"trough", "dome"}
    half_mm : float
        a, half the format in mm.
    """
    if shape not in ("trough", "dome"):
        raise InputError(f"unflatness: expected shape 'trough' or 'dome', got {shape!r}")

    def h(xy: F64) -> F64:
        u, v = xy[:, 0] / half_mm, xy[:, 1] / half_mm
        return 1.0 - 2.0 * u * u if shape == "trough" else 1.0 - (u * u + v * v)

    g = np.linspace(-HALF_FORMAT_MM, HALF_FORMAT_MM, 23)
    gx, gy = np.meshgrid(g, g)
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    unit = np.max(np.hypot(*(grid * (h(grid) / c)[:, None]).T))
    k = um * 1e-3 / unit

    def f(xy: F64) -> F64:
        return xy * (k * h(xy) / c)[:, None]

    return ImageError(f"unflatness {um:.3g} µm ({shape})", f)


@dataclass
class _PerImageField(_Base):
    """A smooth random field per image: c_k cos/sin terms of low order, (m, K, 2) coefficients."""

    name: str
    coef: F64  # (m, K, 2)
    freqs: F64  # (K, 2) cycles per format
    phase: F64  # (m, K, 2)
    half: float

    def __call__(self, xy: ArrayLike, image_index: ArrayLike) -> F64:
        xy = _xy(xy)
        img = np.asarray(image_index, dtype=np.int64).reshape(-1)
        if img.size and (img.min() < 0 or img.max() >= self.coef.shape[0]):
            raise InputError(
                f"film deformation defined for {self.coef.shape[0]} images, got index {img.max()}"
            )
        u = xy / (2.0 * self.half)  # about −0.5 … 0.5 over the format
        arg = 2 * np.pi * (u @ self.freqs.T)  # (n, K)
        out = np.empty_like(xy)
        for d in range(2):
            out[:, d] = np.sum(self.coef[img, :, d] * np.cos(arg + self.phase[img, :, d]), axis=1)
        return out


def film_deformation(
    rng: np.random.Generator, n_images: int, rms_um: float = 2.0, order: int = 2
) -> _PerImageField:
    """Irregular film deformation: a smooth random field, different in every image.

    A sum of cosine waves with 1 … ``order`` cycles per format in x and y, random phases
    and amplitudes scaled to ``rms_um`` µm (root mean square per coordinate). Such errors
    cannot be absorbed by additional parameters shared by many images; they stay in σ0.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the random coefficients.
    n_images : int
        Number of images (the callable accepts image indices 0 … n_images − 1).
    rms_um : float
        Root mean square of each coordinate error in µm.
    order : int
        Highest number of cycles per format.
    """
    f = np.array([(i, j) for i in range(order + 1) for j in range(order + 1) if i + j > 0], float)
    K = f.shape[0]
    amp = rng.normal(0.0, 1.0, (n_images, K, 2)) / np.sqrt(K / 2.0)
    phase = rng.uniform(0.0, 2 * np.pi, (n_images, K, 2))
    return _PerImageField(
        f"film deformation {rms_um:g} µm rms", amp * rms_um * 1e-3, f, phase, HALF_FORMAT_MM
    )


def typical(strength_um: float = 10.0) -> Sum:
    """A typical camera-film combination of the 1970s: errors up to ~``strength_um`` µm.

    Affinity, trapezoid, radial and decentering distortion and a model twist in fixed
    proportions, scaled so that the largest error in the usable format (±110 mm) is
    about ``strength_um`` µm (Ackermann §25: "maximal values around 10 µm").
    """
    parts = [
        affinity(0.45, 0.2),
        trapezoid(0.35),
        radial(0.5),
        decentering(0.15),
        model_twist(0.3),
    ]
    base = Sum(parts)
    s = strength_um / max(magnitude_um(base), 1e-12)
    scaled = [
        affinity(0.45 * s, 0.2 * s),
        trapezoid(0.35 * s),
        radial(0.5 * s),
        decentering(0.15 * s),
        model_twist(0.3 * s),
    ]
    return Sum(
        scaled, f"typical {strength_um:g} µm (affinity, trapezoid, radial, decentering, twist)"
    )


def magnitude_um(model: Callable, half_mm: float = HALF_FORMAT_MM, n: int = 23) -> float:
    """Largest abs(Δxy) in µm of an error model over a grid on the usable format (image 0)."""
    g = np.linspace(-half_mm, half_mm, n)
    gx, gy = np.meshgrid(g, g)
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    d = np.asarray(model(xy, np.zeros(xy.shape[0], np.int64)), float)
    return float(np.max(np.hypot(d[:, 0], d[:, 1])) * 1e3)
