"""The independent-models design, live: one factorisation per structure, updates per change.

The design of a block adjusted by independent models (:func:`orientviz.design.assess_models`
runs :func:`orientviz.stereo_models.independent_models` with precision) needs the 3 × 3
cofactor blocks of every tie point and projection centre. :class:`LiveModels` gets them
from the models' normal equations linearised once at the design's geometry:

* rows v = J dθ_j − dX_s (model j, scalar point coordinate s; the model coordinates of
  :func:`orientviz.stereo_models.form_models`, weights 1/σ² of σ_xy, σ_xy, σ_z as
  ``independent_models`` sets them by default); control coordinates weighted with
  1/σ² (``points.sigma``);
* the point part is diagonal (D) and eliminated: S = U − C D⁻¹ Cᵀ over the 7 parameters
  of every model, formed by 7 × 7 blocks of pairs of models, ordered for the narrowest band
  (reverse Cuthill-McKee or a numbering across the strips) and factored as a band;
* Q_XX = D⁻¹ + Gᵀ S⁻¹ G (G = C D⁻¹) at each point's 3 × 3 block needs S⁻¹ only at pairs of
  models that share a point, which lie inside the band: the banded selected inverse
  (:func:`orientviz.bundle.precision.banded_selected_inverse`) gives them, so the base costs
  about two band factorisations instead of one solve per point coordinate;
* with auxiliary data (statoscope, APR, GNSS; offsets per strip, adjusted jointly as
  ``independent_models`` does) the offsets g are a border: with E = S_θg, Y = S⁻¹E and
  F̃ = F − EᵀY, Q_XX gains Hᵀ F̃⁻¹ H, H = Yᵀ G_θ − G_g (a band solve with one column per
  offset);
* a control change of a point (weights of its three coordinates) is a Woodbury step of
  rank ≤ 3 on Q_XX: Q' = Q − U M Uᵀ, U = Q[:, s], M = (I + Δw U[s])⁻¹ Δw, with Q[:, s]
  from the factor (one solve with three right-hand sides) less the earlier steps' terms.

:meth:`LiveModels.sync` compares the block's control (``points.sigma``) with the design's
and applies every difference as such a step, so the studio's undo is a step too. Every
number equals ``assess_models`` of the same block up to the convergence of its iteration
(``tests/design/test_models_live.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..blas import blas_threads as _blas
from ..block import Block
from ..bundle.precision import BandSolver, banded_selected_inverse
from ..bundle.reduced import geometric_orderings
from ..errors import NotDeterminableError
from ..rotation import skew
from ..stereo_models import (
    check_datum,
    default_model_sigma,
    form_models,
    joint_setup,
    tie_setup,
)
from ._base import TAKAHASHI_BLOCK
from ._live_parts import _weights
from ._methods import models_quality
from ._quality import DesignQuality
from ._steps import COND_LIMIT

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: After this many steps the normal equations are formed and factored again.
MAX_STEPS: int = 40
#: Scaled pivots of the band factor below this count as singular.
PIVOT_TOLERANCE: float = 1e-12
#: The Jacobi-scaled reduced border F̃ of the offsets counts as singular beyond this
#: condition: an undeterminable offset leaves F̃ singular up to the rounding of the band
#: solve F − Eᵀ S⁻¹ E (measured 1e13–1e14 for free height offsets, a few hundred when
#: they are held).
BORDER_COND_LIMIT: float = 1e10
#: What a factorisation sets (restored when a change fails).
_FACTOR_STATE = ("_D", "_G", "_scale", "_perm", "_at", "_cb", "kd", "_H", "_Fi", "_quality")


class LiveModels:
    """The independent-models design of a block, updated per control change.

    Parameters
    ----------
    block : Block
        A design block (planned geometry, error-free observations, weighted control,
        ``images.strip`` set). Its point roles and σ are read again by :meth:`sync`.
    spec : dict
        Needs ``base_m`` (air base, m).
    level : float
        Probability of the confidence ellipsoids.
    auxiliary : list of Auxiliary, optional
        Statoscope / APR / GNSS data with offsets per strip, adjusted jointly (as
        ``assess_models`` does): a border of the reduced system.
    blas_threads : int or None
        BLAS threads of the work (None: the process's).

    Raises
    ------
    NotDeterminableError, DatumDefectError
        If models cannot be formed, the control gives no datum or the normal equations
        are singular.
    """

    def __init__(
        self, block: Block, spec: dict[str, Any], *, level: float = 0.95,
        auxiliary: list | None = None, blas_threads: int | None = 1,
    ) -> None:  # fmt: skip
        self.block, self.spec, self.level = block, spec, level
        self.auxiliary = list(auxiliary or [])
        self.blas_threads = blas_threads
        with _blas(blas_threads):
            self._build()

    # ------------------------------------------------------------------ the base
    def _build(self) -> None:
        b = self.block
        ms = form_models(b)
        su = tie_setup(b, ms, control="weighted", use_centres=True)
        if not self.auxiliary:  # with auxiliary data the normal equations tell (as there)
            check_datum(su, ms, need_xy=True, need_z=True)
        s_xy, s_z = default_model_sigma(b, ms)
        wc = np.array([1 / s_xy**2, 1 / s_xy**2, 1 / s_z**2])
        j, m = su.row_model, su.m
        # ∂(λ R m + T)/∂(rotation-vector increment, λ, T) at the design's geometry: λ = 1,
        # R and T of the models' start (the left image's orientation), where the
        # error-free model coordinates fit without correction
        R = ms.start_rotation[j]
        Rm = np.einsum("nij,nj->ni", R, m)
        J = np.zeros((j.size, 3, 7))
        J[:, :, :3] = -(R @ skew(m))
        J[:, :, 3] = Rm
        J[:, :, 4:] = np.eye(3)
        sc = su.scalar[su.row_point]  # (k, 3) scalar unknown of each row coordinate
        if np.any(su.scalar < 0):
            raise NotDeterminableError(
                "a live models design needs weighted control (σ > 0)", parameters=[]
            )
        n, ns = ms.n_models, su.n_scalar
        JW = J * wc[None, :, None]
        Ublk = np.zeros((n, 7, 7))
        np.add.at(Ublk, j, JW.transpose(0, 2, 1) @ J)
        self._C = -JW  # (k, 3, 7): the entries of C = Jᵀ W · (−1) of each row coordinate
        self._rows = (j, sc)
        self._D0 = np.bincount(sc.ravel(), np.tile(wc, j.size), minlength=ns)
        self._aux = None
        if self.auxiliary:  # rows v = dX_s + Σ_g a_g dg (readings of one coordinate each)
            js = joint_setup(b, ms, su, wc, None, "model", None, self.auxiliary)
            a, asc = js.aux, js.aux_scalar
            if np.any(asc < 0):
                raise NotDeterminableError(
                    "a live models design needs weighted control (σ > 0)", parameters=[]
                )
            Jg = a.jacobian_global()  # (rows, na)
            self._D0 += np.bincount(asc, a.w, minlength=ns)
            Cg = np.zeros((ns, Jg.shape[1]))  # Cgᵀ: C_g[g, s] = Σ w a_g over the rows of s
            np.add.at(Cg, asc, Jg * a.w[:, None])
            self._aux = (Cg.T.copy(), Jg.T @ (Jg * a.w[:, None]))
        self._Ublk = Ublk
        self.su, self.ms, self.n = su, ms, n
        self._pairs = _pair_structure(su.row_point, j, n)
        self._centres = b.images.X0[ms.models].mean(axis=1)  # of the models, for the order
        self._tie_of = np.full(b.n_points, -1, np.int64)
        self._tie_of[su.tie_points] = np.arange(su.tie_points.size)
        self._sigma = b.points.sigma.copy()  # the control the terms belong to
        self._refactor()

    def _refactor(self) -> None:
        """Factor and invert for the current weights; no steps."""
        self._factor()
        self._Q = self._base_blocks()
        self._steps: list[tuple[F64, F64]] = []
        self._quality = self._assemble()

    def _factor(self) -> None:
        """S = U − C D⁻¹ Cᵀ of the current weights by 7 × 7 blocks of pairs of models,
        ordered for the narrowest band (:func:`_model_order`) and factored as a band
        (Jacobi-scaled)."""
        j, sc = self._rows
        n = self.n
        D = self._D0 + self.su.prior_w
        pr = self._pairs
        a, bb = pr.a, pr.b
        # Σ over the rows' shared coordinates of C_aᵀ D⁻¹ C_b, summed per pair of models
        prod = (self._C[a] / D[sc[a]][:, :, None]).transpose(0, 2, 1) @ self._C[bb]
        S = -(pr.summed @ prod.reshape(-1, 49)).reshape(-1, 7, 7)  # (pairs of models, 7, 7)
        P, Q = pr.pair // n, pr.pair % n
        diag = P == Q
        S[diag] += self._Ublk[P[diag]]
        s = np.zeros((n, 7))
        s[P[diag]] = 1.0 / np.sqrt(np.einsum("kii->ki", S[diag]))
        S *= s[P][:, :, None] * s[Q][:, None, :]
        # ordered by models (each model's 7 parameters together, so that the band holds
        # whole 7 × 7 blocks of every pair of coupled models)
        pm, at = _model_order(n, P, Q, self._centres)
        kd = 7 * int(np.max(np.abs(at[P] - at[Q]), initial=0)) + 6
        perm = (7 * pm[:, None] + np.arange(7)).ravel()
        low = at[P] >= at[Q]
        r7 = np.arange(7)
        R = 7 * at[P][low][:, None, None] + r7[None, :, None]
        R, Cc = np.broadcast_arrays(R, 7 * at[Q][low][:, None, None] + r7[None, None, :])
        keep = R >= Cc
        ab = np.zeros((kd + 1, 7 * n))  # the Jacobi-scaled S[perm][:, perm], lower band
        ab[(R - Cc)[keep], Cc[keep]] = S[low][keep]
        try:
            cb = scipy.linalg.cholesky_banded(ab, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            cb = None
        if cb is None or np.min(cb[0]) ** 2 < PIVOT_TOLERANCE:
            raise NotDeterminableError(
                "the models design is not determinable (check the control and weakly "
                "connected models)",
                parameters=[],
            )
        self._D, self._G, self._scale = D, None, s.reshape(-1)
        # band position of each model (its 7 parameters from 7·at on)
        self._perm, self._at, self._cb, self.kd = perm, at, cb, kd
        self._H = self._Fi = None
        if self._aux is not None:  # the offsets' border: E = −Gθ Cgᵀ, F = Σ w aᵀa − Cg D⁻¹ Cgᵀ
            G = self._gmat()
            Cg, Faux = self._aux
            Gg = Cg / D[None, :]
            E = -(G @ Cg.T)
            Y = self._solve(E)
            Ft = Faux - Gg @ Cg.T - E.T @ Y  # F̃ = F − Eᵀ A⁻¹ E
            Ft = 0.5 * (Ft + Ft.T)
            if not _regular(Ft):
                raise NotDeterminableError(
                    "the offsets of the auxiliary data are not determinable by this models design",
                    parameters=[],
                )
            # Q_XX = D⁻¹ + Gθᵀ A⁻¹ Gθ + Hᵀ F̃⁻¹ H, H = Yᵀ Gθ − Gg
            self._H = (G.T @ Y).T - Gg
            self._Fi = np.linalg.inv(Ft)

    def _gmat(self) -> sp.csr_matrix:
        """G = C D⁻¹ (7n, n_scalar) of the current weights (formed when first needed)."""
        if self._G is None:
            j, sc = self._rows
            k, n = j.size, self.n
            rows = np.broadcast_to((7 * j)[:, None, None] + np.arange(7), (k, 3, 7)).ravel()
            cols = np.repeat(sc.ravel(), 7)
            vals = (self._C / self._D[sc][:, :, None]).ravel()
            self._G = sp.csr_matrix((vals, (rows, cols)), shape=(7 * n, self._D.size))
        return self._G

    def _solve(self, rhs: F64) -> F64:
        """S⁻¹ rhs for rhs (7n, r), with the band factor."""
        s, p = self._scale[:, None], self._perm
        b = (rhs * s)[p]
        if b.shape[1] >= 4:  # many columns: block products on views of the factor
            z = BandSolver(self._cb).solve(b)
        else:
            z = scipy.linalg.cho_solve_banded((self._cb, True), b, check_finite=False)
        out = np.empty_like(z)
        out[p] = z
        return out * s

    def _base_blocks(self) -> F64:
        """Q_XX at every tie's 3 × 3 block: D⁻¹ + Σ_ab g_aᵀ Z(j_a, j_b) g_b over the pairs
        of rows (a, b) of each tie, g the rows' columns of G = C D⁻¹ and Z = S⁻¹ inside
        the band."""
        j, sc = self._rows
        su, D, pr = self.su, self._D, self._pairs
        g = self._C / D[sc][:, :, None]  # (k, 3, 7)
        a, bb = pr.a, pr.b
        # the 7 × 7 blocks of Z, once per pair of models (positions P, Q in the band, each
        # model's parameters together): Z[7P + a, 7Q + b]
        n = self.n
        P, Qp = self._at[pr.pair // n], self._at[pr.pair % n]
        r7 = np.arange(7)
        u = 7 * P[:, None, None] + r7[None, :, None]
        v = 7 * Qp[:, None, None] + r7[None, None, :]
        if np.abs(u - v).max(initial=0) > self.kd:  # cannot be: models sharing a point are coupled
            raise NotDeterminableError("models sharing a point lie outside the band", parameters=[])
        sm = self._scale.reshape(n, 7)  # the Jacobi scale of each model's parameters
        # the whole band, then the blocks (asking for the 49 entries of every pair of
        # models with at= reads them one by one: slower for this narrow band)
        Zb = banded_selected_inverse(self._cb, TAKAHASHI_BLOCK)
        Z = Zb[np.minimum(u, v), np.abs(u - v)]
        Z *= sm[pr.pair // n][:, :, None] * sm[pr.pair % n][:, None, :]  # (pairs of models, 7, 7)
        blk = g[a] @ Z[pr.inv] @ g[bb].transpose(0, 2, 1)  # (pairs of rows, 3, 3)
        Q = np.zeros((su.scalar.shape[0], 3, 3))
        Q[pr.points] = np.add.reduceat(blk, pr.point_starts, axis=0)
        Q += np.einsum("ta,ab->tab", 1.0 / D[su.scalar], np.eye(3))
        if self._H is not None:
            Ht = self._H.T[su.scalar]  # (nt, 3, na)
            Q += Ht @ self._Fi @ Ht.transpose(0, 2, 1)
        return Q

    # ------------------------------------------------------------------ updates
    def _columns(self, s3: I64) -> F64:
        """The current Q_XX at the columns of scalar unknowns ``s3``: (n_scalar, r)."""
        G = self._gmat()
        Gs = G[:, s3].toarray()
        col = G.T @ self._solve(Gs)
        col[s3, np.arange(s3.size)] += 1.0 / self._D[s3]
        if self._H is not None:
            col += self._H.T @ (self._Fi @ self._H[:, s3])
        for U, M in self._steps:
            col -= U @ (M @ U[s3].T)
        return col

    def _step(self, tie: int, w_new: F64) -> None:
        """Change the weights of tie ``tie``'s coordinates to ``w_new`` (1/m²)."""
        su = self.su
        s3 = su.scalar[tie]
        dw = w_new - su.prior_w[s3]
        on = dw != 0
        if not on.any():
            return
        s3, dw = s3[on], dw[on]
        U = self._columns(s3)
        Uss = U[s3]
        Uss = 0.5 * (Uss + Uss.T)
        sq, sg = np.sqrt(np.abs(dw)), np.sign(dw)
        B = np.eye(dw.size) + sg[:, None] * (sq[:, None] * Uss * sq[None, :])
        if not np.isfinite(B).all() or np.linalg.cond(B) > COND_LIMIT:
            raise NotDeterminableError(
                "the changed models design is not determinable (too little control)",
                parameters=[],
            )
        M = sq[:, None] * np.linalg.solve(B, np.diag(sg)) * sq[None, :]
        M = 0.5 * (M + M.T)
        Ut = U[su.scalar]  # (nt, 3, r)
        self._Q = self._Q - Ut @ M @ Ut.transpose(0, 2, 1)
        self._steps.append((U, M))
        su.prior_w[s3] = w_new[on]

    def sync(self) -> DesignQuality:
        """The quality for the block's current control: every point whose σ differs from
        the design's is changed by one update (a new factorisation after
        :data:`MAX_STEPS` steps).

        Raises
        ------
        NotDeterminableError, DatumDefectError
            If the changed control leaves the models design without a datum (the
            design keeps its last state).
        """
        P = self.block.points
        now = np.where(np.isfinite(P.sigma), P.sigma, -1.0)
        was = np.where(np.isfinite(self._sigma), self._sigma, -1.0)
        changed = np.flatnonzero((now != was).any(axis=1) & (self._tie_of >= 0))
        if not changed.size:
            return self._quality
        su = self.su
        saved = (su.prior_w.copy(), su.known.copy(), su.given.copy(), self._Q, list(self._steps))
        kept = {k: self.__dict__[k] for k in _FACTOR_STATE}
        try:
            with _blas(self.blas_threads):
                for p in changed:
                    t = int(self._tie_of[p])
                    given = np.isfinite(P.sigma[p])
                    su.given[t] = given
                    su.known[t] = np.where(given, P.xyz[p], np.nan)
                if not self.auxiliary:
                    check_datum(su, self.ms, need_xy=True, need_z=True)
                for p in changed:
                    t = int(self._tie_of[p])
                    w = _weights(P.sigma[p])
                    if len(self._steps) >= MAX_STEPS:
                        su.prior_w[su.scalar[t]] = w
                    else:
                        self._step(t, w)
                if len(self._steps) >= MAX_STEPS:
                    self._refactor()
                else:
                    self._quality = self._assemble()
        except Exception:
            su.prior_w[:], su.known[:], su.given[:] = saved[0], saved[1], saved[2]
            self._Q, self._steps = saved[3], saved[4]
            self.__dict__.update(kept)  # the factor, if a new one was begun
            raise
        self._sigma = P.sigma.copy()
        return self._quality

    def quality(self) -> DesignQuality:
        """The quality of the design's control (see :meth:`sync` for the block's)."""
        return self._quality

    def _assemble(self) -> DesignQuality:
        su = self.su
        nb = su.tie_points.size
        return models_quality(
            self.block, self.spec, self._Q[:nb], su.tie_points, self._Q[nb:],
            su.centre_images, self.level,
        )  # fmt: skip


def _model_order(n: int, P: I64, Q: I64, centres: F64) -> tuple[I64, I64]:
    """The models' order of the narrowest band: reverse Cuthill-McKee on the graph of the
    coupled pairs of models (P, Q) or a numbering across the strips
    (:func:`orientviz.bundle.reduced.geometric_orderings` on the models' centres, m):
    (order, position of each model)."""
    graph = sp.csr_matrix((np.ones(P.size), (P, Q)), shape=(n, n))
    best = None
    for perm in [reverse_cuthill_mckee(graph, symmetric_mode=True)] + geometric_orderings(
        centres, (P, Q)
    ):
        perm = np.asarray(perm, np.int64)
        at = np.empty_like(perm)
        at[perm] = np.arange(n)
        bw = int(np.max(np.abs(at[P] - at[Q]), initial=0))
        if best is None or bw < best[0]:
            best = (bw, perm, at)
    return best[1], best[2]


def _regular(F: F64) -> bool:
    """Whether the reduced border F̃ (offsets) is regular: finite, positive diagonal and
    the condition of its Jacobi-scaled form below :data:`BORDER_COND_LIMIT`."""
    d = np.diag(F)
    if not np.isfinite(F).all() or np.any(d <= 0):
        return False
    s = 1.0 / np.sqrt(d)
    return bool(np.linalg.cond(F * s[:, None] * s[None, :]) < BORDER_COND_LIMIT)


@dataclass(frozen=True)
class _Pairs:
    """The ordered pairs (a, b) of rows of the same tie (or centre), grouped by tie, and
    their pairs of models: ``pair`` (unique codes P·n + Q), ``inv`` (each row pair's
    pair of models), ``summed`` (the sparse sum of the row pairs' terms per pair of
    models), ``points``/``point_starts`` (the ties and where their run of row pairs
    starts)."""

    a: I64
    b: I64
    pair: I64
    inv: I64
    summed: sp.csr_matrix
    points: I64
    points: I64
    point_starts: I64


def _pair_structure(row_point: I64, row_model: I64, n: int) -> _Pairs:
    """The :class:`_Pairs` of a models design's rows (tie of each row, model of each row;
    n models)."""
    order = np.argsort(row_point, kind="stable")
    tp = row_point[order]
    first = np.flatnonzero(np.r_[True, tp[1:] != tp[:-1]])
    size = np.diff(np.r_[first, tp.size])
    st, c = np.repeat(first, size), np.repeat(size, size)  # per sorted row: its group
    A = np.repeat(np.arange(tp.size), c)
    off = np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
    a, b = order[A], order[np.repeat(st, c) + off]
    pair, inv = np.unique(row_model[a] * n + row_model[b], return_inverse=True)
    inv = inv.reshape(-1)
    summed = sp.csr_matrix(
        (np.ones(inv.size), (inv, np.arange(inv.size))), shape=(pair.size, inv.size)
    )
    pts = row_point[a]  # sorted: the pairs come grouped by tie
    point_starts = np.flatnonzero(np.r_[True, pts[1:] != pts[:-1]])
    return _Pairs(a, b, pair, inv, summed, pts[point_starts], point_starts)
