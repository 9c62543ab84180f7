"""Rank-defect diagnosis: which parameters a normal matrix cannot determine.

Used by the engine instead of letting a ``LinAlgError`` escape: the null space of the
(Jacobi-scaled) normal matrix is computed and the parameters that take part in it are
named, largest share first.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import NotDeterminableError, parameter_words

#: Relative eigenvalue below which a direction counts as undetermined.
RANK_TOLERANCE: float = 1e-10


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


def raise_if_singular(N: NDArray[np.float64], names: list[str], context: str = "") -> None:
    """Raise :class:`NotDeterminableError` naming the parameters if ``N`` is singular."""
    null = null_space_of_normal(N)
    if null.shape[1] == 0:
        return
    involved = describe_defect(names, null)
    defect = null.shape[1]
    prefix = f"{context}: " if context else ""
    raise NotDeterminableError(
        f"{prefix}{defect} parameter combination(s) not determinable from the observations; "
        f"involved: {parameter_words(involved)}",
        parameters=involved,
        defect=defect,
    )
