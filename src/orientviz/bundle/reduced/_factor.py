"""Factoring the reduced camera system S and solving with the factor.

The solver is the structure's (:attr:`ReducedStructure.solver
<orientviz.bundle.reduced.ReducedStructure>`, chosen by :mod:`._choice`):

* ``"banded"`` — S's blocks are scattered into LAPACK's lower band storage in the
  band-minimising image order (:mod:`._orderings`) and factored by the banded Cholesky
  (:func:`scipy.linalg.cholesky_banded`, LAPACK ``dpbtrf``; cost ≈ n·kd² flops, n = 6m
  unknowns, kd the half-bandwidth); solves by :func:`scipy.linalg.cho_solve_banded`.
* ``"dense"`` — the dense Cholesky (LAPACK ``dpotrf``, n³/3 flops); S may have been
  formed densely already (:func:`._schur.dense_schur`).
* ``"sparse"`` — the multifrontal Cholesky along a nested dissection of the image graph
  (:mod:`._dissection`, :mod:`._multifrontal`).

A singular S never surfaces as ``LinAlgError``: :func:`raise_not_determinable` names the
parameters (null-space analysis for small systems, the failing pivot for large ones).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ...adjust.rank import describe_defect, null_space_of_normal
from ...errors import NotDeterminableError, parameter_words
from ._multifrontal import factor_fronts, solve_fronts
from ._structure import ReducedStructure

F64 = NDArray[np.float64]


@dataclass
class Factor:
    """A factorisation of the reduced matrix S with ``solve(rhs)`` for (n,) or (n, k)."""

    structure: ReducedStructure
    kind: str
    data: object

    def solve(self, rhs: F64) -> F64:
        st = self.structure
        if self.kind == "banded":
            p = st.scalar_perm
            z = scipy.linalg.cho_solve_banded(
                (self.data, True), rhs[p], overwrite_b=True, check_finite=False
            )
            out = np.empty_like(z)
            out[p] = z
            return out
        if self.kind == "sparse":
            return solve_fronts(st.fronts, self.data, rhs)
        return scipy.linalg.cho_solve((self.data, True), rhs, check_finite=False)


def factor_reduced(
    st: ReducedStructure,
    blocks: F64,
    names: list[str] | None = None,
    dense: F64 | None = None,
) -> Factor:
    """Factor S given its 6×6 blocks; a singular S raises :class:`NotDeterminableError`.

    Parameters
    ----------
    st : ReducedStructure
        The structure (solver, ordering, band layout or fronts).
    blocks : ndarray, shape (n_blocks, 6, 6)
        S's blocks (i ≤ k) in the structure's order.
    names : list of str, optional
        The 6m parameter names (for the message of a singular S).
    dense : ndarray, shape (6m, 6m), optional
        S as a dense array (lower triangle used) when the formation made it
        (:func:`orientviz.bundle.reduced._schur.dense_schur`); overwritten by the factor.
    """
    n = st.n_reduced
    flat = blocks.reshape(-1)
    try:
        if st.solver == "banded":
            ab = np.zeros(n * (st.kd + 1) + 1)  # + the spare slot (see ReducedStructure)
            ab[st.band_dst] = flat
            # the Fortran-ordered (kd + 1, n) band as a view: LAPACK factors it in place
            c = scipy.linalg.cholesky_banded(
                ab[:-1].reshape(n, st.kd + 1).T, overwrite_ab=True, lower=True, check_finite=False
            )
            return Factor(st, "banded", c)
        if st.solver == "sparse":
            return Factor(st, "sparse", factor_fronts(st.fronts, blocks))
        S = dense_matrix(st, blocks, lower=True) if dense is None else dense
        if not np.isfinite(S[:: n + 1]).all():
            raise np.linalg.LinAlgError("non-finite diagonal")
        c, _ = scipy.linalg.cho_factor(S, lower=True, overwrite_a=True, check_finite=False)
        if not np.isfinite(c[:: n + 1]).all():
            raise np.linalg.LinAlgError("non-finite pivot")
        return Factor(st, "dense", c)
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError, RuntimeError, ValueError) as exc:
        raise_not_determinable(st, blocks, names, str(exc))
    raise AssertionError("unreachable")  # pragma: no cover


def dense_matrix(st: ReducedStructure, blocks: F64, lower: bool = False) -> F64:
    """The reduced matrix S as a dense (6m, 6m) array (original image order), in Fortran
    order (what LAPACK reads without a copy); ``lower``: only the lower triangle (and
    the diagonal blocks) is filled — what the dense Cholesky reads."""
    n, m = st.n_reduced, st.n_cam
    S = np.zeros((n, n), order="F")
    S4 = S.T.reshape(m, 6, m, 6)  # S4[i, r, k, c] = S[6k + c, 6i + r]
    if not lower:
        S4[st.block_k, :, st.block_i, :] = blocks.transpose(0, 2, 1)
    S4[st.block_i, :, st.block_k, :] = blocks  # diagonal blocks: Bᵀ
    return S


def raise_not_determinable(
    st: ReducedStructure, blocks: F64, names: list[str] | None, detail: str = ""
) -> None:
    """Raise :class:`NotDeterminableError` naming the parameters of a singular S."""
    n = st.n_reduced
    names = names or [f"c{i}" for i in range(n)]
    if n <= st.options.dense_diagnosis_limit:
        null = null_space_of_normal(dense_matrix(st, blocks))
        if null.shape[1]:
            involved = describe_defect(names, null)
            raise NotDeterminableError(
                f"{null.shape[1]} parameter combination(s) of the image orientations are not "
                f"determinable from the observations; involved: {parameter_words(involved)}",
                parameters=involved,
                defect=null.shape[1],
            )
    where = ""
    if st.solver == "sparse" and "at unknown" in detail:
        scalar = int(detail.rsplit(" ", 1)[-1])
        where = f" (the elimination broke down at {parameter_words([names[scalar]])})"
    if st.solver == "banded" and "minor" in detail:
        digits = [int(t) for t in detail.replace("-", " ").split() if t.isdigit()]
        if digits:
            scalar = int(st.scalar_perm[min(digits[0] - 1, n - 1)])
            where = f" (the elimination broke down at {parameter_words([names[scalar]])})"
    raise NotDeterminableError(
        "the reduced normal equations of the image orientations are singular or "
        f"numerically not positive definite{where}; check the datum and weakly connected "
        "images",
        parameters=[],
        defect=0,
    )
