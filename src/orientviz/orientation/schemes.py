"""Point schemes of relative orientation and the classical formulas that go with them.

A scheme places its points on *profiles* (columns across the strip at X = 0, under the
left projection centre, …, X = b, under the right one) and *rows* (Y = +d at the upper
image edge, 0, −d at the lower edge), in the model frame of
:mod:`orientviz.orientation.relative` (X along the base, Y left, Z up, Z < 0).

* Gruber's 6 points: 1 (0, 0), 2 (b, 0), 3 (0, +d), 4 (b, +d), 5 (0, −d), 6 (b, −d).
* Hallert's 9 points as numbered by Kovarik (1968): Gruber's six plus the middle
  profile X = b/2 with 7 (+d), 8 (0), 9 (−d).
* Schmid's grid: R columns × (2R − 1) rows over the whole model (R = 2 is Gruber's
  scheme, R = 3 the 15 points both Schmid and Kasper name as the optimum).

The ordinate ratio ``k = |Y|/|Z|`` of the edge rows and ``K = 1 + k²`` are Kovarik's
constants. Angles are radians unless a name says ``_c`` (centesimal minutes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from .relative import DEPENDENT, check_determinable, design_dependent, kovarik_to_orientviz

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Scheme:
    """Positions of the orientation points, relative to the base and the ordinate.

    Attributes
    ----------
    name : str
        E.g. ``"gruber6"``, ``"kovarik9"``, ``"schmid3"``.
    labels : tuple of str
        Point numbers as in the literature (``"1"`` … ``"9"``).
    u : ndarray, shape (n,)
        X / b (0 under O1, 1 under O2).
    v : ndarray, shape (n,)
        Y / d (+1 upper edge, 0 the base line, −1 lower edge).
    """

    name: str
    labels: tuple[str, ...]
    u: F64
    v: F64

    @property
    def n(self) -> int:
        return len(self.labels)

    def index(self, label: str) -> int:
        """Position of the point numbered ``label``."""
        return self.labels.index(str(label))

    def model_points(
        self, b: float, d: float, Z: ArrayLike, placement: str = "plan"
    ) -> tuple[F64, F64, F64]:
        """Model coordinates of the scheme points.

        Parameters
        ----------
        b : float
            Model base, model units.
        d : float
            Ordinate of the edge rows (abs(Y) at the reference height), model units.
        Z : float or array_like, shape (n,)
            Height of each point (negative), model units.
        placement : {"plan", "ratio"}
            ``"plan"``: the point is set at plan position (u b, v d) whatever its height
            (a plotter's X, Y counters); ``"ratio"``: Y = v d Z / Z_ref so that
            Y/Z = ∓k exactly, Kovarik's assumption (Z_ref = mean Z).

        Returns
        -------
        X, Y, Z : ndarray, shape (n,)
        """
        Z = np.broadcast_to(np.asarray(Z, dtype=float), (self.n,)).copy()
        X = self.u * b
        if placement == "plan":
            Y = self.v * d
        elif placement == "ratio":
            Y = self.v * d * Z / Z.mean()
        else:
            raise InputError(f"expected placement 'plan' or 'ratio', got {placement!r}")
        return X, Y, Z


def gruber6() -> Scheme:
    """Gruber's six points (numbering 1–6, see the module docstring)."""
    return Scheme(
        "gruber6",
        ("1", "2", "3", "4", "5", "6"),
        np.array([0, 1, 0, 1, 0, 1], float),
        np.array([0, 0, 1, 1, -1, -1], float),
    )


def kovarik9() -> Scheme:
    """Hallert's nine points in Kovarik's numbering (three profiles X = 0, b/2, b)."""
    return Scheme(
        "kovarik9",
        ("1", "2", "3", "4", "5", "6", "7", "8", "9"),
        np.array([0, 1, 0, 1, 0, 1, 0.5, 0.5, 0.5]),
        np.array([0, 0, 1, 1, -1, -1, 1, 0, -1], float),
    )


def schmid_grid(R: int) -> Scheme:
    """Schmid's grid of R columns × (2R − 1) rows (R ≥ 2), numbered row by row."""
    if int(R) != R or R < 2:
        raise InputError(f"expected a whole number of columns R ≥ 2, got {R}")
    R = int(R)
    uu, vv = np.meshgrid(np.linspace(0, 1, R), np.linspace(1, -1, 2 * R - 1))
    n = uu.size
    return Scheme(f"schmid{R}", tuple(str(i + 1) for i in range(n)), uu.ravel(), vv.ravel())


def fifteen() -> Scheme:
    """The 15-point optimum: Schmid's grid with R = 3 (3 profiles × 5 rows)."""
    return schmid_grid(3)


SCHEMES = {
    "gruber6": gruber6,
    "kovarik9": kovarik9,
    "schmid3": fifteen,
    "schmid4": lambda: schmid_grid(4),
}


def get_scheme(name: str | Scheme) -> Scheme:
    """A scheme by name (``gruber6``, ``kovarik9``, ``schmid3``, ``schmid4``, ``schmidR``)."""
    if isinstance(name, Scheme):
        return name
    if name in SCHEMES:
        return SCHEMES[name]()
    if name.startswith("schmid") and name[6:].isdigit():
        return schmid_grid(int(name[6:]))
    raise InputError(f"unknown point scheme {name!r}; known: {', '.join(SCHEMES)}, schmidR")


# ------------------------------------------------------------------ least squares and influence
def influence(A: ArrayLike) -> F64:
    """Influence of each point on each element: the rows of (AᵀA)⁻¹Aᵀ.

    Parameters
    ----------
    A : array_like, shape (n, 5)
        Linearised design (e.g. :func:`~orientviz.orientation.relative.design_dependent`).

    Returns
    -------
    ndarray, shape (5, n)
        ``G[j, i]`` = change of element j per unit of parallax at point i (model units
        or radians per model unit); ``elements = G @ p_y``.
    """
    A = np.asarray(A, dtype=float)
    check_determinable(A, DEPENDENT, "influence")
    return np.linalg.solve(A.T @ A, A.T)


def least_squares_elements(A: ArrayLike, p: ArrayLike) -> F64:
    """Least-squares solution of the linearised parallax equations ``p = A d`` (equal weights)."""
    return influence(A) @ np.asarray(p, dtype=float)


def scheme_precision(
    scheme: Scheme | str, b: float, d: float, Z: ArrayLike, sigma: float = 1.0
) -> tuple[F64, F64]:
    """Theoretical precision of the dependent-pair elements for a scheme.

    Parameters
    ----------
    scheme : Scheme or str
    b, d : float
        Model base and edge ordinate, model units.
    Z : float or array_like
        Heights of the points (negative), model units.
    sigma : float
        σ of one y-parallax reading, model units.

    Returns
    -------
    std : ndarray, shape (5,)
        σ of by, bz (model units) and ω, φ, κ (radians).
    corr : ndarray, shape (5, 5)
        Correlation matrix.
    """
    sch = get_scheme(scheme)
    A = design_dependent(*sch.model_points(b, d, Z), b)
    check_determinable(A, DEPENDENT, sch.name)
    Q = np.linalg.inv(A.T @ A)
    s = np.sqrt(np.diag(Q))
    return sigma * s, Q / np.outer(s, s)


# ------------------------------------------------------------------ Kovarik's closed form
#: Points 3-7 and 9 lie on the edge rows (K = 1 + k²); 1, 2, 8 on the base line (K = 1).
_EDGE9 = np.array([0, 0, 1, 1, 1, 1, 1, 0, 1], bool)
#: Kovarik's combinations over points 1 … 9: κ (profile 1 − profile 2), φ (3 − 4 − 5 + 6),
#: bz (upper − lower row), and the printed coefficients of dbz (÷ 12k) and dby (÷ 18).
_C9 = (
    np.array([1, -1, 1, -1, 1, -1, 0, 0, 0], float),
    np.array([0, 0, 1, -1, -1, 1, 0, 0, 0], float),
    np.array([0, 0, 1, 1, -1, -1, 1, 0, -1], float),
    np.array([0, 0, 1, -5, -1, 5, -2, 0, 2], float),
    np.array([-1, 5, -1, 5, -1, 5, 2, 2, 2], float),
)


def kovarik_nine_point(
    by: ArrayLike, z: ArrayLike, b: float, k: float, *, convention: str = "orientviz"
) -> F64:
    """Kovarik's closed-form 9-point formulas for mountainous terrain (1968).

    Implemented as printed (case "base inside, connection right, equal weights"):
    dω = −Z/N, then dφ, dκ, dbz and dby from the by readings and dω, with
    K_1 = K_2 = K_8 = 1 and K = 1 + k² for the edge points.

    Parameters
    ----------
    by : array_like, shape (9,)
        by readings at points 1 … 9 (Kovarik numbering; relative to the current by),
        model units. They play the role of p_y.
    z : array_like, shape (9,)
        z of the points, *as a coordinate* (negative below the base, model units).
    b : float
        Model base, model units.
    k : float
        abs(y)/abs(z) of the edge points (the ordinate over the projection distance).
    convention : {"orientviz", "kovarik"}
        Signs of the returned elements (see ``relative.KOVARIK_SIGNS``).

    Returns
    -------
    ndarray, shape (5,)
        dby, dbz (model units), dω, dφ, dκ (radians).
    """
    p = np.asarray(by, dtype=float).reshape(-1)
    zz = np.asarray(z, dtype=float).reshape(-1)
    if p.shape != (9,) or zz.shape != (9,):
        raise InputError(f"expected 9 by readings and 9 z values, got {p.shape} and {zz.shape}")
    if not b or not k:
        raise InputError("expected a non-zero model base b and ordinate ratio k")
    K = 1.0 + k * k
    zK = zz * np.where(_EDGE9, K, 1.0)
    ck, cp, cz, cb, cy = _C9
    Zn = (
        np.sum(zK * (p.mean() - p))
        + (ck @ zK) * (ck @ p) / 6
        + (cp @ zK) * (cp @ p) / 4
        + (cz @ zK) * (cz @ p) / 6
    )
    Nn = (
        np.sum(zK * (zK.mean() - zK)) + (ck @ zK) ** 2 / 6 + (cp @ zK) ** 2 / 4 + (cz @ zK) ** 2 / 6
    )
    domega = -Zn / Nn
    dphi = (cp @ p + (cp @ zK) * domega) / (2 * b * k)
    dkappa = (ck @ p + (ck @ zK) * domega) / (3 * b)
    dbz = (cb @ p + (cb @ zK) * domega) / (12 * k)
    dby = (cy @ p + (cy @ zK) * domega) / 18
    out = np.array([dby, dbz, domega, dphi, dkappa])
    if convention == "kovarik":
        return out
    if convention != "orientviz":
        raise InputError(f"expected convention 'orientviz' or 'kovarik', got {convention!r}")
    return kovarik_to_orientviz(out)


# ------------------------------------------------------------------ condition equation
def condition_equation(X: ArrayLike, Y: ArrayLike, Z: ArrayLike, b: float) -> F64:
    """Schmid's condition equation of 6 points: coefficients a with aᵀp = 0.

    Six parallaxes over five elements leave one redundancy: the left null vector of
    the 6 × 5 linearised design. It is scaled so that the coefficient of point 1 is 2;
    with all Z equal and the Gruber layout it is (2, −2, −1, 1, −1, 1), i.e.
    ``(2p1 − p3 − p5) − (2p2 − p4 − p6) = 0``.

    Parameters
    ----------
    X, Y, Z : array_like, shape (6,)
        Model coordinates of Gruber's points 1 … 6 (model units, Z < 0).
    b : float
        Model base.

    Returns
    -------
    ndarray, shape (6,)
    """
    A = design_dependent(X, Y, Z, b)
    if A.shape != (6, 5):
        raise InputError(f"the condition equation needs exactly 6 points, got {A.shape[0]}")
    check_determinable(A, DEPENDENT, "condition equation")
    U, s, Vt = np.linalg.svd(A)
    a = U[:, -1]
    if abs(a[0]) < 1e-12 * np.abs(a).max():
        raise InputError("point 1 does not enter the condition equation of this layout")
    return 2.0 * a / a[0]


def flat_condition(p: ArrayLike) -> float:
    """Misclosure (2p1 − p3 − p5) − (2p2 − p4 − p6) of Gruber's six parallaxes (flat terrain)."""
    p = np.asarray(p, dtype=float).reshape(-1)
    if p.shape != (6,):
        raise InputError(f"expected 6 parallaxes (Gruber points 1-6), got {p.shape[0]}")
    return float((2 * p[0] - p[2] - p[4]) - (2 * p[1] - p[3] - p[5]))


def condition_misclosure(
    p: ArrayLike, X: ArrayLike, Y: ArrayLike, Z: ArrayLike, b: float
) -> tuple[float, float]:
    """Misclosure w = aᵀp of Schmid's general condition and its σ for unit σ_p.

    Returns
    -------
    w : float
        Misclosure, model units.
    sigma_w : float
        Its standard deviation per unit σ of one parallax, ``|a|``; a consistent model
        has abs(w) ≲ 3 σ_p abs(a).
    """
    a = condition_equation(X, Y, Z, b)
    return float(a @ np.asarray(p, dtype=float)), float(np.linalg.norm(a))
