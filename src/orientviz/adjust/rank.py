"""Rank-defect diagnosis: which parameters a normal matrix cannot determine.

Used by the engine instead of letting a ``LinAlgError`` escape: the null space of the
(Jacobi-scaled) normal matrix is computed and the parameters that take part in it are
named, largest share first.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..errors import NotDeterminableError, parameter_words

#: Relative eigenvalue below which a direction counts as undetermined.
RANK_TOLERANCE: float = 1e-10


def scaled_condition_bound(
    N: NDArray[np.float64], factor: tuple[NDArray[np.float64], bool] | None = None
) -> float:
    """An upper bound of the 2-norm condition number of the Jacobi-scaled normal matrix.

    With M = D⁻¹ N D⁻¹ (D² = diag N) and M = Rᵀ R, cond(M) = ‖M‖₂ ‖R⁻¹‖₂² ≤ ‖M‖_F ‖R⁻¹‖_F²,
    and R⁻¹ = D T⁻¹ from N's own triangular factor T (one triangular inverse, a third of
    the Cholesky factor's flops, far fewer than the singular values or eigenvalues). The
    bound exceeds cond(M) by at most a factor u^1.5 (u unknowns), so a small bound proves
    a well-conditioned matrix; a large one proves nothing.

    Parameters
    ----------
    N : ndarray, shape (u, u)
        Symmetric normal matrix JᵀPJ.
    factor : tuple (c, lower), optional
        N's Cholesky factor with zeros in its unused triangle, as
        ``scipy.linalg.lapack.dpotrf(N, lower, clean=1)`` returns it; computed if not
        given. Other values in the unused triangle (``scipy.linalg.cho_factor`` leaves N's
        there) only enlarge the bound: it stays an upper bound.

    Returns
    -------
    float
        The bound (dimensionless); ``inf`` (or NaN) when N is not positive definite or not
        finite.
    """
    d = np.sqrt(np.abs(np.diag(N)))
    d[d == 0] = 1.0
    if factor is None:
        c, info = scipy.linalg.lapack.dpotrf(N, lower=0, clean=1)
        if info != 0:
            return float("inf")
        factor = (c, False)
    c, low = factor
    inv, info = scipy.linalg.lapack.dtrtri(c, lower=int(low))
    if info != 0:
        return float("inf")
    R_inv = inv * d[None, :] if low else inv * d[:, None]
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.linalg.norm(N / np.outer(d, d))) * float(np.einsum("ij,ij->", R_inv, R_inv))


def null_space_of_normal(N: NDArray[np.float64], tol: float = RANK_TOLERANCE):
    """Null space of a symmetric positive semi-definite normal matrix.

    Parameters
    ----------
    N : ndarray, shape (u, u)
        Normal matrix JᵀPJ.
    tol : float
        Eigenvalues below ``tol · max eigenvalue`` of the unit-diagonal scaled matrix
        count as zero.

    Returns
    -------
    ndarray, shape (u, d)
        Orthonormal basis of the (scaled-back) null space, d = rank defect.
    """
    d = np.sqrt(np.abs(np.diag(N)))
    zero_cols = d == 0
    s = np.where(zero_cols, 1.0, 1.0 / np.where(zero_cols, 1.0, d))
    Ns = N * s[:, None] * s[None, :]
    Ns[zero_cols, :] = 0.0
    Ns[:, zero_cols] = 0.0
    w, V = np.linalg.eigh(Ns)
    top = max(float(w[-1]), 1e-300)
    null = V[:, w < tol * top]
    # back to parameter space (direction of change of the unscaled parameters)
    null = null * s[:, None]
    norms = np.linalg.norm(null, axis=0)
    return null / np.where(norms > 0, norms, 1.0)


def describe_defect(names: list[str], null: NDArray[np.float64], max_names: int = 8) -> list[str]:
    """Parameter names with the largest share in the null space, most involved first."""
    share = np.sum(null**2, axis=1)
    order = np.argsort(-share)
    keep = order[share[order] > 1e-6 * max(share.max(), 1e-300)]
    return [names[i] for i in keep[:max_names]]


def raise_if_singular(N: NDArray[np.float64], names: list[str], context: str = "") -> float:
    """Raise :class:`NotDeterminableError` naming the parameters if ``N`` is singular
    (eigenvalues below :data:`RANK_TOLERANCE` of the largest, :func:`null_space_of_normal`).

    A matrix whose :func:`scaled_condition_bound` is below half of 1/RANK_TOLERANCE has
    no such eigenvalue (the margin is far above the rounding error of either number at
    that size), and its eigenvalues are not computed.

    Returns
    -------
    float
        N's :func:`scaled_condition_bound` (when N is not singular).
    """
    bound = scaled_condition_bound(N)
    if bound < 0.5 / RANK_TOLERANCE:
        return bound
    null = null_space_of_normal(N)
    if null.shape[1] == 0:
        return bound
    involved = describe_defect(names, null)
    defect = null.shape[1]
    prefix = f"{context}: " if context else ""
    raise NotDeterminableError(
        f"{prefix}{defect} parameter combination(s) not determinable from the observations; "
        f"involved: {parameter_words(involved)}",
        parameters=involved,
        defect=defect,
    )
