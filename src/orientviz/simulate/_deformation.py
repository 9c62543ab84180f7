"""Deformation fields of images and stereo models (Ackermann's Bild 6) as data.

Two kinds of fields, both plain arrays for plots (:mod:`orientviz.plot.deformation`) and
for the 3D viewer:

* :func:`image_field` — the image error Δxy (mm) on a grid over the format, of a
  systematic error model (:mod:`orientviz.simulate.systematic`) or of estimated additional
  parameters (:mod:`orientviz.bundle`).
* :func:`model_field` — the **model deformation** these image errors cause: a stereo model
  of two vertical images (normal case, base B along +X, flat ground at Z = 0) is
  oriented relatively from the *erroneous* image coordinates of a grid of ground points
  (dependent relative orientation: the left image and the base component bx fixed; by,
  bz, ω, φ, κ of the right image and all model points adjusted by the collinearity
  equations, :func:`orientviz.adjust.gauss_newton`), then fitted to the true points by a
  3D similarity transformation (:func:`orientviz.orientation.absolute.similarity_closed_form`).
  What is left, model minus truth (m), is the deformation that neither relative nor
  absolute orientation can remove: affinity and trapezoid in planimetry, twist and
  bending in height.

:func:`split_field` asks how much of an image error field an additional-parameter set
can describe at all: a least-squares fit of the set's terms (and of the six image
deformations the exterior orientation makes itself) on a grid over the format splits the
field into a described part and a remainder that no value of the parameters removes.

:func:`animate` and :func:`frames` turn two fields (without and with self-calibration)
into exaggerated point positions for a parameter t ∈ [0, 1]: t = 0 without, t = 1 with.

Conventions: image coordinates in mm, x along the flight direction; object frame in m,
X along the base, Z up; rotations R = R_ω R_φ R_κ ("opk"), radians.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust import gauss_newton
from ..bundle.model import eo_deformations
from ..camera import collinearity_jacobian, project
from ..errors import InputError
from ..orientation.absolute import similarity_closed_form
from .systematic import ImageError

F64 = NDArray[np.float64]

__all__ = [
    "FieldSplit",
    "ImageField",
    "ModelField",
    "animate",
    "frames",
    "image_field",
    "model_field",
    "model_fields",
    "split_field",
]


@dataclass
class ImageField:
    """An image deformation on a grid.

    Attributes
    ----------
    xy : ndarray, shape (N, 2)
        Grid positions in mm.
    d : ndarray, shape (N, 2)
        Error vectors in mm (add to the true coordinates to get the observed ones).
    shape : tuple of int
        Grid shape (rows, cols) so that ``xy.reshape(*shape, 2)`` is a meshgrid.
    name : str
        What produced it.
    """

    xy: F64
    d: F64
    shape: tuple[int, int]
    name: str = ""

    @property
    def max_um(self) -> float:
        """Largest abs(Δxy) in µm."""
        return float(np.max(np.hypot(self.d[:, 0], self.d[:, 1]), initial=0.0) * 1e3)

    @property
    def rms_um(self) -> float:
        """Root mean square of the vector lengths in µm."""
        return float(np.sqrt(np.mean(np.sum(self.d**2, axis=1))) * 1e3)


@dataclass
class ModelField:
    """A stereo-model deformation on a grid of ground points.

    Attributes
    ----------
    xyz : ndarray, shape (N, 3)
        True ground points in m (model frame = object frame of the normal case).
    d : ndarray, shape (N, 3)
        Deformation in m: oriented model (after the best 3D similarity) minus truth.
    shape : tuple of int
        Grid shape.
    base_m, height_m, scale : float
        Base B and flying height H in m, image scale number.
    name : str
        What produced it.
    """

    xyz: F64
    d: F64
    shape: tuple[int, int]
    base_m: float
    height_m: float
    scale: float
    name: str = ""

    def rms(self) -> F64:
        """RMS of the deformation in X, Y, Z (m)."""
        return np.sqrt(np.mean(self.d**2, axis=0))

    def rms_image_um(self) -> F64:
        """RMS in X, Y, Z converted to µm at image scale (divide by the scale number)."""
        return self.rms() / self.scale * 1e6


def _grid(half_x: tuple[float, float], half_y: float, n: int) -> tuple[F64, tuple[int, int]]:
    gx, gy = np.meshgrid(np.linspace(half_x[0], half_x[1], n), np.linspace(-half_y, half_y, n))
    return np.column_stack([gx.ravel(), gy.ravel()]), gx.shape


def _error_fn(error) -> Callable[[F64, NDArray[np.int64]], F64]:
    if error is None:
        return lambda xy, img: np.zeros_like(xy)
    if isinstance(error, tuple) and len(error) == 2:  # (ap_set, params): estimated field
        aps, p = error
        return lambda xy, img: aps.correction(xy, p)
    if callable(error):
        return error
    raise InputError("error: expected a callable (xy, image) -> Δxy or a tuple (ap_set, params)")


def image_field(error, *, image: int = 0, half_mm: float = 110.0, n: int = 11) -> ImageField:
    """The image deformation of an error model on an n × n grid over ±``half_mm``.

    Parameters
    ----------
    error : callable or (ap_set, params)
        ``error(xy_mm, image_index) -> Δxy_mm`` (a systematic error model), or an
        additional-parameter set with its estimated parameters (µm).
    image : int
        Image index passed to the error model (matters for per-image errors).
    half_mm : float
        Half the grid width in mm.
    n : int
        Grid points per side.
    """
    fn = _error_fn(error)
    xy, shape = _grid((-half_mm, half_mm), half_mm, int(n))
    d = np.asarray(fn(xy, np.full(xy.shape[0], int(image), np.int64)), float)
    return ImageField(xy, d, shape, getattr(error, "name", "estimated additional parameters"))


@dataclass
class FieldSplit:
    """An image error field split into what a parameter set describes and the rest.

    Attributes
    ----------
    name : str
        The field's and the set's names.
    params : ndarray, shape (k,)
        Least-squares values of the set's parameters in µm (the set's units).
    orientation : ndarray, shape (6,) or None
        Coefficients of the six exterior-orientation deformations (mm at u = x/b = 1,
        order of :func:`orientviz.bundle.model.eo_deformations`: shift x, shift y,
        scale, rotation, two projective tilts); None if they were not included.
    share : ndarray, shape (3,)
        Share of the field's sum of squares on the grid that the fit describes, for x,
        y and both coordinates (1 = all of it, 0 = none; NaN for a coordinate that is
        zero everywhere).
    rms_um : ndarray, shape (3,)
        RMS over the grid in µm of the field, the described part and the remainder
        (vector lengths).
    described, remainder : ImageError
        Error models (``(xy_mm, image) -> Δxy_mm``) of the described part (set terms
        plus orientation deformations) and of ``field − described``; defined everywhere,
        e.g. for :func:`model_field`.
    grid : ImageField
        The field on the grid used for the fit.
    """

    name: str
    params: F64
    orientation: F64 | None
    share: F64
    rms_um: F64
    described: ImageError
    remainder: ImageError
    grid: ImageField


def split_field(
    error,
    aps,
    *,
    orientation: bool = True,
    image: int = 0,
    half_mm: float = 110.0,
    n: int = 23,
) -> FieldSplit:
    """Split an image error field into the part a parameter set describes and the rest.

    The field Δ(x, y) is sampled on the n × n grid of :func:`image_field` and fitted by
    least squares (both coordinates at once) with the columns of ``aps.design`` and,
    with ``orientation=True``, the six image deformations that the exterior orientation
    produces itself (shifts, scale, rotation, projective tilts: every self-calibrating
    adjustment absorbs them without additional parameters). The remainder is what no
    value of the parameters can remove, e.g. a cubic term in x for Ebner's set.

    Parameters
    ----------
    error : callable
        Image error model ``error(xy_mm, image_index) -> Δxy_mm``
        (:mod:`orientviz.simulate.systematic`).
    aps : AdditionalParameters
        The parameter set (``design(xy) -> (n, 2, k)`` mm per µm), e.g. ``Ebner12()``.
    orientation : bool
        Also fit the six exterior-orientation deformations (scaled with u = x/b, b =
        ``aps.b`` if the set has one, else ``half_mm``).
    image : int
        Image index passed to the error model.
    half_mm : float
        Half the grid width in mm (default: the usable 23 cm format, ±110 mm).
    n : int
        Grid points per side (n ≥ 3).

    Returns
    -------
    FieldSplit
        Parameters, shares and the two parts as error models.

    Raises
    ------
    InputError
        If n < 3 or the error model is not callable.
    """
    if int(n) < 3:
        raise InputError(f"split_field: expected n ≥ 3 grid points per side, got {n}")
    if not callable(error):
        raise InputError("split_field: expected an error model (xy_mm, image) -> Δxy_mm")
    grid = image_field(error, image=image, half_mm=half_mm, n=int(n))
    b = float(getattr(aps, "b", half_mm))
    k = len(aps.names)

    def columns(xy: F64) -> F64:
        A = np.asarray(aps.design(xy), float)  # (N, 2, k) mm per µm
        if orientation:
            A = np.concatenate([A, eo_deformations(xy[:, 0] / b, xy[:, 1] / b)], axis=2)
        return A

    A = columns(grid.xy)
    coef, *_ = np.linalg.lstsq(A.reshape(-1, A.shape[2]), grid.d.reshape(-1), rcond=None)

    def fitted(xy: F64) -> F64:
        return columns(np.asarray(xy, float)) @ coef

    part = fitted(grid.xy)
    rest = grid.d - part
    with np.errstate(invalid="ignore", divide="ignore"):
        ss = np.sum(grid.d**2, axis=0)
        share = 1.0 - np.sum(rest**2, axis=0) / np.where(ss > 0, ss, np.nan)
        total = 1.0 - np.sum(rest**2) / np.sum(ss) if np.sum(ss) > 0 else np.nan
    rms = [float(np.sqrt(np.mean(np.sum(v**2, axis=1))) * 1e3) for v in (grid.d, part, rest)]
    fn = _error_fn(error)
    label = f"{getattr(error, 'name', 'image errors')} / {getattr(aps, 'name', 'set')}"
    described = ImageError(f"{label}: described", fitted)
    remainder = ImageError(
        f"{label}: remainder",
        lambda xy: fn(xy, np.full(xy.shape[0], int(image), np.int64)) - fitted(xy),
    )
    return FieldSplit(
        label,
        coef[:k],
        coef[k:] if orientation else None,
        np.array([*share, total]),
        np.array(rms),
        described,
        remainder,
        grid,
    )


def model_field(
    error,
    *,
    left: int = 0,
    right: int = 1,
    correction=None,
    c: float = 152.0,
    scale: float = 10_000.0,
    forward_overlap: float = 0.6,
    half_mm: float = 105.0,
    n: int = 7,
) -> ModelField:
    """The deformation of one stereo model caused by image errors (see module docstring).

    Parameters
    ----------
    error : callable or (ap_set, params) or None
        Image errors added to the true coordinates: ``error(xy_mm, image_index)``.
    left, right : int
        Image indices passed to the error model for the two images.
    correction : callable or (ap_set, params), optional
        Image corrections subtracted from the observed coordinates before the
        orientation — e.g. the estimated additional parameters of a self-calibrating
        adjustment, to show what deformation is *left* with self-calibration.
    c : float
        Principal distance in mm.
    scale : float
        Image scale number (H = c · scale).
    forward_overlap : float
        Forward overlap (B = (1 − overlap) · 230 mm · scale).
    half_mm : float
        Half the model width across the flight line in image mm; the model spans the
        overlap along the flight line with the same margin.
    n : int
        Grid points per side (n × n ground points; ≥ 3).
    """
    if n < 3:
        raise InputError(f"model_field: expected n ≥ 3 grid points per side, got {n}")
    err, cor = _error_fn(error), (None if correction is None else _error_fn(correction))
    H = c * scale / 1000.0
    b_mm = (1.0 - forward_overlap) * 230.0
    B = b_mm * scale / 1000.0
    margin = 115.0 - half_mm
    xs = ((b_mm - 115.0 + margin) * scale / 1000.0, (115.0 - margin) * scale / 1000.0)
    gxy, shape = _grid(xs, half_mm * scale / 1000.0, int(n))
    truth = np.column_stack([gxy, np.zeros(gxy.shape[0])])
    N = truth.shape[0]
    X0 = np.array([[0.0, 0.0, H], [B, 0.0, H]])
    ident = np.eye(3)
    obs = []
    for k, img in enumerate((left, right)):
        xy = project(truth, X0[k], ident, c)
        xy = xy + err(xy, np.full(N, img, np.int64))
        if cor is not None:
            xy = xy - cor(xy, np.full(N, img, np.int64))
        obs.append(xy)
    l = np.concatenate([o.reshape(-1) for o in obs])

    # unknowns: right image (Y0, Z0, ω, φ, κ), then the N points
    def equations(x):
        eo = np.array([B, x[0], x[1]]), x[2:5]
        pts = x[5:].reshape(N, 3)
        J = np.zeros((4 * N, 5 + 3 * N))
        fl, _, Jpl, _ = collinearity_jacobian(pts, X0[0], np.zeros(3), c)
        fr, Jer, Jpr, _ = collinearity_jacobian(pts, eo[0], eo[1], c)
        rows = np.arange(N)
        for k, Jp in enumerate((Jpl, Jpr)):
            for a in range(2):
                r = 2 * N * k + 2 * rows + a
                for q in range(3):
                    J[r, 5 + 3 * rows + q] = Jp[:, a, q]
        for a in range(2):
            J[2 * N + 2 * rows + a, 0:5] = Jer[:, a, 1:6]
        return np.concatenate([fl.reshape(-1), fr.reshape(-1)]), J

    x0 = np.concatenate([[0.0, H, 0.0, 0.0, 0.0], truth.reshape(-1)])
    adj = gauss_newton(equations, x0, l, 0.005, precision=False, context="model_field")
    if not adj.converged:
        raise InputError(f"model_field: relative orientation did not converge ({adj.reason})")
    pts = adj.x[5:].reshape(N, 3)
    T = similarity_closed_form(pts, truth)
    d = T.apply(pts) - truth
    name = getattr(error, "name", "image errors")
    if correction is not None:
        name += " (self-calibrated)"
    return ModelField(truth, d, shape, B, H, float(scale), name)


def model_fields(error, pairs: ArrayLike, *, correction=None, **options) -> list[ModelField]:
    """:func:`model_field` for every model (left, right) of a block, e.g. ``layout.models``.

    With per-image errors (:class:`~orientviz.simulate.systematic.PerGroup`, film
    deformation) every model gets its own deformation; the ground grid is the same
    normal-case grid for all (the field describes the images, not the terrain).
    """
    P = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return [
        model_field(error, left=int(a), right=int(b), correction=correction, **options)
        for a, b in P
    ]


def animate(without, with_, t: float, exaggeration: float = 1.0) -> F64:
    """Point positions for a frame t ∈ [0, 1] between two fields of the same grid.

    ``positions = base + exaggeration · ((1 − t) · d_without + t · d_with)`` where base is
    the grid (``xy`` of an :class:`ImageField`, ``xyz`` of a :class:`ModelField`).

    Parameters
    ----------
    without, with_ : ImageField or ModelField
        The fields without and with self-calibration (same grid).
    t : float
        0 = without, 1 = with; values in between interpolate linearly.
    exaggeration : float
        Factor applied to the deformation (e.g. 1000 to see µm on a mm-size image, or
        to see cm on a km-size model).
    """
    base_a = without.xy if isinstance(without, ImageField) else without.xyz
    base_b = with_.xy if isinstance(with_, ImageField) else with_.xyz
    if base_a.shape != base_b.shape or not np.allclose(base_a, base_b):
        raise InputError("animate: the two fields must be on the same grid")
    if not 0.0 <= float(t) <= 1.0:
        raise InputError(f"animate: expected t in [0, 1], got {t}")
    return base_a + exaggeration * ((1.0 - t) * without.d + t * with_.d)


def frames(without, with_, n_frames: int = 21, exaggeration: float = 1.0) -> F64:
    """All frames (n_frames, N, dim) of :func:`animate` for t = 0 … 1."""
    ts: ArrayLike = np.linspace(0.0, 1.0, int(n_frames))
    return np.stack([animate(without, with_, float(t), exaggeration) for t in ts])
