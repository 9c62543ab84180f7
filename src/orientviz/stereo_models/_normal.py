"""Sparse normal equations of model blocks: per-model parameters and scalar point coordinates.

The independent-model and polynomial methods have observation equations of one form:
every *row* (one coordinate of one point in one model or strip) reads ::

    v = r + J · dθ_j − dX_t

with dθ_j the p corrections of the transformation parameters of model (or strip) j and
dX_t the correction of one scalar point coordinate t (or none: a fixed coordinate).
Because every point coordinate enters with −1 and a diagonal weight, the point part of
the normal matrix is *diagonal*; it is eliminated (Schur complement) leaving the reduced
system of the transformation parameters ::

    S dθ = bθ − C D⁻¹ bX,   S = U − C D⁻¹ Cᵀ,   dX = D⁻¹ (bX − Cᵀ dθ)

(U = JᵀWJ block diagonal, C = JᵀW·(−I), D = Σ w + prior weights). S is sparse: models
that share a point are coupled. It is factored densely for small systems and otherwise
by SuperLU with a minimum-degree ordering; the alternative of Ackermann's programs,
bandwidth minimisation (reverse Cuthill-McKee) and a banded Cholesky, is kept for
comparison (its band grows with the block's width; timings: ``benchmarks/bench_models.py``
and benchmarks/README.md). The bundle's reduced camera system is built for 6 × 6 image
blocks, so model blocks (4, 3 or 7 parameters) use this small module instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..adjust.rank import raise_if_singular
from ..bundle.precision import banded_selected_inverse
from ..errors import NotDeterminableError, parameter_words
from ._banded import band_order as _band_order
from ._banded import group_products as _group_products

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Reduced systems up to this size are factored (and diagnosed) densely.
DENSE_LIMIT: int = 2500
#: Scaled pivots below this count as a singular reduced system.
PIVOT_TOLERANCE: float = 1e-12
#: :func:`scalar_cofactors` takes the banded selected inverse when the half-band of the
#: reduced system (reverse Cuthill-McKee) is at most this fraction of its size.
BAND_FRACTION: float = 0.125


@dataclass
class Factor:
    """Cholesky factor of the (Jacobi-scaled) reduced matrix with ``solve``."""

    kind: str
    data: object
    scale: F64
    perm: I64 | None = None

    def solve(self, rhs: F64) -> F64:
        """Solve S x = rhs for (n,) or (n, k) right-hand sides."""
        s = self.scale if rhs.ndim == 1 else self.scale[:, None]
        b = rhs * s
        if self.kind == "dense":
            x = scipy.linalg.cho_solve((self.data, True), b, check_finite=False)
        elif self.kind == "splu":
            x = self.data.solve(b)
        else:
            p = self.perm
            z = scipy.linalg.cho_solve_banded((self.data, True), b[p], check_finite=False)
            x = np.empty_like(z)
            x[p] = z
        return x * s


def factor_spd(S: sp.spmatrix, names: list[str], context: str = "", solver: str = "splu") -> Factor:
    """Factor a sparse symmetric positive definite matrix; name parameters if singular.

    Parameters
    ----------
    S : scipy.sparse matrix, shape (n, n)
        The reduced normal matrix.
    names : list of str
        Parameter names for the diagnosis.
    context : str
        Prefix of the error message.
    solver : {"splu", "banded"}
        For systems above :data:`DENSE_LIMIT`: SuperLU with a minimum-degree ordering
        (symmetric mode; the default) or reverse Cuthill-McKee + banded Cholesky.

    Raises
    ------
    NotDeterminableError
        If S is singular (with the parameters of the null space for small systems).
    """
    S = sp.csr_matrix(S)
    n = S.shape[0]
    d = np.sqrt(np.abs(S.diagonal()))
    if np.any(d == 0):
        zero = [names[i] for i in np.flatnonzero(d == 0)[:8]]
        raise NotDeterminableError(
            f"{context}: parameters without any observation: {parameter_words(zero)}",
            parameters=zero,
            defect=int(np.sum(d == 0)),
        )
    s = 1.0 / d
    Ss = sp.csr_matrix(S.multiply(s[:, None]).multiply(s[None, :]))
    if n <= DENSE_LIMIT:
        A = Ss.toarray()
        try:
            c = scipy.linalg.cholesky(A, lower=True, check_finite=False)
            if np.min(np.diag(c)) ** 2 > PIVOT_TOLERANCE:
                return Factor("dense", c, s)
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
            pass
        raise_if_singular(A, names, context)
        raise NotDeterminableError(f"{context}: the reduced normal matrix is numerically singular")
    if solver == "splu":
        try:
            lu = sp.linalg.splu(
                sp.csc_matrix(Ss), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )  # fmt: skip
        except RuntimeError as exc:
            raise NotDeterminableError(
                f"{context}: the reduced normal matrix is singular ({exc}); check the datum "
                "(control) and weakly connected models"
            ) from None
        piv = np.abs(lu.U.diagonal())
        if np.min(piv) < PIVOT_TOLERANCE:
            bad = names[int(lu.perm_c[int(np.argmin(piv))])]
            raise NotDeterminableError(
                f"{context}: the reduced normal matrix is numerically singular at {bad}; "
                "check the datum (control) and weakly connected models",
                parameters=[bad],
            )
        return Factor("splu", lu, s)
    perm = reverse_cuthill_mckee(Ss, symmetric_mode=True).astype(np.int64)
    P = Ss[perm][:, perm].tocoo()
    low = P.row >= P.col
    kd = int(np.max(P.row[low] - P.col[low], initial=0))
    ab = np.zeros((kd + 1, n))
    ab[P.row[low] - P.col[low], P.col[low]] = P.data[low]
    try:
        c = scipy.linalg.cholesky_banded(ab, lower=True, overwrite_ab=True, check_finite=False)
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError) as exc:
        raise NotDeterminableError(
            f"{context}: the reduced normal matrix is singular ({exc}); check the datum "
            "(control) and weakly connected models"
        ) from None
    piv = c[0] ** 2
    if np.min(piv) < PIVOT_TOLERANCE:
        bad = names[int(perm[int(np.argmin(piv))])]
        raise NotDeterminableError(
            f"{context}: the reduced normal matrix is numerically singular at {bad}; check "
            "the datum (control) and weakly connected models",
            parameters=[bad],
        )
    return Factor("banded", c, s, perm)


class DeferredFactor:
    """:func:`factor_spd` of S made at the first solve (for a system whose cofactors may
    come from elsewhere, :func:`scalar_cofactors`). ``scale`` (the Jacobi scale) and the
    check for parameters without any observation are there at once."""

    def __init__(self, S: sp.spmatrix, names: list[str], context: str = "") -> None:
        d = np.sqrt(np.abs(S.diagonal()))
        if np.any(d == 0):
            factor_spd(S, names, context)  # raises: parameters without any observation
        self.scale = 1.0 / d
        self._args = (S, names, context)
        self._factor: Factor | None = None

    @property
    def factor(self) -> Factor:
        """The factor (made now if not yet)."""
        if self._factor is None:
            self._factor = factor_spd(*self._args)
        return self._factor

    @property
    def kind(self) -> str:
        return self.factor.kind

    @property
    def data(self) -> object:
        return self.factor.data

    @property
    def perm(self) -> I64 | None:
        return self.factor.perm

    def solve(self, rhs: F64) -> F64:
        """Solve S x = rhs (:meth:`Factor.solve`)."""
        return self.factor.solve(rhs)


@dataclass
class LinearSolution:
    """Corrections and the pieces needed for precision and for :meth:`resolve`.

    Rows read ``v = r + Ja · dθ + sign · dX_t`` (:func:`solve_sparse`); ``sign``,
    ``row_scalar`` and ``w`` are kept per row so that other misclosures can be solved
    with the same factorisation.
    """

    dtheta: F64 | None  # (n_models, p) or flat (n_reduced,); None: not solved
    dX: F64 | None  # (n_scalar,)
    factor: Factor | DeferredFactor
    G: sp.csr_matrix  # C · D⁻¹, (n_reduced, n_scalar)
    D: F64  # (n_scalar,) diagonal of the point part, prior weights included
    C: sp.csr_matrix | None = None
    JmW: sp.csr_matrix | None = None
    row_scalar: I64 | None = None
    w: F64 | None = None
    sign: F64 | None = None  # (n,) coefficient of the scalar unknown of each row
    prior_w: F64 | None = None  # (n_scalar,) weights of the scalar pseudo-observations
    S: sp.csr_matrix | None = None  # the reduced matrix (for :func:`scalar_cofactors`)

    def resolve(self, r: F64, prior_e: F64 | None = None) -> tuple[F64, F64]:
        """Corrections (dθ, dX) for other misclosures with the same factorisation.

        Used for repeated simulations of a linear problem. The normal matrix (design,
        weights, signs of the scalar unknowns, prior weights) is the one factored by
        :func:`solve_sparse`; only the right-hand side changes.

        Parameters
        ----------
        r : ndarray, shape (n,)
            Misclosures f(x) − l of the rows, in the units of the rows.
        prior_e : ndarray, shape (n_scalar,), optional
            Misclosures X − X_given of the pseudo-observations of the scalar unknowns
            (weighted control); None = 0 (the prior weights still count in the normal
            matrix).

        Returns
        -------
        dtheta : ndarray
            Reduced corrections, shaped like :attr:`dtheta` (flat when made without a
            solve, ``solve=False``).
        dX : ndarray, shape (n_scalar,)
            Corrections of the scalar unknowns.

        Raises
        ------
        ValueError
            If the solution does not carry the row data (not made by
            :func:`solve_sparse`) or ``r`` has the wrong length.
        """
        if self.row_scalar is None or self.w is None or self.sign is None or self.C is None:
            raise ValueError("resolve: this LinearSolution carries no row data (sign, w)")
        r = np.asarray(r, dtype=float)
        if r.shape != self.w.shape:
            raise ValueError(f"resolve: expected {self.w.size} misclosures, got {r.shape}")
        bX = _scalar_rhs(self.row_scalar, self.sign, self.w, r, self.D.size)
        if prior_e is not None and self.prior_w is not None:
            bX = bX - self.prior_w * np.asarray(prior_e, dtype=float)
        dt = self.factor.solve(-(self.JmW @ r) - self.G @ bX)
        dX = (bX - self.C.T @ dt) / self.D
        return (dt if self.dtheta is None else dt.reshape(self.dtheta.shape)), dX


def _scalar_rhs(row_scalar: I64, sign: F64, w: F64, r: F64, n_scalar: int) -> F64:
    """Right-hand side −Σ w·sign·r of the scalar unknowns (rows without one skipped)."""
    has = (row_scalar >= 0) & (sign != 0)
    return -np.bincount(row_scalar[has], (w * r * sign)[has], minlength=n_scalar)


def solve_rows(
    row_model: I64,
    J: F64,
    row_scalar: I64,
    w: F64,
    r: F64,
    n_models: int,
    n_scalar: int,
    *,
    prior_w: F64 | None = None,
    prior_e: F64 | None = None,
    names: list[str] | None = None,
    context: str = "",
    solve: bool = True,
) -> LinearSolution:
    """Least-squares corrections for rows ``v = r + J dθ_j − dX_t`` (see module docstring).

    Parameters
    ----------
    row_model : ndarray of int, shape (n,)
        Model (or strip) j of each row.
    J : ndarray, shape (n, p)
        Derivatives of each row by the p parameters of its model.
    row_scalar : ndarray of int, shape (n,)
        Scalar point-coordinate unknown t of each row, −1 for a fixed coordinate.
    w : ndarray, shape (n,)
        Weights 1/σ² of the rows.
    r : ndarray, shape (n,)
        Misclosures f(x) − l at the current values.
    n_models, n_scalar : int
        Numbers of models and scalar unknowns.
    prior_w, prior_e : ndarray, shape (n_scalar,), optional
        Weights and current misclosures (X − X_given) of pseudo-observations of the
        scalar unknowns (weighted control); 0 weight where there is none.
    names : list of str, optional
        Names of the n_models·p parameters (for singularity messages).
    context : str
        Prefix for error messages.
    solve : bool
        False: the normal equations only, for cofactors (:func:`scalar_cofactors`) and
        :meth:`LinearSolution.resolve`; ``dtheta`` and ``dX`` are None and S is factored
        when first solved with (:class:`DeferredFactor`).

    Returns
    -------
    LinearSolution
    """
    n, p = J.shape
    nt = n_models * p
    cols = (row_model[:, None] * p + np.arange(p)[None, :]).ravel()
    rows = np.repeat(np.arange(n), p)
    Jm = sp.csr_matrix((J.ravel(), (rows, cols)), shape=(n, nt))
    sol = solve_sparse(
        Jm, row_scalar, -np.ones(n), w, r, n_scalar,
        prior_w=prior_w, prior_e=prior_e,
        names=names or [f"model{k // p}.p{k % p}" for k in range(nt)],
        context=context, solve=solve,
    )  # fmt: skip
    if sol.dtheta is not None:
        sol.dtheta = sol.dtheta.reshape(n_models, p)
    return sol


def scalar_cofactors(
    sol: LinearSolution, groups: I64, chunk: int = 512, *, centres: F64 | None = None
) -> F64:
    """Cofactor blocks of groups of scalar unknowns (e.g. the X, Y, Z of each point).

    Q_XX = D⁻¹ + G ᵀ S⁻¹ G restricted to the groups. A group's block needs S⁻¹ only
    between the parameters of the models that hold its unknowns, which are coupled in S:
    for a large S whose band (reverse Cuthill-McKee) is narrow (:data:`BAND_FRACTION`)
    these entries come from the banded selected inverse
    (:func:`orientviz.bundle.precision.banded_selected_inverse`, two band
    factorisations' work), else from solves with the columns of G.

    Parameters
    ----------
    sol : LinearSolution
    groups : ndarray of int, shape (g, k)
        Scalar unknown indices per group (−1 = not an unknown, gives 0 rows/columns).
    chunk : int
        Groups solved at once.
    centres : ndarray, shape (n_models, 2), optional
        Positions (m) of the models whose parameters are the reduced unknowns (p each,
        consecutive, as :func:`solve_rows` numbers them): the band's order is then also
        sought across the strips (:func:`orientviz.bundle.reduced.geometric_orderings`),
        the narrowest taken.

    Returns
    -------
    ndarray, shape (g, k, k)
    """
    g, k = groups.shape
    if sol.S is not None and sol.S.shape[0] > DENSE_LIMIT:
        out = _banded_cofactors(sol, groups, chunk, centres)
        if out is not None:
            return out
    out = np.zeros((g, k, k))
    Gc = sp.csc_matrix(sol.G)
    for s0 in range(0, g, chunk):
        grp = groups[s0 : s0 + chunk]
        valid = grp >= 0
        idx = np.where(valid, grp, 0).ravel()
        cols = Gc[:, idx].toarray()
        Z = sol.factor.solve(cols)
        Gs = cols.reshape(cols.shape[0], -1, k)
        Zs = Z.reshape(Z.shape[0], -1, k)
        blk = np.einsum("nga,ngb->gab", Gs, Zs)
        dinv = np.where(valid, 1.0 / sol.D[idx].reshape(-1, k), 0.0)
        blk += np.einsum("ga,ab->gab", dinv, np.eye(k))
        blk *= (valid[:, :, None] & valid[:, None, :]).astype(float)
        out[s0 : s0 + chunk] = blk
    return out


def solve_sparse(
    Ja: sp.spmatrix,
    row_scalar: I64,
    sign: F64,
    w: F64,
    r: F64,
    n_scalar: int,
    *,
    prior_w: F64 | None = None,
    prior_e: F64 | None = None,
    names: list[str] | None = None,
    context: str = "",
    solve: bool = True,
) -> LinearSolution:
    """Least-squares corrections for rows ``v = r + Ja[i] · da + sign_i · dX_t``.

    The general form of :func:`solve_rows`: ``Ja`` (sparse, rows × reduced unknowns)
    may couple any reduced unknowns (model parameters, parameters shared by groups of
    models, offsets of auxiliary data); every row still has at most one scalar point
    coordinate t (``row_scalar``, −1 none) with coefficient ``sign`` (−1 for model rows,
    +1 for direct observations of a coordinate), so the point part stays diagonal and is
    eliminated.

    With ``solve`` False only the normal equations are formed (as :func:`solve_rows`).

    Returns
    -------
    LinearSolution
        ``dtheta`` is the flat vector of reduced corrections.
    """
    Ja = sp.csr_matrix(Ja)
    n, na = Ja.shape
    sign = np.broadcast_to(np.asarray(sign, dtype=float), (n,)).copy()
    has = (row_scalar >= 0) & (sign != 0)
    Jx = sp.csr_matrix((sign[has], (np.flatnonzero(has), row_scalar[has])), shape=(n, n_scalar))
    JaW = sp.csr_matrix(Ja.T.multiply(w[None, :]))
    U = JaW @ Ja
    C = sp.csr_matrix(JaW @ Jx)
    D = np.bincount(row_scalar[has], w[has] * sign[has] ** 2, minlength=n_scalar)
    bX = _scalar_rhs(row_scalar, sign, w, r, n_scalar)
    if prior_w is not None:
        D = D + prior_w
        bX = bX - prior_w * prior_e
    if np.any(D <= 0):
        bad = np.flatnonzero(D <= 0)[:5]
        raise NotDeterminableError(
            f"{context}: point coordinate(s) without observations: {bad.tolist()}",
            defect=int(np.sum(D <= 0)),
        )
    bt = -(JaW @ r)
    G = sp.csr_matrix(C.multiply(1.0 / D[None, :]))
    S = U - G @ C.T
    names = names or [f"u{k}" for k in range(na)]
    if not solve:
        fac = DeferredFactor(S, names, context)
        return LinearSolution(None, None, fac, G, D, C, JaW, row_scalar, w, sign, prior_w, S)
    fac = factor_spd(S, names, context)
    dt = fac.solve(bt - G @ bX)
    dX = (bX - C.T @ dt) / D
    return LinearSolution(dt, dX, fac, G, D, C, JaW, row_scalar, w, sign, prior_w, S)


def _banded_cofactors(
    sol: LinearSolution, groups: I64, chunk: int, centres: F64 | None = None
) -> F64 | None:
    """:func:`scalar_cofactors` by the banded selected inverse of S, ordered (:func:`_band_order`)
    on S's pattern and the pairs of reduced unknowns a group's block reads (so that all lie
    in the band); None when the band is wide."""
    s = sol.factor.scale  # Jacobi scale: S⁻¹ = s (s S s)⁻¹ s
    Ss = sp.csr_matrix(sol.S.multiply(s[:, None]).multiply(s[None, :]))
    n = Ss.shape[0]
    Gc = sp.csc_matrix(sol.G)
    g, k = groups.shape
    # the entries needed: S's and those between the unknowns of a group's columns of G
    valid = groups >= 0
    member = sp.csr_matrix(
        (np.ones(int(valid.sum())), (groups[valid], np.nonzero(valid)[0])), shape=(Gc.shape[1], g)
    )
    H = abs(Gc) @ member  # (n, g): the reduced unknowns each group's block reads
    graph = (abs(Ss) + H @ H.T).tocsr()
    pos, kd = _band_order(graph, centres)
    if kd > BAND_FRACTION * n:
        return None
    P = Ss.tocoo()
    pr, pc = pos[P.row], pos[P.col]
    low = pr >= pc
    ab = np.zeros((kd + 1, n))
    ab[pr[low] - pc[low], pc[low]] = P.data[low]
    try:
        cb = scipy.linalg.cholesky_banded(ab, lower=True, overwrite_ab=True, check_finite=False)
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        return None
    if np.min(cb[0] ** 2) < PIVOT_TOLERANCE:  # numerically singular: the factor says why
        return None
    Zb = banded_selected_inverse(cb, 48)
    out = np.zeros((g, k, k))
    for s0 in range(0, g, chunk):
        out[s0 : s0 + chunk] = _group_products(Gc, groups[s0 : s0 + chunk], Zb, pos, s)
    dinv = np.where(valid, 1.0 / sol.D[np.where(valid, groups, 0)], 0.0)
    out += np.einsum("ga,ab->gab", dinv, np.eye(k))
    return out
