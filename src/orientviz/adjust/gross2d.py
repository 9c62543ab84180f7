"""Two-dimensional outlier test of an image point (both coordinates of one ray at once).

A gross error in an image measurement moves the point in some direction of the image
plane, so it biases x *and* y. Testing the two coordinates separately (two w-tests)
ignores that; the 2-D test uses the 2×2 block of the redundancy matrix of the ray.

With ``z = P½ v`` (the residuals of the ray in units of their a-priori σ) and
``R = P½ Q_vv P½`` restricted to the ray (diagonal: the redundancy numbers r_x, r_y;
off-diagonal r_xy), the hypothesis "this ray carries a bias ∇ (2-vector)" is tested by

    T = zᵀ R⁻¹ z,

which is χ² with 2 degrees of freedom without gross errors (a-priori σ0 = 1) and equals
the decrease of vᵀPv when the ray is left out. If R is singular — e.g. a tie point
measured in only two images has no redundancy along the base — only the controlled
direction is tested (rank 1, ``T = (uᵀz)²/λ`` with the eigenpair (λ, u) of R, one
degree of freedom); a ray with R ≈ 0 cannot be tested at all (dof 0, T = 0).

Critical values follow Baarda's B-method: all tests share one non-centrality
``λ0 = δ0²`` (α0 = 0.1 %, β0 = 80 % → λ0 = 17.07): the 1-D test keeps α0 (T > 10.83,
i.e. abs(w) > 3.29) and the 2-D test gets the level at which a bias of non-centrality λ0
is found with the same power β0 (T > 11.73, α = 0.28 %).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .gross import critical_value, noncentrality

F64 = NDArray[np.float64]

__all__ = ["RANK_TOL", "critical_values_2d", "level_2d", "noncentrality_2d", "statistic_2d"]

#: Eigenvalues of the 2×2 redundancy block below this are treated as 0 (a bias in that
#: direction would need more than δ0/√0.01 = 41 σ to be found with power β0).
RANK_TOL: float = 0.01


def statistic_2d(
    z: ArrayLike, r: ArrayLike, r_xy: ArrayLike, rank_tol: float = RANK_TOL
) -> tuple[F64, NDArray[np.int64]]:
    """2-D test statistic of image points (see module docstring).

    Parameters
    ----------
    z : array_like, shape (m, 2)
        Residuals of x and y divided by their a-priori σ (dimensionless).
    r : array_like, shape (m, 2)
        Redundancy numbers of x and y (diagonal of P½ Q_vv P½), in [0, 1].
    r_xy : array_like, shape (m,)
        Off-diagonal element of P½ Q_vv P½ for the pair.
    rank_tol : float
        Eigenvalues of the 2×2 block below this count as 0.

    Returns
    -------
    T : ndarray, shape (m,)
        Test statistic (dimensionless; χ² with ``dof`` degrees of freedom without
        gross errors); 0 where nothing can be tested, NaN input counts as 0.
    dof : ndarray of int, shape (m,)
        Rank of the block used: 2, 1 or 0.
    """
    z = np.nan_to_num(np.asarray(z, float).reshape(-1, 2))
    r = np.nan_to_num(np.asarray(r, float).reshape(-1, 2))
    c = np.nan_to_num(np.asarray(r_xy, float).reshape(-1))
    a, b = r[:, 0], r[:, 1]
    mean, half = 0.5 * (a + b), np.hypot(0.5 * (a - b), c)
    lmax, lmin = mean + half, mean - half
    T = np.zeros(z.shape[0])
    dof = np.zeros(z.shape[0], np.int64)
    full = lmin > rank_tol
    det = a * b - c * c
    with np.errstate(divide="ignore", invalid="ignore"):
        T2 = (b * z[:, 0] ** 2 - 2 * c * z[:, 0] * z[:, 1] + a * z[:, 1] ** 2) / det
    T[full], dof[full] = T2[full], 2
    one = ~full & (lmax > rank_tol)
    # eigenvector of λmax: (c, λmax − a), or (λmax − b, c); take the better conditioned
    u1 = np.stack([c, lmax - a], 1)
    u2 = np.stack([lmax - b, c], 1)
    u = np.where((np.abs(lmax - a) >= np.abs(lmax - b))[:, None], u1, u2)
    nu = np.linalg.norm(u, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        proj = np.einsum("ij,ij->i", u, z) / nu
        T1 = proj**2 / lmax
    # a diagonal block (c = 0, a = λmax = b impossible here as λmin ≤ tol) gives u = 0:
    # then the controlled direction is the axis with the larger redundancy number
    diag = one & (nu == 0)
    T1[diag] = np.where(a[diag] >= b[diag], z[diag, 0] ** 2, z[diag, 1] ** 2) / lmax[diag]
    T[one], dof[one] = T1[one], 1
    return T, dof


def noncentrality_2d(bias: ArrayLike, sigma: ArrayLike, r: ArrayLike, r_xy: ArrayLike) -> F64:
    """Non-centrality λ = ∇ᵀ P½ R P½ ∇ that a bias ∇ of an image point gives the 2-D test.

    Parameters
    ----------
    bias : array_like, shape (m, 2)
        Bias of x and y (observation units, e.g. mm).
    sigma : array_like, shape (m, 2)
        A-priori σ of x and y (same units).
    r, r_xy
        As in :func:`statistic_2d`.

    Returns
    -------
    ndarray, shape (m,)
        λ (dimensionless); the bias is found with power ≥ β0 when λ ≥ λ0 = δ0² (with
        the B-method critical values of :func:`critical_values_2d`).
    """
    e = np.asarray(bias, float).reshape(-1, 2) / np.asarray(sigma, float).reshape(-1, 2)
    r = np.nan_to_num(np.asarray(r, float).reshape(-1, 2))
    c = np.nan_to_num(np.asarray(r_xy, float).reshape(-1))
    return r[:, 0] * e[:, 0] ** 2 + 2 * c * e[:, 0] * e[:, 1] + r[:, 1] * e[:, 1] ** 2


def critical_values_2d(alpha0: float = 0.001, beta0: float = 0.80) -> dict[int, float]:
    """Critical values of T for 1 and 2 degrees of freedom by Baarda's B-method.

    Parameters
    ----------
    alpha0 : float
        Level of the 1-D test (0.1 %: T > 3.29² = 10.83).
    beta0 : float
        Common power at the common non-centrality λ0 = δ0(α0, β0)².

    Returns
    -------
    dict
        ``{0: inf, 1: k², 2: c2}``; the level of the 2-D test is ``chdtrc(2, c2)``.
    """
    from scipy.special import chndtrix  # scipy.special loads many modules: not at the package's import

    lam0 = noncentrality(alpha0, beta0) ** 2
    return {0: float("inf"), 1: critical_value(alpha0) ** 2, 2: float(chndtrix(1 - beta0, 2, lam0))}


def level_2d(alpha0: float = 0.001, beta0: float = 0.80) -> float:
    """Significance level of the 2-D test under the B-method (0.1 %, 80 % → 0.28 %)."""
    from scipy.special import chdtrc  # as in critical_values_2d

    return float(chdtrc(2, critical_values_2d(alpha0, beta0)[2]))
