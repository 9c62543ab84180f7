"""The camera's interior orientation and lens distortion inside the bundle's projection.

:class:`LensModel` is a parameter set for ``bundle_adjust(additional=...)`` that is not
a correction added to the projection but the projection itself. With the normalised
image point n = −(u, v)/w of the collinearity equations ((u, v, w) = Rᵀ(X − X0), image
plane at z = −c, x right, y up, mm) and per camera the parameters

    c, x0, y0 (mm), as (affinity), sk (shear), three radial and two decentring terms,

two models are offered, in the two directions users meet:

* ``kind="backward"`` — photogrammetry (DBAT's model 3, PhotoModeler, Australis): the
  distortion is a function of the *measured* point m; the corrected point must equal the
  pinhole point c·n. With z = [[1 + as, sk], [0, 1]] (m − (x0, y0)), r² = ‖z‖²::

      x̄(m) = z + z (K1 r² + K2 r⁴ + K3 r⁶)
               + (P1 (r² + 2 z_x²) + 2 P2 z_x z_y,  P2 (r² + 2 z_y²) + 2 P1 z_x z_y)
      v = c·n − x̄(m)                       (mm; K in mm⁻², mm⁻⁴, mm⁻⁶, P in mm⁻¹)

  (the same as :func:`orientviz.lens.backward_ideal`). The observation enters as the
  predicted value ``f = m + c·n − x̄(m)`` so that ``v = f − m``.
* ``kind="forward"`` — computer vision (OpenCV, COLMAP's OPENCV camera): the distortion
  acts on the ideal normalised point n = (x, y), r² = x² + y²::

      d = n (1 + k1 r² + k2 r⁴ + k3 r⁶) + (2 p1 x y + p2 (r² + 2x²),  p1 (r² + 2y²) + 2 p2 x y)
      f = (x0, y0) + c · [[1 + as, sk], [0, 1]] d          (mm; k, p dimensionless)

  In OpenCV's frame (y down) the same camera has fx = c(1 + as)/pixel, fy = c/pixel,
  the same k1–k3 and p2, and p1 of the opposite sign
  (:func:`orientviz.lens.forward_from_backward` converts a backward camera).

Every parameter — c and the principal point included — acts inside the equation: no
term is evaluated at an observed coordinate where an unknown scales it (except, by its
definition, the backward model's distortion of the measured point). The design (the
derivatives by the parameters) therefore changes with the iterate; the bundle
recomputes it at every linearisation (:meth:`BundleProblem.residuals`).

Units of the estimated corrections: one unit moves the image point by 1 µm at the
reference radius ``r0`` (the largest move over a ring of radius r0 about the principal
point), so estimates, σ and pseudo-observation σ read in µm for every parameter and the
normal equations are well scaled whatever the camera; :meth:`BoundLens.estimates` gives
the physical values. ``r0`` follows the camera: by default the RMS distance of the
camera's image points from its principal point (rounded to 2 digits).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ._lens_rays import lens_rays

F64 = NDArray[np.float64]
UM = 1e-3  # mm per µm

#: Parameters of the backward and the forward model, in their order.
BACKWARD_NAMES = ("c", "x0", "y0", "as", "sk", "K1", "K2", "K3", "P1", "P2")
FORWARD_NAMES = ("c", "x0", "y0", "as", "sk", "k1", "k2", "k3", "p1", "p2")
#: Units of the physical parameters (backward, forward).
UNITS = {
    "backward": ("mm", "mm", "mm", "1", "1", "mm⁻²", "mm⁻⁴", "mm⁻⁶", "mm⁻¹", "mm⁻¹"),
    "forward": ("mm", "mm", "mm", "1", "1", "1", "1", "1", "1", "1"),
}
KINDS = ("backward", "forward")

__all__ = ["LensModel", "BoundLens", "LensEstimates", "lens_model", "opencv_camera"]


def _names(kind: str) -> tuple[str, ...]:
    return BACKWARD_NAMES if kind == "backward" else FORWARD_NAMES


@dataclass
class LensModel:
    """An exact camera model for self-calibration in the bundle (see the module docstring).

    Parameters
    ----------
    kind : {"backward", "forward"}
        Photogrammetric (distortion of the measured point) or computer-vision (of the
        ideal point) model.
    free : sequence of str, optional
        Parameters estimated without a prior (default: all but the shear ``sk``).
    prior : dict of str to float, optional
        Parameters estimated with a pseudo-observation "= its given value ± σ"
        (σ in the parameter's physical unit, see :data:`UNITS`).
    values : dict of str to float or sequence, optional
        Given values of the distortion parameters (default 0) and of as, sk; c, x0, y0
        come from the block's cameras unless given here. Fixed parameters keep them. A
        sequence gives one value per camera of the block (in its order).
    r0 : float, optional
        Reference radius in mm (default: from the camera's image points).

    Parameters neither free nor with a prior are held fixed at their given values.
    """

    kind: str = "backward"
    free: tuple[str, ...] | None = None
    prior: dict[str, float] = field(default_factory=dict)
    values: dict[str, float] = field(default_factory=dict)
    r0: float | None = None
    name: str = "lens"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(
                f"lens model: kind expected one of {', '.join(KINDS)}, got {self.kind!r}"
            )
        all_names = _names(self.kind)
        free = tuple(all_names[:4] + all_names[5:]) if self.free is None else tuple(self.free)
        for what, keys in (("free", free), ("prior", self.prior), ("values", self.values)):
            bad = [k for k in keys if k not in all_names]
            if bad:
                raise InputError(
                    f"lens model ({self.kind}): {what}: unknown parameter {bad[0]!r}; "
                    f"expected some of {', '.join(all_names)}"
                )
        for k, s in self.prior.items():
            if not (np.isfinite(s) and s > 0):
                raise InputError(f"lens model: prior σ of {k}: expected a positive number, got {s}")
        for k, v in self.values.items():
            if not np.all(np.isfinite(np.asarray(v, dtype=float))):
                raise InputError(f"lens model: value of {k}: expected a finite number, got {v}")
        self.free = tuple(k for k in all_names if k in free and k not in self.prior)
        if self.r0 is not None and not (np.isfinite(self.r0) and self.r0 > 0):
            raise InputError(f"lens model: r0 expected a positive radius in mm, got {self.r0}")

    @property
    def all_names(self) -> tuple[str, ...]:
        """All ten parameters of the model, in order."""
        return _names(self.kind)

    @property
    def names(self) -> list[str]:
        """The estimated parameters (free or with a prior), in the model's order."""
        return [k for k in self.all_names if k in self.free or k in self.prior]

    def bind(self, block, xy: F64, image: NDArray[np.int64], group: NDArray[np.int64]) -> BoundLens:
        """The model on a block: given values, reference radius and scales per group.

        Parameters
        ----------
        block : Block
            Its cameras give c, x0, y0 (every group must use one camera's values).
        xy : ndarray, shape (n, 2)
            Measured image points (mm) of the rays that enter.
        image : ndarray of int, shape (n,)
            Image of each ray.
        group : ndarray of int, shape (m,)
            Parameter group of each image.
        """
        names = self.all_names
        G = int(group.max()) + 1 if group.size else 0
        cams = block.cameras
        theta0 = np.zeros((G, 10))
        r0 = np.zeros(G)
        ray_group = group[image]  # a ray is in group g where its image is
        # images and rays by group (stable: each group's in their own order), once
        by_group, img_bounds = _grouped(group, G)
        if G == 1:  # every ray, in its order
            rays_by_group, ray_bounds = slice(None), [0, ray_group.size]
        else:
            rays_by_group, ray_bounds = _grouped(ray_group, G)
        for g in range(G):
            members = by_group[img_bounds[g] : img_bounds[g + 1]]
            if members.size == 0:
                raise InputError(f"lens model: parameter group {g} has no image")
            cam = np.unique(block.images.camera[members])
            vals = {(cams.c[i], cams.x0[i], cams.y0[i]) for i in cam}
            if len(vals) > 1 and not {"c", "x0", "y0"} <= set(self.values):
                raise InputError(
                    f"lens model: parameter group {g} mixes cameras with different c, x0, y0 "
                    f"({', '.join(cams.ids[i] for i in cam)}); give each camera its own group"
                )
            i = cam[0]
            base = {"c": cams.c[i], "x0": cams.x0[i], "y0": cams.y0[i]}
            given = {k: (v[i] if np.ndim(v) else v) for k, v in self.values.items()}
            theta0[g] = [given.get(k, base.get(k, 0.0)) for k in names]
            if not theta0[g, 0] > 0:
                raise InputError(
                    f"lens model: camera {cams.ids[i]}: c expected > 0 mm, got {theta0[g, 0]}"
                )
            if self.r0 is not None:
                r0[g] = self.r0
            else:
                sel = rays_by_group[ray_bounds[g] : ray_bounds[g + 1]] if G > 1 else slice(None)
                d = xy[sel] - theta0[g, 1:3]
                rms = float(np.sqrt(np.mean(np.sum(d * d, axis=1)))) if d.size else 0.0
                r0[g] = float(f"{rms:.2g}") if rms > 0 else theta0[g, 0] / 2
        return BoundLens(self, theta0, r0)


def _grouped(keys: NDArray[np.int64], G: int) -> tuple[NDArray[np.int64], list[int]]:
    """The indices of ``keys`` (in [0, G)) sorted stably by key and where each key's run
    begins (G + 1 bounds): ``order[b[g]:b[g + 1]]`` = ``np.flatnonzero(keys == g)``."""
    k = keys.astype(np.int16) if G <= np.iinfo(np.int16).max else keys  # radix sort
    order = np.argsort(k, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(keys, minlength=G))]).tolist()
    return order, bounds


def _affinity_apply(a: F64, s: F64, v: F64) -> tuple[F64, F64]:
    return (1.0 + a) * v[:, 0] + s * v[:, 1], v[:, 1]


def evaluate_lens(kind: str, th: F64, nrm: F64, m: F64, jac: bool = True):
    """Predicted observations, ∂f/∂n and ∂f/∂θ of rays with per-ray parameters.

    Parameters
    ----------
    kind : {"backward", "forward"}
    th : ndarray, shape (n, 10)
        Physical parameters of each ray's camera, in the model's order.
    nrm : ndarray, shape (n, 2)
        Normalised image points −(u, v)/w.
    m : ndarray, shape (n, 2)
        Measured image points, mm.
    jac : bool
        Also return the derivatives.

    Returns
    -------
    f : ndarray, shape (n, 2)
        Predicted observation, mm (``v = f − m``).
    M : ndarray, shape (n, 2, 2) or None
        ∂f/∂n (mm); None without ``jac``.
    D : ndarray, shape (n, 2, 10) or None
        ∂f/∂θ (mm per physical unit); None without ``jac``.
    """
    c, x0, y0, a, s = th[:, 0], th[:, 1], th[:, 2], th[:, 3], th[:, 4]
    K1, K2, K3, P1, P2 = th[:, 5], th[:, 6], th[:, 7], th[:, 8], th[:, 9]
    if kind == "forward":  # OpenCV's p1 is the 2xy term of x (Brown's P1 the r² + 2x² one)
        P1, P2 = P2, P1
    n = nrm.shape[0]
    if kind == "backward":
        x, y = m[:, 0] - x0, m[:, 1] - y0
        zx, zy = (1.0 + a) * x + s * y, y
    else:
        zx, zy = nrm[:, 0], nrm[:, 1]
    r2 = zx * zx + zy * zy
    rad = K1 * r2 + K2 * r2 * r2 + K3 * r2 * r2 * r2
    dx = zx + zx * rad + P1 * (r2 + 2 * zx * zx) + 2 * P2 * zx * zy
    dy = zy + zy * rad + P2 * (r2 + 2 * zy * zy) + 2 * P1 * zx * zy
    f = np.empty((n, 2))
    if kind == "backward":
        f[:, 0] = m[:, 0] + c * nrm[:, 0] - dx
        f[:, 1] = m[:, 1] + c * nrm[:, 1] - dy
    else:
        ax, ay = _affinity_apply(a, s, np.column_stack([dx, dy]))
        f[:, 0] = x0 + c * ax
        f[:, 1] = y0 + c * ay
    if not jac:
        return f, None, None
    # ∂d/∂z (2 × 2) and ∂d/∂(K1, K2, K3, P1, P2)
    g = 2.0 * (K1 + 2 * K2 * r2 + 3 * K3 * r2 * r2)
    a11 = 1 + rad + g * zx * zx + 6 * P1 * zx + 2 * P2 * zy
    a12 = g * zx * zy + 2 * P1 * zy + 2 * P2 * zx
    a21 = g * zx * zy + 2 * P2 * zx + 2 * P1 * zy
    a22 = 1 + rad + g * zy * zy + 6 * P2 * zy + 2 * P1 * zx
    Dd = np.empty((n, 2, 5))
    Dd[:, 0, 0], Dd[:, 1, 0] = zx * r2, zy * r2
    Dd[:, 0, 1], Dd[:, 1, 1] = zx * r2 * r2, zy * r2 * r2
    Dd[:, 0, 2], Dd[:, 1, 2] = zx * r2**3, zy * r2**3
    Dd[:, 0, 3], Dd[:, 1, 3] = r2 + 2 * zx * zx, 2 * zx * zy
    Dd[:, 0, 4], Dd[:, 1, 4] = 2 * zx * zy, r2 + 2 * zy * zy
    D = np.zeros((n, 2, 10))
    M = np.zeros((n, 2, 2))
    if kind == "backward":
        M[:, 0, 0] = M[:, 1, 1] = c
        D[:, :, 0] = nrm
        # z = A (m − p): ∂z/∂x0 = (−(1 + a), 0), ∂z/∂y0 = (−s, −1), ∂z/∂a = (x, 0), ∂z/∂s = (y, 0)
        dz = np.zeros((n, 2, 4))
        dz[:, 0, 0] = -(1.0 + a)
        dz[:, 0, 1], dz[:, 1, 1] = -s, -1.0
        dz[:, 0, 2] = x
        dz[:, 0, 3] = y
        D[:, 0, 1:5] = -(a11[:, None] * dz[:, 0] + a12[:, None] * dz[:, 1])
        D[:, 1, 1:5] = -(a21[:, None] * dz[:, 0] + a22[:, None] * dz[:, 1])
        D[:, :, 5:] = -Dd
    else:
        # f = p + c A d: ∂f/∂n = c A ∂d/∂n, ∂f/∂θ_d = c A ∂d/∂θ_d
        cA = np.zeros((n, 2, 2))
        cA[:, 0, 0], cA[:, 0, 1], cA[:, 1, 1] = c * (1.0 + a), c * s, c
        Jd = np.stack([np.stack([a11, a12], 1), np.stack([a21, a22], 1)], 1)
        M = cA @ Jd
        D[:, 0, 0] = (1.0 + a) * dx + s * dy
        D[:, 1, 0] = dy
        D[:, 0, 1] = 1.0
        D[:, 1, 2] = 1.0
        D[:, 0, 3] = c * dx
        D[:, 0, 4] = c * dy
        D[:, :, 5:] = cA @ Dd[:, :, [0, 1, 2, 4, 3]]  # p1, p2 in OpenCV's roles
    return f, M, D


@dataclass
class LensEstimates:
    """The cameras' parameters after a bundle with a :class:`LensModel` (physical units).

    Attributes
    ----------
    kind : str
        ``"backward"`` or ``"forward"``.
    names : tuple of str
        The ten parameters (:data:`BACKWARD_NAMES` or :data:`FORWARD_NAMES`).
    units : tuple of str
        Their units.
    value : ndarray, shape (G, 10)
        Estimated (or fixed) values per parameter group.
    sigma : ndarray, shape (G, 10)
        Standard deviations (σ̂0 applied); 0 for fixed parameters, NaN without precision.
    estimated : ndarray of bool, shape (10,)
        Which parameters were estimated.
    correlation : ndarray, shape (G, 10, 10)
        Correlations of the estimated parameters of a group (NaN elsewhere).
    r0 : ndarray, shape (G,)
        Reference radius of the scaled units, mm.
    """

    kind: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    value: F64
    sigma: F64
    estimated: NDArray[np.bool_]
    correlation: F64
    r0: F64

    def get(self, name: str, group: int = 0) -> tuple[float, float]:
        """(value, σ) of one parameter."""
        j = self.names.index(name)
        return float(self.value[group, j]), float(self.sigma[group, j])

    def high_correlations(self, threshold: float = 0.9) -> list[tuple[int, str, str, float]]:
        """(group, a, b, ρ) of estimated pairs with abs(ρ) > threshold, largest first."""
        out = []
        for g in range(self.value.shape[0]):
            for a in range(10):
                for b in range(a + 1, 10):
                    r = self.correlation[g, a, b]
                    if np.isfinite(r) and abs(r) > threshold:
                        out.append((g, self.names[a], self.names[b], float(r)))
        return sorted(out, key=lambda t: -abs(t[3]))

    def table(self) -> str:
        """Plain text: one line per parameter and group (value ± σ unit)."""
        lines = []
        for g in range(self.value.shape[0]):
            for j, nm in enumerate(self.names):
                tag = f"± {self.sigma[g, j]:.3g}" if self.estimated[j] else "(fixed)"
                lines.append(f"g{g} {nm:<3} {self.value[g, j]: .7g} {tag} {self.units[j]}")
        pairs = self.high_correlations()
        if pairs:
            lines.append(
                "high correlations: "
                + ", ".join(f"{a}~{b} ρ={r:+.2f}" + (f"@g{g}" if g else "") for g, a, b, r in pairs)
            )
        return "\n".join(lines)


def opencv_camera(est: LensEstimates, pixel_mm: float, group: int = 0) -> dict[str, float]:
    """A forward-model camera in OpenCV's terms (pixels, y down).

    Valid where the image coordinates came from pixels as ``units.image = "px"`` reads
    them (x = u·p, y = −v·p mm from the upper-left corner): then u = fx·x_d + s·y_d + cx,
    v = fy·y_d + cy with OpenCV's distorted point (x_d, y_d) and
    fx = c(1 + as)/p, fy = c/p, s = −c·sk/p, cx = x0/p, cy = −y0/p, k1–k3 as estimated,
    p1 with the opposite sign, p2 as estimated.
    """
    if est.kind != "forward":
        raise InputError("opencv_camera: a forward model is needed (the backward model has "
                         "no closed OpenCV form: orientviz.lens.forward_from_backward fits one)")  # fmt: skip
    v = dict(zip(est.names, est.value[group]))
    p = float(pixel_mm)
    return {"fx": v["c"] * (1 + v["as"]) / p, "fy": v["c"] / p, "skew": -v["c"] * v["sk"] / p,
            "cx": v["x0"] / p, "cy": -v["y0"] / p, "k1": v["k1"], "k2": v["k2"], "k3": v["k3"],
            "p1": -v["p1"], "p2": v["p2"]}  # fmt: skip


class BoundLens:
    """A :class:`LensModel` bound to a block's parameter groups (constant in a bundle).

    Attributes
    ----------
    model : LensModel
    theta0 : ndarray, shape (G, 10)
        Given (start) values, physical units.
    r0 : ndarray, shape (G,)
        Reference radius per group, mm.
    est : ndarray of int, shape (k,)
        Positions of the estimated parameters among the ten.
    scale : ndarray, shape (G, k)
        Physical units per scaled unit (1 µm at r0).
    sigma : ndarray, shape (G, k)
        Pseudo-observation σ in scaled units (inf = free).
    """

    def __init__(self, model: LensModel, theta0: F64, r0: F64) -> None:
        self.model, self.kind = model, model.kind
        self.theta0, self.r0 = theta0, r0
        self.est = np.array([model.all_names.index(k) for k in model.names], np.int64)
        self.scale = self._ring_scale(theta0, np.asarray(r0, dtype=float))
        prior = np.array([model.prior.get(k, np.inf) for k in model.names])
        self.sigma = prior[None, :] / self.scale

    def _ring_scale(self, th: F64, r0: F64) -> F64:
        """Per group (G, k): 1 µm over the largest image shift per unit of each estimated
        parameter on the ring of radius r0 (16 points), all groups in one evaluation."""
        t = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
        u = np.column_stack([np.cos(t), np.sin(t)])
        ru = r0[:, None, None] * u  # (G, 16, 2)
        nrm = (ru / th[:, None, 0, None]).reshape(-1, 2)
        m = (th[:, None, 1:3] + ru).reshape(-1, 2)
        _, _, D = evaluate_lens(self.kind, np.repeat(th, t.size, axis=0), nrm, m)
        big = np.max(np.linalg.norm(D, axis=1).reshape(th.shape[0], t.size, -1), axis=1)
        big = big[:, self.est]
        return np.where(big > 0, UM / np.where(big > 0, big, 1.0), UM)

    @property
    def k(self) -> int:
        """Estimated parameters per group."""
        return int(self.est.size)

    def theta(self, ap: F64) -> F64:
        """Physical parameters (G, 10) at the scaled corrections ``ap`` (G·k,)."""
        th = self.theta0.copy()
        th[:, self.est] += self.scale * ap.reshape(th.shape[0], self.k)
        return th

    def evaluate(self, ap: F64, ray_group: NDArray[np.int64], nrm: F64, m: F64, jac: bool):
        """(f, ∂f/∂n, design (n, 2, k) in mm per scaled unit) of rays; see :func:`evaluate_lens`
        (evaluated by :func:`~orientviz.bundle.model._lens_rays.lens_rays`: the terms that act)."""
        return lens_rays(self.kind, self.theta(ap), ray_group, nrm, m, self.est, self.scale, jac)

    def pinhole(self, ap: F64, ray_group: NDArray[np.int64], m: F64) -> tuple[F64, F64]:
        """Measured points (n, 2) as a pinhole camera would have seen them.

        Returns ``(xy, io)``: xy = (x0, y0) + c·n with n the normalised point the model
        maps onto m, and io (n, 3) = c, x0, y0 per ray — what a plain intersection of
        rays (check points) needs. Backward: c·n = x̄(m); forward: n by Newton steps.
        """
        th = self.theta(ap)[ray_group]
        pp, c = th[:, 1:3], th[:, 0]
        if self.kind == "backward":
            cn = (
                m - evaluate_lens(self.kind, th, np.zeros_like(m), m, False)[0]
            )  # f(n=0) = m − x̄(m)
        else:
            a, s = th[:, 3], th[:, 4]
            d = m - pp
            nrm = np.column_stack([(d[:, 0] - s * d[:, 1]) / (1 + a), d[:, 1]]) / c[:, None]
            for _ in range(20):
                f, M, _ = evaluate_lens(self.kind, th, nrm, m)
                step = np.linalg.solve(M, (f - m)[:, :, None])[:, :, 0]
                nrm = nrm - step
                if np.max(np.abs(step), initial=0.0) < 1e-15:
                    break
            cn = c[:, None] * nrm
        return pp + cn, np.column_stack([c, pp])

    def estimates(self, ap: F64, cofactor: F64 | None, sigma0: float) -> LensEstimates:
        """Physical values, σ and correlations from the scaled estimates and cofactor."""
        G, k = self.theta0.shape[0], self.k
        value = self.theta(ap)
        sigma = np.zeros((G, 10))
        corr = np.full((G, 10, 10), np.nan)
        s0 = sigma0 if np.isfinite(sigma0) else 1.0
        if cofactor is None or cofactor.shape != (G * k, G * k):
            sigma[:, self.est] = np.nan
        else:
            for g in range(G):
                Q = cofactor[g * k : (g + 1) * k, g * k : (g + 1) * k]
                d = np.sqrt(np.clip(np.diag(Q), 0.0, None))
                sigma[g, self.est] = s0 * d * self.scale[g]
                with np.errstate(invalid="ignore", divide="ignore"):
                    corr[g][np.ix_(self.est, self.est)] = Q / np.outer(d, d)
        est = np.zeros(10, bool)
        est[self.est] = True
        return LensEstimates(
            self.kind, self.model.all_names, UNITS[self.kind], value, sigma, est, corr, self.r0
        )


def lens_model(kind: str = "backward", **options) -> LensModel:
    """A :class:`LensModel` (``kind`` "backward" or "forward"; options as the class)."""
    return LensModel(kind, **options)
