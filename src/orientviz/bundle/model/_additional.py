"""Additional-parameter sets for self-calibration, and their significance and correlations.

Self-calibration (Ackermann 1974, Table 1 method 4) extends every image ray by a
correction that is linear in a few parameters shared by a group of images::

    x_obs + v = project(X, X0, R, c, x0, y0) + A(x_obs) · p        (mm)

``A`` is evaluated at the *observed* image coordinates (x along the flight direction,
mm, from the principal point), so it is constant during the iterations. Every set here
follows the :class:`AdditionalParameters` protocol (book/api/contracts.md): ``name``, ``names``
and ``design(xy) -> (n, 2, k)`` in mm per unit of the parameter. The parameters are
scaled so that **one unit is 1 µm** of image error at a reference point (stated per
set): estimates, σ and pseudo-observation σ (``ap_sigma``) all read in µm.

Sets
----
* :class:`Ebner12` — Ebner's 12 parameters (1976): the 18 polynomial terms of degree ≤ 2
  in x and in y, minus the 6 deformations the exterior orientation makes itself (two
  shifts, scale, rotation, two projective tilts), orthogonal on the 3 × 3 standard point
  grid (x, y ∈ {−b, 0, b}, b = image base).
* :class:`Brown` — a physical model (Brown 1971, as usually written): principal point
  and principal distance corrections, radial distortion k1…k3, decentering p1, p2,
  affinity b1 and shear b2.
* :class:`Gruen44` — a Grün-type set of 44 parameters: products of discrete orthogonal
  polynomials of degree ≤ 4 in x and y on the 5 × 5 grid (x, y ∈ {−b, −b/2, 0, b/2, b}),
  50 terms, minus the same 6 exterior-orientation deformations, orthonormalised. This is
  orientviz's construction following Grün's idea (1978) — the structure and count are
  his, the individual functions are not his printed table.

:func:`ap_set` makes a set by name; :func:`analyse` tests every parameter for
significance and names over-parameterisation (correlated pairs, parameters correlated
with the exterior orientation) instead of absorbing it silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import InputError, NotDeterminableError

F64 = NDArray[np.float64]
UM = 1e-3  # mm per µm

__all__ = [
    "AdditionalParameters",
    "APAnalysis",
    "Brown",
    "Ebner12",
    "Gruen44",
    "analyse",
    "ap_set",
    "SETS",
]


class AdditionalParameters(Protocol):
    """The contract of book/api/contracts.md ("Additional parameters")."""

    name: str
    names: list[str]

    def design(self, xy: ArrayLike) -> F64: ...


def _check(xy: ArrayLike) -> F64:
    a = np.asarray(xy, dtype=float)
    if a.ndim != 2 or a.shape[1] != 2 or not np.all(np.isfinite(a)):
        raise InputError(f"image coordinates: expected finite (n, 2) mm, got shape {a.shape}")
    return a


class _Set:
    name: str
    names: list[str]

    def design(self, xy: ArrayLike) -> F64:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def k(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def correction(self, xy: ArrayLike, p: ArrayLike) -> F64:
        """Δxy = A(xy) · p in mm (n, 2) for parameters ``p`` (k,) in µm."""
        p = np.asarray(p, dtype=float).reshape(-1)
        if p.shape != (self.k,):
            raise InputError(f"{self.name}: expected {self.k} parameters, got {p.shape[0]}")
        return self.design(xy) @ p


# --------------------------------------------------------------------------- Ebner
@dataclass
class Ebner12(_Set):
    """Ebner's 12 orthogonal additional parameters.

    With u = x/b, v = y/b (b = image base in mm, the spacing of the 3 × 3 standard
    points) and ``s = 2/3`` (the mean of u² over {−1, 0, 1}), in µm::

        Δx =  b1 u + b2 v − b3 (2u² − 2s) + b4 uv + b5 (v² − s) + b7 u(v² − s)
              + b9 v(u² − s) + b11 (u² − s)(v² − s)
        Δy = −b1 v + b2 u + b3 uv − b4 (2v² − 2s) + b6 (u² − s) + b8 v(u² − s)
              + b10 u(v² − s) + b12 (u² − s)(v² − s)

    Parameters
    ----------
    b : float
        Image base in mm (92 mm: 60 % forward overlap of a 230 mm format).
    """

    b: float = 92.0
    name: str = "ebner12"
    names: list[str] = field(default_factory=lambda: [f"b{i}" for i in range(1, 13)])

    def design(self, xy: ArrayLike) -> F64:
        xy = _check(xy)
        if not self.b > 0:
            raise InputError(f"ebner12: expected an image base b > 0 mm, got {self.b}")
        u, v = xy[:, 0] / self.b, xy[:, 1] / self.b
        s = 2.0 / 3.0
        U, V = u * u - s, v * v - s
        A = np.zeros((xy.shape[0], 2, 12))
        A[:, 0, 0], A[:, 1, 0] = u, -v
        A[:, 0, 1], A[:, 1, 1] = v, u
        A[:, 0, 2], A[:, 1, 2] = -2.0 * U, u * v
        A[:, 0, 3], A[:, 1, 3] = u * v, -2.0 * V
        A[:, 0, 4] = V
        A[:, 1, 5] = U
        A[:, 0, 6] = u * V
        A[:, 1, 7] = v * U
        A[:, 0, 8] = v * U
        A[:, 1, 9] = u * V
        A[:, 0, 10] = U * V
        A[:, 1, 11] = U * V
        return A * UM


# --------------------------------------------------------------------------- Brown
@dataclass
class Brown(_Set):
    """A physical additional-parameter model after Brown, linearised.

    With x̄ = x − x0, ȳ = y − y0 (nominal principal point), ξ = x̄/r0, η = ȳ/r0,
    ρ² = ξ² + η², in µm::

        Δx = dx0 + (x̄/c) dc + ξ (k1 ρ² + k2 ρ⁴ + k3 ρ⁶) + p1 (ρ² + 2ξ²) + 2 p2 ξη + b1 ξ + b2 η
        Δy = dy0 + (ȳ/c) dc + η (k1 ρ² + k2 ρ⁴ + k3 ρ⁶) + p2 (ρ² + 2η²) + 2 p1 ξη

    What is linearised: the principal-distance term is the exact derivative
    ∂x/∂c = x̄/c but evaluated at the observed, not the projected, coordinates; the
    distortion terms are evaluated at the observed coordinates and about the *nominal*
    principal point (the coupling of dx0, dy0 with the distortion centre is dropped);
    products of corrections are neglected. All are second-order small for µm-size
    parameters.

    Parameters
    ----------
    c : float
        Nominal principal distance in mm (for the dc term).
    r0 : float
        Reference radius in mm: k1 … p2, b1, b2 are µm at r = r0 (default 100 mm).
    x0, y0 : float
        Nominal principal point in mm.
    """

    c: float = 152.0
    r0: float = 100.0
    x0: float = 0.0
    y0: float = 0.0
    name: str = "brown"
    names: list[str] = field(
        default_factory=lambda: ["dx0", "dy0", "dc", "k1", "k2", "k3", "p1", "p2", "b1", "b2"]
    )

    def design(self, xy: ArrayLike) -> F64:
        xy = _check(xy)
        if not (self.c > 0 and self.r0 > 0):
            raise InputError("brown: expected c > 0 and r0 > 0 (mm)")
        xb, yb = xy[:, 0] - self.x0, xy[:, 1] - self.y0
        xi, eta = xb / self.r0, yb / self.r0
        r2 = xi * xi + eta * eta
        A = np.zeros((xy.shape[0], 2, 10))
        A[:, 0, 0] = 1.0
        A[:, 1, 1] = 1.0
        A[:, 0, 2], A[:, 1, 2] = xb / self.c, yb / self.c
        for j, pw in enumerate((1, 2, 3)):
            A[:, 0, 3 + j], A[:, 1, 3 + j] = xi * r2**pw, eta * r2**pw
        A[:, 0, 6], A[:, 1, 6] = r2 + 2 * xi * xi, 2 * xi * eta
        A[:, 0, 7], A[:, 1, 7] = 2 * xi * eta, r2 + 2 * eta * eta
        A[:, 0, 8] = xi
        A[:, 0, 9] = eta
        return A * UM


# --------------------------------------------------------------------------- Grün-type
def _discrete_legendre(t: F64, nodes: F64, degree: int) -> F64:
    """Polynomials of degree 0..degree orthonormal on ``nodes``, evaluated at ``t``."""
    V = np.vander(nodes, degree + 1, increasing=True)
    Q, R = np.linalg.qr(V)
    # P(t) = [1, t, t², …] R⁻¹  (columns orthonormal on the nodes)
    return np.vander(t, degree + 1, increasing=True) @ np.linalg.inv(R) * np.sqrt(nodes.size)


def eo_deformations(u: F64, v: F64) -> F64:
    """The six image deformations of the exterior orientation, (n, 2, 6)."""
    z, o = np.zeros_like(u), np.ones_like(u)
    return np.stack(
        [
            np.stack([o, z], 1),  # shift x (φ, X0)
            np.stack([z, o], 1),  # shift y (ω, Y0)
            np.stack([u, v], 1),  # scale (Z0)
            np.stack([-v, u], 1),  # rotation (κ)
            np.stack([u * u, u * v], 1),  # projective tilt about y (φ)
            np.stack([u * v, v * v], 1),  # projective tilt about x (ω)
        ],
        axis=2,
    )


@dataclass
class Gruen44(_Set):
    """A Grün-type set of 44 additional parameters, orthonormal on the 5 × 5 grid.

    Build: on the grid u, v ∈ {−1, −½, 0, ½, 1} (u = x/b) take the 25 products
    P_i(u) P_j(v), i, j ≤ 4, of discrete orthonormal polynomials for Δx and the same for
    Δy (50 functions); remove the 6-dimensional span of the exterior-orientation
    deformations (:func:`eo_deformations`); an SVD gives 44 functions orthonormal on the
    grid, each scaled so that its largest value on the grid is 1 µm. Parameters g1…g44.

    Parameters
    ----------
    b : float
        Image base in mm (the grid reaches ±b).
    """

    b: float = 92.0
    name: str = "gruen44"
    names: list[str] = field(default_factory=lambda: [f"g{i}" for i in range(1, 45)])

    def __post_init__(self) -> None:
        if not self.b > 0:
            raise InputError(f"gruen44: expected an image base b > 0 mm, got {self.b}")
        nodes = np.linspace(-1.0, 1.0, 5)
        gu, gv = np.meshgrid(nodes, nodes)
        u, v = gu.ravel(), gv.ravel()
        B = self._basis(u, v)  # (25, 2, 50)
        M = B.reshape(50, 50)  # rows: grid point × coordinate
        E = eo_deformations(u, v).reshape(50, 6)
        Qe, _ = np.linalg.qr(E)
        Mp = M - Qe @ (Qe.T @ M)
        U, s, Vt = np.linalg.svd(Mp, full_matrices=False)
        # the EO deformations are polynomials of degree ≤ 2, inside the span of the 50
        # products: Mp @ C = M @ C' with C' = M⁻¹ Mp C, exact everywhere, not only on the grid
        C = np.linalg.solve(M, Mp @ (Vt[:44].T / s[:44]))
        F = M @ C
        self._coef = C / np.max(np.abs(F), axis=0)

    @staticmethod
    def _basis(u: F64, v: F64) -> F64:
        nodes = np.linspace(-1.0, 1.0, 5)
        Pu = _discrete_legendre(u, nodes, 4)
        Pv = _discrete_legendre(v, nodes, 4)
        prod = (Pu[:, :, None] * Pv[:, None, :]).reshape(u.size, 25)
        out = np.zeros((u.size, 2, 50))
        out[:, 0, :25] = prod
        out[:, 1, 25:] = prod
        return out

    def design(self, xy: ArrayLike) -> F64:
        xy = _check(xy)
        u, v = xy[:, 0] / self.b, xy[:, 1] / self.b
        B = self._basis(u, v)  # (n, 2, 50)
        return (B @ self._coef) * UM


#: name → constructor
SETS = {"ebner12": Ebner12, "brown": Brown, "gruen44": Gruen44}


def ap_set(name: str, **options) -> _Set:
    """An additional-parameter set by name (``"ebner12"``, ``"brown"``, ``"gruen44"``).

    Parameters
    ----------
    name : str
        The set's name.
    **options
        Passed to the set (``b`` for ebner12/gruen44; ``c``, ``r0`` for brown).

    Raises
    ------
    InputError
        For an unknown name or option (one line listing what is known).
    """
    key = str(name).lower().replace("-", "").replace("_", "")
    if key not in SETS:
        raise InputError(
            f"unknown additional-parameter set {name!r}; expected one of {', '.join(SETS)}"
        )
    try:
        return SETS[key](**options)
    except TypeError as exc:
        raise InputError(f"{key}: {exc}") from None


# --------------------------------------------------------------------------- analysis
@dataclass
class APAnalysis:
    """Significance and correlations of estimated additional parameters.

    Attributes
    ----------
    names : list of str
        Parameter names (``"b3@g0"`` = parameter b3 of image group 0).
    value, sigma : ndarray
        Estimates and their standard deviations (µm).
    t : ndarray
        Test statistic abs(value) / σ.
    significant : ndarray of bool
        abs(t) > z(1 − α/2).
    pairs : list of (str, str, float)
        Pairs of additional parameters with abs(ρ) > threshold.
    with_exterior : list of (str, str, float)
        (additional parameter, most correlated exterior/point parameter, ρ) above threshold.
    undetermined : list of str
        Parameters the block does not determine: their a-priori σ (σ0 = 1) is above
        1/√2 of their pseudo-observation's σ, i.e. the observations carry less weight for
        them than the pseudo-observation p = 0 ± σ. Pairwise correlations miss such
        dependencies among many parameters.
    warnings : list of str
        Sentences naming over-parameterisation.
    """

    names: list[str]
    value: F64
    sigma: F64
    t: F64
    significant: NDArray[np.bool_]
    pairs: list[tuple[str, str, float]]
    with_exterior: list[tuple[str, str, float]]
    alpha: float
    threshold: float
    undetermined: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def table(self) -> str:
        """Plain-text table: name, value, σ, t, significant."""
        lines = [f"{'parameter':<12} {'value µm':>9} {'σ µm':>7} {'t':>6}  significant"]
        for n, v, s, t, g in zip(self.names, self.value, self.sigma, self.t, self.significant):
            lines.append(f"{n:<12} {v:9.2f} {s:7.2f} {t:6.1f}  {'yes' if g else 'no'}")
        return "\n".join(lines + self.warnings)


def analyse(
    adj, *, alpha: float = 0.05, threshold: float = 0.9, ap_sigma: ArrayLike | None = None
) -> APAnalysis:
    """Test the additional parameters of a self-calibrating adjustment.

    Parameters
    ----------
    adj : Adjustment
        With a block ``"additional"``; correlations need the cofactor of the additional
        parameters (``cofactor`` dense, or ``cofactor_groups["additional"]``) — with the
        dense cofactor also correlations with every other parameter are checked.
    alpha : float
        Significance level of the two-sided test of each parameter against 0.
    threshold : float
        abs(ρ) above which a pair is reported as over-parameterisation.
    ap_sigma : float or array_like (k,), optional
        σ (µm) of the pseudo-observations used in the adjustment; with it, parameters
        determined only by their pseudo-observation are named (``undetermined``).
    """
    if "additional" not in adj.groups:
        raise InputError("the adjustment has no additional parameters (block 'additional')")
    sl = adj.groups["additional"]
    idx = np.arange(adj.n_unknowns)[sl]
    names = [adj.names[i] for i in idx]
    value = adj.x[sl]
    s0 = adj.sigma0 if np.isfinite(adj.sigma0) and adj.redundancy > 0 else 1.0
    if adj.cofactor is not None:
        Qa = adj.cofactor[np.ix_(idx, idx)]
    elif "additional" in adj.cofactor_groups:
        Qa = np.asarray(adj.cofactor_groups["additional"], float)
    else:
        raise NotDeterminableError(
            "no cofactor of the additional parameters was computed (precision=False?)"
        )
    d = np.sqrt(np.clip(np.diag(Qa), 1e-300, None))
    sigma = s0 * d
    t = np.abs(value) / sigma
    from scipy.special import ndtri  # scipy.special loads many modules: needed here only

    sig = t > float(ndtri(1 - alpha / 2))
    R = Qa / np.outer(d, d)
    i, j = np.triu_indices(len(idx), 1)
    big = np.abs(R[i, j]) > threshold
    pairs = sorted(
        ((names[a], names[b], float(R[a, b])) for a, b in zip(i[big], j[big])),
        key=lambda p: -abs(p[2]),
    )
    with_ext: list[tuple[str, str, float]] = []
    if adj.cofactor is not None:
        Q = adj.cofactor
        dq = np.sqrt(np.clip(np.diag(Q), 1e-300, None))
        others = np.setdiff1d(np.arange(adj.n_unknowns), idx)
        others = others[np.diag(Q)[others] > 0]
        if others.size:
            C = Q[np.ix_(idx, others)] / np.outer(dq[idx], dq[others])
            for a in range(len(idx)):
                jmax = int(np.argmax(np.abs(C[a])))
                if abs(C[a, jmax]) > threshold:
                    with_ext.append((names[a], adj.names[others[jmax]], float(C[a, jmax])))
    undetermined: list[str] = []
    if ap_sigma is not None:
        k = len(idx) // max(1, len({n.split("@")[-1] for n in names}))
        ps = np.resize(np.broadcast_to(np.asarray(ap_sigma, float), (k,)), len(idx))
        with np.errstate(invalid="ignore"):
            undetermined = [
                n for n, q, p in zip(names, d, ps) if np.isfinite(p) and q > p / np.sqrt(2)
            ]
    warns = []
    if undetermined:
        warns.append(
            "not determinable by the block (held only by the pseudo-observation): "
            + ", ".join(undetermined[:8])
            + (" …" if len(undetermined) > 8 else "")
        )
    if pairs:
        warns.append(
            "over-parameterised: "
            + ", ".join(f"{a}~{b} (ρ={r:+.2f})" for a, b, r in pairs[:6])
            + (" …" if len(pairs) > 6 else "")
            + "; drop one of each pair or give ap_sigma"
        )
    if with_ext:
        warns.append(
            "not separable from the orientation: "
            + ", ".join(f"{a}~{b} (ρ={r:+.2f})" for a, b, r in with_ext[:6])
            + (" …" if len(with_ext) > 6 else "")
        )
    return APAnalysis(
        names, value, sigma, t, sig, pairs, with_ext, alpha, threshold, undetermined, warns
    )
