"""Sparse normal equations of block problems: Schur complement and the reduced system.

A bundle block has three kinds of unknowns: 6 exterior-orientation elements per image
(X0, Y0, Z0 in m, ω, φ, κ in rad), 3 coordinates per object point (m) and, optionally,
``q`` group parameters (additional parameters of self-calibration). The normal
equations ::

    [ U   W   E  ] [dc]   [bc]
    [ Wᵀ  V   Gᵀ ] [dp] = [bp]        U: 6×6 blocks (images), V: 3×3 blocks (points)
    [ Eᵀ  G   F  ] [da]   [ba]

are never formed as a whole. The point blocks V_j are inverted (vectorised 3×3
inverses) and eliminated — the *Schur complement* — which leaves the reduced camera
system ::

    S dc = bc − W V⁻¹ bp,     S = U − W V⁻¹ Wᵀ,

a sparse matrix of 6×6 blocks: block (i, k) is non-zero only if images i and k see a
common point. The group parameters border it (``E``, ``F``) and are eliminated with a
few extra solves. After solving, the points follow by back-substitution
dp_j = V_j⁻¹ (bp_j − Σ W_ajᵀ dc_a − Σ G_ajᵀ da).

Solvers of the reduced system (:data:`SOLVERS`; ``"auto"``, the default, chooses from
the structure: :mod:`orientviz.bundle._solver_choice`), measured in
``benchmarks/bench_bundle.py --reduced`` and ``benchmarks/bench_unordered.py``:

* ``"banded"`` (chosen for strips) — Ackermann's bandwidth minimisation: the images are
  renumbered so that S becomes a narrow band, which is factored by LAPACK's banded
  Cholesky (``dpbtrf`` called directly on S's blocks scattered into its Fortran-ordered
  band storage; cost ∝ n·b², b the half-bandwidth). The numbering is the better
  (smaller measured bandwidth) of reverse Cuthill-McKee and a numbering *across* the
  strips from the projection centres (:func:`geometric_orderings`). On the bench's
  30 × 70 block: bandwidth 61 images across the strips against 118 for RCM (an image
  shares points with the images two along its strip, also in the neighbouring strips:
  two columns of 30 images further on, so a numbering by columns cannot do better);
  dpbtrf then runs at ~31 GFlop/s on one core, 56 ms for n = 12 600, kd = 371 (a
  plain bundle factors such a band in single precision, ``spbtrf`` 38 ms, and refines
  each solve: :mod:`orientviz.bundle._mixed_band`);
  factor + solve 0.08 s against 0.22 s (RCM),
  0.35 s (SuperLU) and 16.6 s (dense); on the 10 × 20 block 0.002 s against 0.003,
  0.010 and 0.021 s (``benchmarks/README.md``).
* ``"dense"`` (chosen for small or densely connected systems: unordered close-range
  networks) — dense Cholesky (LAPACK ``potrf``), n³/3 flops at LAPACK's best speed; S
  may then be formed densely as well (:func:`orientviz.bundle._schur.dense_schur`).
* ``"sparse"`` (chosen for large, sparse and wide systems, and for strips when its
  estimate is clearly lower than the band's) — a multifrontal Cholesky along a nested
  dissection of the image graph (:mod:`orientviz.bundle._dissection`,
  :mod:`orientviz.bundle._multifrontal`): separators of images numbered last, dense
  fronts per separator and leaf part factored by LAPACK/BLAS. On the bench's strip
  block ≈ 1.0 GFlop against the band's 1.7, but at a lower speed per flop (fronts with
  few pivots, extend-adds); replaces SciPy's SuperLU (no supernodes, ~5 × slower).

Singular systems never surface as ``LinAlgError``: :func:`raise_not_determinable`
names the parameters (null-space analysis for small systems, the failing pivot for
large ones).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..adjust.rank import describe_defect, null_space_of_normal
from ..errors import NotDeterminableError, parameter_words
from ._dissection import image_adjacency, nested_dissection
from ._mixed_band import MIN_BAND_FLOPS, mixed_band_factor
from ._multifrontal import factor_fronts, front_layout, solve_fronts
from ._solver_choice import SOLVER_CHOICES, choose_formation, choose_solver, image_blocks

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Names of the reduced-system solvers (what ``"auto"`` chooses from).
SOLVERS: tuple[str, ...] = ("banded", "dense", "sparse")
#: Reduced systems up to this many unknowns are diagnosed with a dense null space.
DENSE_DIAGNOSIS_LIMIT: int = 3000


def inv3(A: F64) -> F64:
    """Vectorised inverse of symmetric 3×3 matrices (n, 3, 3) by the adjugate.

    Raises ``ZeroDivisionError``-free: singular blocks give inf/NaN that callers check.
    """
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 1], A[:, 1, 2], A[:, 2, 2]
    c00 = d * f - e * e
    c01 = c * e - b * f
    c02 = b * e - c * d
    det = a * c00 + b * c01 + c * c02
    out = np.empty_like(A)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = 1.0 / det
        out[:, 0, 0] = c00 * r
        out[:, 0, 1] = out[:, 1, 0] = c01 * r
        out[:, 0, 2] = out[:, 2, 0] = c02 * r
        out[:, 1, 1] = (a * f - c * c) * r
        out[:, 1, 2] = out[:, 2, 1] = (b * c - a * e) * r
        out[:, 2, 2] = (a * d - b * b) * r
    return out


def geometric_orderings(X0: F64, pairs: tuple[I64, I64] | None = None) -> list[I64]:
    """Candidate image orders from projection centres (m, 3) in m: numbering across strips.

    Ackermann's rule for a narrow band: number the images along the *shorter* way
    through the block. The centres are projected on their two principal horizontal
    axes; along one axis the images are grouped into columns wherever consecutive
    coordinates jump by more than half the typical image spacing (median
    nearest-neighbour distance), and numbered column by column, sorted along the other
    axis inside a column. Both axes are returned.
    """
    xy = np.asarray(X0, dtype=float)[:, :2]
    if xy.shape[0] < 3:
        return []
    c = xy - xy.mean(axis=0)
    _, _, Vt = np.linalg.svd(c, full_matrices=False)
    if pairs is not None:  # nearest neighbour among the images sharing points
        i, k = pairs
        off = i != k
        dist = np.hypot(*(xy[i[off]] - xy[k[off]]).T)
        nn = np.full(xy.shape[0], np.inf)
        np.minimum.at(nn, i[off], dist)
        np.minimum.at(nn, k[off], dist)
        base = float(np.median(nn[np.isfinite(nn)])) if np.isfinite(nn).any() else 0.0
    else:
        from scipy.spatial import cKDTree

        d, _ = cKDTree(xy).query(xy, k=2)
        base = float(np.median(d[:, 1]))
    if not base > 0:
        return []
    out = []
    for ax in (0, 1):
        a = c @ Vt[ax]
        b = c @ Vt[1 - ax]
        o = np.argsort(a, kind="stable")
        col = np.empty(a.size, np.int64)
        col[o] = np.cumsum(np.concatenate([[0], np.diff(a[o]) > 0.5 * base]))
        out.append(np.lexsort((b, col)).astype(np.int64))
    return out


def _segments(keys: I64, n: int) -> tuple[I64, I64, I64]:
    """Stable order by ``keys`` and the start of each non-empty segment, plus its key."""
    order = np.argsort(keys, kind="stable")
    counts = np.bincount(keys, minlength=n)
    present = np.flatnonzero(counts)
    starts = (np.cumsum(counts) - counts)[present]
    return order, starts, present


@dataclass
class ReducedStructure:
    """Everything about a block problem's sparsity that stays fixed over the iterations.

    Parameters
    ----------
    obs_cam : ndarray of int, shape (n,)
        Image (camera-block) index of each observation.
    obs_pt : ndarray of int, shape (n,)
        Index of the point unknown of each observation, −1 if the point is fixed.
    n_cam, n_pt : int
        Numbers of images and of point unknowns.
    solver : {"auto", "banded", "dense", "sparse"}
        Solver of the reduced system; ``"auto"`` chooses from the structure
        (:func:`orientviz.bundle._solver_choice.choose_solver`). After construction
        ``solver`` is the one chosen, ``choice`` says why.
    orderings : list of ndarray
        Candidate image orders for ``"banded"`` (e.g. from :func:`geometric_orderings`);
        the one with the smallest bandwidth among these and reverse Cuthill-McKee wins.
    positions : ndarray, shape (m, 3), optional
        Projection centres (m): adds the two :func:`geometric_orderings` as candidates.
    formation : {"auto", "pairs", "dense"}
        How the Schur complement is formed (:func:`orientviz.bundle._schur.form_schur`);
        ``"auto"``: :func:`orientviz.bundle._solver_choice.choose_formation`.
    """

    obs_cam: I64
    obs_pt: I64
    n_cam: int
    n_pt: int
    solver: str = "auto"
    orderings: list = field(default_factory=list)
    positions: F64 | None = None
    formation: str = "auto"
    info: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.solver not in SOLVER_CHOICES:
            raise ValueError(
                f"expected a reduced-system solver out of {SOLVER_CHOICES}, got {self.solver!r}"
            )
        oc, op = self.obs_cam, self.obs_pt
        self.cam_order, self.cam_starts, self.cam_present = _segments(oc, self.n_cam)
        var = np.flatnonzero(op >= 0)
        o, s, present = _segments(op[var], self.n_pt)
        if present.size != self.n_pt:
            missing = np.setdiff1d(np.arange(self.n_pt), present)
            raise ValueError(f"point unknowns without observations: {missing[:5].tolist()}")
        self.pt_obs = var[o]  # observation indices sorted by point
        self.pt_starts = s
        # unique 6×6 blocks (i ≤ k), diagonal blocks always present
        m = self.n_cam
        self.block_i, self.block_k, self.n_pairs = image_blocks(oc, op, m, self.n_pt)
        self.n_blocks = self.block_i.size
        self.diag_block = np.searchsorted(self.block_i * m + self.block_k, np.arange(m) * (m + 1))
        self._pairs = None
        self._tracks = None
        self._symmetric = None  # S as block-sparse rows, for the mixed-precision refinement
        self._setup_solver()

    # ------------------------------------------------------------ pairs of rays
    def _form_pairs(self) -> None:
        """All ordered pairs of rays of the same point, grouped by the first ray (in
        ``pt_obs`` order; formed on first use — the precision's image–point cofactors:
        Σ k_j² of them)."""
        s = self.pt_starts
        k = np.diff(np.append(s, self.pt_obs.size))
        g = np.repeat(np.arange(self.n_pt), k)  # point of each sorted obs
        rep = k[g]
        A = np.repeat(np.arange(self.pt_obs.size), rep)
        off = np.arange(A.size) - np.repeat(np.cumsum(rep) - rep, rep)
        B = s[g[A]] + off
        del g, off
        self._pairs = dict(
            all_pairs=(self.pt_obs[A], self.pt_obs[B]),
            all_pairs_starts=np.cumsum(rep) - rep,  # start of each a-group, pt_obs order
        )

    def _pair(self, name: str):
        if self._pairs is None:
            self._form_pairs()
        return self._pairs[name]

    all_pairs = property(lambda self: self._pair("all_pairs"), doc="All ordered pairs (a, b).")
    all_pairs_starts = property(
        lambda self: self._pair("all_pairs_starts"), doc="Start of each a-group."
    )

    @property
    def tracks(self):
        """The rays grouped by track length (:class:`orientviz.bundle._tracks.TrackGroups`),
        formed on first use."""
        if self._tracks is None:
            from ._tracks import track_groups

            self._tracks = track_groups(self)
        return self._tracks

    def release_maps(self) -> None:
        """Drop the Schur formation's sparse maps and the sparse factor's work arena
        (formed again when needed)."""
        if self._tracks is not None:
            self._tracks._maps = None
        if getattr(self, "fronts", None) is not None:
            self.fronts.arena = None

    # ------------------------------------------------------------ layout of S
    def image_graph(self) -> sp.csr_matrix:
        """Adjacency (m, m) of images that share an unknown point (plus the diagonal)."""
        m = self.n_cam
        g = image_adjacency(self.block_i, self.block_k, m)
        return (g + sp.identity(m, dtype=g.dtype, format="csr")).tocsr()

    def _band_ordering(self) -> None:
        """The image numbering of the narrowest band (RCM or across the strips)."""
        m = self.n_cam
        if self.n_blocks == m * (m + 1) // 2:  # every image with every other: no band
            self.perm_img = self.pos_img = np.arange(m, dtype=np.int64)
            self.kd = 6 * m - 1
            self.info.update(ordering="any (complete image graph)", bandwidth_images=m - 1)
            self.info["kd"] = self.kd
            return
        if self.positions is not None:
            self.orderings = list(self.orderings) + geometric_orderings(
                self.positions, (self.block_i, self.block_k)
            )
        rcm = reverse_cuthill_mckee(self.image_graph(), symmetric_mode=True)
        best = None
        for name, perm in [("rcm", rcm)] + [
            (f"geometric{i}", o) for i, o in enumerate(self.orderings)
        ]:
            perm = np.asarray(perm, np.int64)
            if perm.shape != (m,) or np.unique(perm).size != m:
                continue
            pos = np.empty(m, np.int64)
            pos[perm] = np.arange(m)
            bw = int(np.max(np.abs(pos[self.block_i] - pos[self.block_k]), initial=0))
            self.info[f"bandwidth_{name}"] = bw
            if best is None or bw < best[0]:
                best = (bw, name, perm, pos)
        bw_img, name, perm, pos = best
        self.perm_img, self.pos_img = perm, pos
        self.info["ordering"] = name
        self.kd = 6 * bw_img + 5
        self.info.update(bandwidth_images=bw_img, kd=self.kd)

    def _setup_solver(self) -> None:
        m, n = self.n_cam, 6 * self.n_cam
        requested = self.solver
        if requested in ("auto", "banded"):
            self._band_ordering()
        self.choice = choose_solver(
            requested,
            m,
            getattr(self, "kd", None),
            self.block_i,
            self.block_k,
            sparse_estimate=lambda: (self.dissection.flops, self.dissection.n_nodes),
        )
        self.solver = self.choice.solver
        if self.formation == "auto":
            self.formation = choose_formation(self.solver, m, self.n_pt, self.n_pairs)
        self.info.update(
            solver=self.solver, solver_reason=self.choice.reason, formation=self.formation
        )
        if self.solver == "banded":
            if not hasattr(self, "kd"):
                self._band_ordering()
            # LAPACK's lower band storage ab[d, j] = S[j + d, j] in Fortran order, i.e.
            # the C-ordered (n, kd + 1) array abT[j, d]: index j·(kd + 1) + d. Entry (r, c)
            # of block (i, k) is S[6p_i + r, 6p_k + c] (p: position in the band order):
            # for p_i ≥ p_k in the lower band at column 6p_k + c, else mirrored to column
            # 6p_i + r; the upper half of a diagonal block goes to one spare slot at the end
            w = self.kd + 1
            pi, pk = self.pos_img[self.block_i], self.pos_img[self.block_k]
            r6 = np.arange(6)
            lo = (r6[:, None] - r6[None, :]) + w * r6[None, :]  # (r, c) → c·w + r − c
            upper = pi < pk
            p_lo = np.where(upper, pi, pk)
            base = 6 * w * p_lo + 6 * np.abs(pi - pk)
            dst = (
                base[:, None] + np.stack([lo.reshape(-1), lo.T.reshape(-1)])[upper.astype(np.intp)]
            )
            dst[np.flatnonzero(pi == pk)[:, None], np.flatnonzero(np.triu(np.ones((6, 6)), 1))] = (
                n * w
            )
            self.band_dst = dst.reshape(-1)
            self.scalar_perm = (6 * self.perm_img[:, None] + np.arange(6)).reshape(-1)
        elif self.solver == "sparse":
            diss = self.dissection
            self.fronts = front_layout(diss, self.block_i, self.block_k)
            self.info.update(
                ordering="nested dissection",
                fronts=diss.n_nodes,
                flops=float(diss.flops),
                largest_separator=int(max(v.size for v in diss.pivots)),
            )

    @property
    def dissection(self):
        """The nested dissection of the image graph
        (:class:`orientviz.bundle._dissection.Dissection`; formed on first use, with
        geometric separators when ``positions`` are given)."""
        if getattr(self, "_diss", None) is None:
            self._diss = nested_dissection(self.block_i, self.block_k, self.n_cam, self.positions)
        return self._diss

    @property
    def n_reduced(self) -> int:
        return 6 * self.n_cam


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
            z, info = scipy.linalg.lapack.dpbtrs(self.data, rhs[p], lower=1, overwrite_b=1)
            if info != 0:  # pragma: no cover - arguments are ours
                raise ValueError(f"dpbtrs: illegal argument {-info}")
            out = np.empty_like(z)
            out[p] = z
            return out
        if self.kind == "sparse":
            return solve_fronts(st.fronts, self.data, rhs)
        if self.kind == "mixed":
            return self.data.solve(rhs)
        return scipy.linalg.cho_solve((self.data, True), rhs, check_finite=False)


def factor_reduced(
    st: ReducedStructure,
    blocks: F64,
    names: list[str] | None = None,
    dense: F64 | None = None,
    single: bool = False,
) -> Factor:
    """Factor S given its 6×6 blocks; a singular S raises :class:`NotDeterminableError`.

    ``dense``: S as a dense (6m, 6m) array (lower triangle used) when the formation made
    it (:func:`orientviz.bundle._schur.dense_schur`); it is overwritten by the factor.
    ``single``: a wide band may be factored in single precision with double-precision
    refinement of every solve (:mod:`orientviz.bundle._mixed_band`; kind ``"mixed"``) —
    only for factors that serve solves alone (not the precision's inverse).
    """
    n = st.n_reduced
    flat = blocks.reshape(-1)
    if single and st.solver == "banded" and n * float(st.kd) ** 2 >= MIN_BAND_FLOPS:
        mixed = mixed_band_factor(st, blocks, lambda: factor_reduced(st, blocks, names))
        if mixed is not None:
            return Factor(st, "mixed", mixed)
    try:
        if st.solver == "banded":
            ab = np.zeros(n * (st.kd + 1) + 1)  # + the spare slot (see _setup_solver)
            ab[st.band_dst] = flat
            # LAPACK directly on the Fortran-ordered band (no copy, no checks)
            c, info = scipy.linalg.lapack.dpbtrf(
                ab[:-1].reshape(n, st.kd + 1).T, lower=1, overwrite_ab=1
            )
            if info != 0:
                raise np.linalg.LinAlgError(f"{info}-th leading minor not positive definite")
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
    if n <= DENSE_DIAGNOSIS_LIMIT:
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
