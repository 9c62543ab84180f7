"""Solving the bundle's normal equations with a border of group parameters.

With self-calibration the reduced camera system S (points eliminated, see
:mod:`orientviz.bundle.reduced`) gains a border of q = G·k additional parameters ::

    [ S   E ] [dc]   [r ]
    [ Eᵀ  F ] [da] = [ra]

which is eliminated by block elimination: ``Fs = F − Eᵀ S⁻¹ E``, ``Fs da = ra − Eᵀ S⁻¹ r``,
``dc = S⁻¹ (r − E da)``. The pieces:

* :func:`solve_bordered` forms Fs exactly. With the banded factor S = L Lᵀ only the
  forward half is needed, ``Z = L⁻¹ E`` and ``Fs = F − ZᵀZ``; :func:`band_forward_solve`
  does it block-wise with dense triangular solves and products (BLAS level 3) instead
  of LAPACK's column-by-column banded solve. Still, for q ≈ the band width it costs
  about twice the factorisation of S (2·n·kd·q against n·kd² flops).
* :func:`form_preconditioner` forms the same Fs in single precision (half the time),
  only to precondition:
* :func:`solve_bordered_pcg` solves ``Fs da = …`` by conjugate gradients, applying
  Fs = F − Eᵀ S⁻¹ E to a vector (one banded solve with S and two products with the
  dense E per step), preconditioned with the Cholesky factor of an Fs formed once. The
  geometry hardly changes between Gauss-Newton iterations, so that factor stays a good
  preconditioner (the eigenvalues of Fs_old⁻¹·Fs stay close to 1).

The bundle (:meth:`orientviz.bundle.problem.BundleProblem.solve`) forms the preconditioner
in the first iteration that solves for the parameters, uses the conjugate gradients from
then on, forms Fs anew when they need more than ``BundleOptions.pcg_stale_steps`` steps, and falls
back to the exact :func:`solve_bordered` (which also names a singular border) when they
fail. ``BundleResult.reduced_info["ap_border"]`` of the result logs what each solve did.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.blas as _blas
from numpy.lib.stride_tricks import as_strided
from numpy.typing import NDArray

from ...errors import NotDeterminableError
from ..reduced import NormalEquations
from ._ap_normal import BorderE, dense

F64 = NDArray[np.float64]


def _skewed_block(L: F64, r0: int, r1: int, c0: int) -> F64:
    """Dense rows r0:r1, columns c0:r1 of a lower band matrix in LAPACK band storage.

    Element (i, j) of the block is band entry d = (r0 + i) − (c0 + j) of column c0 + j;
    a skewed strided view of a copy of the band columns, with zero rows for the
    diagonals d outside the band (d < 0 or d > kd), reads them all at once.
    """
    kd = L.shape[0] - 1
    w, h = r1 - c0, r1 - r0
    dmin, dmax = r0 - c0 - (w - 1), r0 - c0 + h - 1  # diagonals the block touches
    P = np.empty((dmax - dmin + 1, w), dtype=L.dtype)  # row d − dmin holds diagonal d
    lo, hi = max(dmin, 0), min(dmax, kd)
    P[: lo - dmin] = 0.0
    P[lo - dmin : hi - dmin + 1] = L[lo : hi + 1, c0:r1]
    P[hi - dmin + 1 :] = 0.0
    # (i, j) → row d − dmin = w − 1 + i − j, column j
    view = as_strided(
        P.reshape(-1)[(w - 1) * w :], shape=(h, w), strides=(w * P.itemsize, -(w - 1) * P.itemsize)
    )
    return view.copy()


def band_forward_solve(L: F64, B: F64) -> F64:
    """X = L⁻¹ B for a lower-banded triangular L in LAPACK lower band storage.

    Parameters
    ----------
    L : ndarray, shape (kd + 1, n)
        ``L[d, j]`` = L(j + d, j), as returned by ``scipy.linalg.cholesky_banded(...,
        lower=True)``; float64 or float32 (the computation follows its type).
    B : ndarray, shape (n, r)
        Right-hand sides.

    Returns
    -------
    ndarray, shape (n, r), C order

    Notes
    -----
    Row blocks of nb = kd + 1 rows: block I depends on block I − 1 only, so
    X_I = L_II⁻¹ (B_I − L_I,I−1 X_I−1) — one triangular solve (``dtrsm``) and one
    triangular product (``dtrmm``; L_I,I−1 is strictly upper triangular) per block, each
    with all r columns at once (BLAS level 3). The transposed forms are used so that
    the C-ordered blocks reach BLAS without copies.
    """
    kd = L.shape[0] - 1
    n = L.shape[1]
    nb = kd + 1
    X = np.empty((n, B.shape[1]), dtype=L.dtype)
    trmm, trsm = _blas.get_blas_funcs(("trmm", "trsm"), (L,))
    for r0 in range(0, n, nb):
        r1 = min(r0 + nb, n)
        c0 = max(r0 - nb, 0)
        M = _skewed_block(L, r0, r1, c0)
        rhs = np.array(B[r0:r1], order="C", dtype=L.dtype)
        if r0 > c0:
            off = M[:, : r0 - c0]
            if r1 - r0 == nb:  # Xᵀ_I−1 L_I,I−1ᵀ with L_I,I−1ᵀ strictly lower triangular
                t = trmm(1.0, off.T, X[c0:r0].T, side=1, lower=1)
                rhs -= t.T
            else:
                rhs -= off @ X[c0:r0]
        # X_Iᵀ = rhsᵀ L_IIᵀ⁻¹ (L_IIᵀ upper triangular)
        d = np.ascontiguousarray(M[:, r0 - c0 :])
        X[r0:r1] = trsm(1.0, d.T, rhs.T, side=1, lower=0).T
    return X


def band_backward_solve(L: F64, B: F64) -> F64:
    """X = L⁻ᵀ B for a lower-banded triangular L in LAPACK lower band storage.

    The transposed counterpart of :func:`band_forward_solve` (same storage, same
    blocking), so that ``band_backward_solve(L, band_forward_solve(L, B))`` = S⁻¹ B for
    S = L Lᵀ with BLAS level-3 work only.

    Parameters
    ----------
    L : ndarray, shape (kd + 1, n)
        ``L[d, j]`` = L(j + d, j) (``scipy.linalg.cholesky_banded(..., lower=True)``).
    B : ndarray, shape (n, r)
        Right-hand sides.

    Returns
    -------
    ndarray, shape (n, r), C order

    Notes
    -----
    Row blocks of nb = kd + 1 rows from the bottom: X_I = L_IIᵀ⁻¹ (B_I − L_JIᵀ X_J) with J
    the block below I; L_JI is strictly upper triangular (``dtrmm``), L_II lower
    (``dtrsm`` with the transposed matrix).
    """
    kd = L.shape[0] - 1
    n = L.shape[1]
    nb = kd + 1
    X = np.empty((n, B.shape[1]), dtype=L.dtype)
    trmm, trsm = _blas.get_blas_funcs(("trmm", "trsm"), (L,))
    M_below = None  # rows of the block below (J), columns from this block's start
    for r0 in reversed(range(0, n, nb)):
        r1 = min(r0 + nb, n)
        c0 = max(r0 - nb, 0)
        M = _skewed_block(L, r0, r1, c0)  # [L_I,I−1  L_II]
        rhs = np.array(B[r0:r1], order="C", dtype=L.dtype)
        if r1 < n:
            r2 = min(r1 + nb, n)
            off = M_below[:, : r1 - r0]  # L_JI, rows r1:r2 (I is a full block here)
            if r2 - r1 == nb:  # (X_Jᵀ L_JI)ᵀ, L_JIᵀ strictly lower
                t = trmm(1.0, off.T, X[r1:r2].T, side=1, lower=1, trans_a=1)
                rhs -= t.T
            else:
                rhs -= off.T @ X[r1:r2]
        M_below = M
        d = np.ascontiguousarray(M[:, r0 - c0 :])  # L_II
        # X_Iᵀ = rhsᵀ L_II⁻¹: BLAS sees the C-ordered d as its transpose (upper), hence
        # trans_a
        X[r0:r1] = trsm(1.0, d.T, rhs.T, side=1, lower=0, trans_a=1).T
    return X


def _not_determinable(names):
    return NotDeterminableError(
        "the additional parameters are not determinable (singular); give ap_sigma",
        parameters=list(names),
    )


def solve_bordered(fac, E: F64, F: F64, rhs: F64, ba: F64, names: list[str]):
    """Solve the bordered system by forming Fs; return ``(dc, da, Fs, chol(Fs))``.

    Parameters
    ----------
    fac : orientviz.bundle.reduced.Factor
        Factor of S.
    E, F, rhs, ba : ndarray
        Border blocks and right-hand sides (see module docstring).
    names : list of str
        Names of the parameters of the border (for the error message).
    """
    E = dense(E)
    if fac.kind == "banded":
        p = fac.structure.scalar_perm
        B = np.empty((E.shape[0], E.shape[1] + 1))
        B[:, :-1] = E[p]
        B[:, -1] = rhs[p]
        Zz = band_forward_solve(fac.data, B)
        C = _blas.dsyrk(1.0, Zz.T)  # upper triangle of [Z z]ᵀ [Z z]
        q = E.shape[1]
        ZZ = np.triu(C[:q, :q]) + np.triu(C[:q, :q], 1).T
        Fs = F - ZZ
        ra = ba - C[:q, q]
    else:
        Y = fac.solve(E)
        Fs = F - E.T @ Y
        ra = ba - E.T @ fac.solve(rhs)
    try:
        c = scipy.linalg.cho_factor(Fs, lower=True, check_finite=False)
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        raise _not_determinable(names) from None
    da = scipy.linalg.cho_solve(c, ra, check_finite=False)
    dc = fac.solve(rhs - E @ da)
    return dc, da, Fs, c


def form_preconditioner(fac, E: F64, F: F64):
    """Cholesky factor of Fs = F − Eᵀ S⁻¹ E computed in single precision, or None.

    Only a preconditioner (:func:`solve_bordered_pcg` solves the exact system): the
    forward solve Z = L⁻¹ E, the dominant cost, runs at twice the float64 speed; the
    rounding (≈ 1e-7 relative, amplified by the cancellation in F − ZᵀZ) only adds a
    step or two to the conjugate gradients. None for non-banded factors or if the
    single-precision Fs is not positive definite (the caller then forms Fs exactly).
    """
    if fac.kind != "banded":
        return None
    if isinstance(E, BorderE):  # formed in single precision and row order at once
        E32 = E.permuted(fac.structure.pos_img)
    else:
        E32 = dense(E).astype(np.float32)[fac.structure.scalar_perm]
    Z = band_forward_solve(fac.data.astype(np.float32), E32)
    Fs = F - _blas.ssyrk(1.0, Z.T).astype(float)
    Fs = np.triu(Fs) + np.triu(Fs, 1).T  # the upper triangle of F − ZᵀZ, symmetrised
    try:
        return scipy.linalg.cho_factor(Fs, lower=True, check_finite=False)
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        return None


def solve_bordered_pcg(
    fac, E: F64, F: F64, rhs: F64, ba: F64, prec, tol: float = 1e-4, max_steps: int = 40
):
    """Solve the bordered system by preconditioned conjugate gradients on Fs.

    Parameters
    ----------
    fac : orientviz.bundle.reduced.Factor
        Factor of S.
    E : ndarray or orientviz.bundle.problem._ap_normal.BorderE
        Border of this iteration (only ``E @ v`` and ``E.T @ y`` are used).
    F, rhs, ba : ndarray
        Parameter block and right-hand sides of this iteration.
    prec : tuple
        ``scipy.linalg.cho_factor`` of an earlier Fs (the preconditioner).
    tol : float
        Stop when the preconditioned residual norm fell below ``tol`` times its start.
    max_steps : int
        Give up after this many steps.

    Returns
    -------
    dc, da : ndarray
        Corrections; ``None, None`` when the steps ran out or Fs turned out not to be
        positive definite along a search direction (the caller forms Fs).
    steps : int
        Conjugate-gradient steps taken (each one banded solve with S).
    """
    z0 = fac.solve(rhs)
    ra = ba - E.T @ z0

    # S⁻¹E d of every step is kept as a sum α·S⁻¹E d, so that S⁻¹E x (for dc) costs
    # no extra banded solve
    SEx = np.zeros_like(z0)

    def Fs(v):
        u = fac.solve(E @ v)
        return F @ v - E.T @ u, u

    x = np.zeros_like(ra)
    r = ra.copy()
    y = scipy.linalg.cho_solve(prec, r, check_finite=False)
    rho = float(r @ y)
    stop = tol**2 * rho
    d = y.copy()
    steps = 0
    while rho > stop and rho > 0:
        if steps == max_steps:
            return None, None, steps
        steps += 1
        w, u = Fs(d)
        dw = float(d @ w)
        if not dw > 0:
            return None, None, steps
        alpha = rho / dw
        x += alpha * d
        SEx += alpha * u
        r -= alpha * w
        y = scipy.linalg.cho_solve(prec, r, check_finite=False)
        rho_new = float(r @ y)
        d = y + (rho_new / rho) * d
        rho = rho_new
    dc = z0 - SEx
    return dc, x, steps


#: A dense S with a group of parameters per image (the border's per-point terms formed in
#: batches, :mod:`._ap_batches`: SfM cameras): Fs is formed exactly (:func:`solve_bordered`)
#: when (6m)²·q is at most this — its one multi-column solve with S costs less than the
#: conjugate gradients' ~10 steps of single solves and block products (measured on the real
#: SfM models, benchmarks/README.md), and the step is exact.
DENSE_EXACT_MAX: float = 2e7


def solve_border(prob, ne: NormalEquations, fac) -> tuple[F64, F64]:
    """The bundle's solve with additional parameters: (dc (6m,), da (q,)).

    Held parameters (``prob.run.border.hold``): the plain step, da = 0. A small dense S
    with a group per image (:data:`DENSE_EXACT_MAX`): the exact :func:`solve_bordered`.
    Otherwise conjugate
    gradients with the preconditioner (formed in single precision on first use, formed
    anew after ``prob.options.pcg_stale_steps`` steps) and, if they fail, the exact
    :func:`solve_bordered`. Appends what it did to ``prob.run.border.log``.
    """
    if prob.run.border.hold:
        prob.run.border.log.append("held")
        return fac.solve(ne.rhs), np.zeros(prob.q)
    if (
        fac.kind == "dense"
        and prob.ap.structure.batched
        and float(6 * prob.m) ** 2 * prob.q <= DENSE_EXACT_MAX
    ):
        dc, da, ne.Fs, prob.run.border.preconditioner = solve_bordered(
            fac, ne.ap.E, ne.ap.F, ne.rhs, ne.ap.ba, prob.ap.names
        )
        prob.run.border.log.append("Fs formed (dense S)")
        return dc, da
    dc = None
    tag = "E,F reused, " if ne.ap.reused else ""
    if prob.run.border.preconditioner is None:
        prob.run.border.preconditioner = form_preconditioner(fac, ne.ap.E_border, ne.ap.F)
        tag += "Fs formed (float32), " if prob.run.border.preconditioner is not None else ""
    if prob.run.border.preconditioner is not None:
        opts = prob.options
        dc, da, steps = solve_bordered_pcg(
            fac, ne.ap.E_border, ne.ap.F, ne.rhs, ne.ap.ba, prob.run.border.preconditioner,
            tol=opts.pcg_tol, max_steps=opts.pcg_max_steps,
        )  # fmt: skip
        prob.run.border.log.append(tag + f"cg{steps}")
        if dc is None or steps > opts.pcg_stale_steps:
            prob.run.border.preconditioner = None  # stale preconditioner: form Fs next time
    if dc is None:
        dc, da, Fs, prob.run.border.preconditioner = solve_bordered(
            fac, ne.ap.E, ne.ap.F, ne.rhs, ne.ap.ba, prob.ap.names
        )
        ne.Fs = Fs
        prob.run.border.log.append("Fs formed")
    return dc, da
