"""Which solver factors the reduced camera system, and how it is formed: chosen from the structure.

The reduced system S (6 unknowns per image, points eliminated; see
:mod:`orientviz.bundle.reduced`) has a 6 × 6 block (i, k) wherever images i and k see
a common unknown point. Its shape tells which factorisation is cheapest:

* aerial strips, numbered across the strips, give a narrow band: LAPACK's banded
  Cholesky costs ≈ n·kd² flops (n = 6m unknowns, kd the half-bandwidth);
* small systems and densely connected ones (close-range networks where most images
  share points) are cheapest as one dense Cholesky, n³/3 flops, at LAPACK's best
  speed;
* large, sparse and wide systems need a fill-reducing ordering: the multifrontal
  factorisation along a nested dissection of the image graph costs the flops of its
  dense fronts (:attr:`orientviz.bundle.reduced._dissection.Dissection.flops`, known once the
  dissection is made) at a lower speed per flop, plus a fixed cost per front.

:func:`choose_solver` compares these estimates (relative speeds per flop and thresholds:
:class:`~orientviz.bundle.reduced.ReducedOptions`, measured with
``benchmarks/bench_unordered.py`` and ``benchmarks/bench_bundle.py --reduced``) and says why. The Schur complement itself is
formed either by pairs of rays of a point (cost ∝ the number of such pairs, the only
way for banded and sparse S) or, for a dense S, by dense products of the per-point
couplings (cost ∝ m²·p flops but at BLAS speed, :func:`orientviz.bundle.reduced._schur.dense_schur`);
:func:`choose_formation` picks the cheaper one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ._dissection import nested_dissection
from ._options import SOLVER_CHOICES, ReducedOptions

I64 = NDArray[np.int64]

#: Names of the reduced-system solvers (what ``"auto"`` chooses from).
SOLVERS: tuple[str, ...] = ("banded", "dense", "sparse")


@dataclass(frozen=True)
class SolverChoice:
    """The chosen solver of the reduced system and why.

    Attributes
    ----------
    solver : {"banded", "dense", "sparse"}
    requested : {"auto", "banded", "dense", "sparse"}
    reason : str
        One line for the log: the estimates compared (flops) or "requested".
    costs : dict
        Estimated cost of each factorisation considered, in dense-flop equivalents.
    """

    solver: str
    requested: str
    reason: str
    costs: dict


#: :func:`image_blocks`: the dense product BᵀB costs m²·p multiply-adds at BLAS speed, the
#: sparse one about this many of them per pair of rays of a point (Σ k²): between 500 and 1000
#: (m = 20 … 400 images, p = 1500 … 100 000 points, tracks of 3–8 rays, one thread).
DENSE_PATTERN_FLOPS_PER_PAIR: float = 500.0
#: :func:`image_blocks` forms B densely (float32) only up to this many entries (32 MB).
DENSE_PATTERN_MAX_ENTRIES: int = 2**23


def image_blocks(obs_cam: I64, obs_pt: I64, n_cam: int, n_pt: int) -> tuple[I64, I64, int]:
    """Blocks (i ≤ k) of S: pairs of images that share an unknown point, and the diagonal.

    Formed from the point–image incidence B (p × m) as the pattern of BᵀB, by a sparse
    product (cost ≈ Σ_j k_j², k_j the rays of point j) or, when that is larger, a dense
    single-precision one (m²·p flops at BLAS speed; :data:`DENSE_PATTERN_FLOPS_PER_PAIR`,
    at most :data:`DENSE_PATTERN_MAX_ENTRIES` entries of B). Both give the same pattern
    (B's entries are 0 and 1; BᵀB counts shared points exactly in single precision).

    Returns
    -------
    block_i, block_k : ndarray of int
        Images of each block, sorted by ``block_i * m + block_k``.
    n_pairs : int
        Number of pairs (a, b) of rays of the same point with image(a) ≤ image(b) —
        the work of the pair-wise Schur formation.
    """
    m = n_cam
    var = obs_pt >= 0
    c, p = obs_cam[var], obs_pt[var]
    k = np.bincount(p, minlength=n_pt).astype(np.int64)
    n_pairs = int(np.sum(k * (k + 1) // 2))
    dense = float(m) * m * n_pt / DENSE_PATTERN_FLOPS_PER_PAIR < float(np.sum(k * k))
    if n_pt and dense and m * n_pt <= DENSE_PATTERN_MAX_ENTRIES:
        B = np.zeros((n_pt, m), np.float32)
        B[p, c] = 1.0
        G = B.T @ B
        iu, ku = np.nonzero(np.triu(G) > 0)
        keys = iu.astype(np.int64) * m + ku
    else:
        B = sp.csr_matrix((np.ones(p.size, np.float32), (p, c)), shape=(n_pt, m))
        G = sp.triu(B.T @ B, format="coo")
        keys = G.row.astype(np.int64) * m + G.col
    keys = np.union1d(keys, np.arange(m, dtype=np.int64) * (m + 1))
    return keys // m, keys % m, n_pairs


def sparse_cost(block_i: I64, block_k: I64, m: int, positions=None) -> tuple[float, int]:
    """Flops of the multifrontal Cholesky of S and its number of fronts, from a nested
    dissection of the image graph (:func:`orientviz.bundle.reduced._dissection.nested_dissection`;
    ``positions``: projection centres, for geometric separators)."""
    diss = nested_dissection(block_i, block_k, m, positions)
    return diss.flops, diss.n_nodes


#: What each solver is, for the log.
_HOW = {"banded": "", "dense": "", "sparse": ", nested-dissection multifrontal Cholesky"}


def choose_solver(
    requested: str,
    m: int,
    kd: int | None,
    block_i: I64,
    block_k: I64,
    sparse_estimate: Callable[[], tuple[float, int]] | None = None,
    options: ReducedOptions | None = None,
) -> SolverChoice:
    """The solver of the reduced system for ``requested`` (``"auto"``: from the estimates).

    Parameters
    ----------
    requested : {"auto", "banded", "dense", "sparse"}
    m : int
        Number of images (S is 6m × 6m).
    kd : int or None
        Half-bandwidth (scalars) of S in the best image numbering found, if computed.
    block_i, block_k : ndarray of int
        The blocks of S (:func:`image_blocks`).
    sparse_estimate : callable, optional
        ``() -> (flops, fronts)`` of the sparse factorisation (default:
        :func:`sparse_cost` without positions); called only when it is considered.
    options : ReducedOptions, optional
        The rates and thresholds of the comparison (default: ``ReducedOptions()``).
    """
    o = ReducedOptions() if options is None else options
    if requested not in SOLVER_CHOICES:
        raise ValueError(
            f"expected a reduced-system solver out of {SOLVER_CHOICES}, got {requested!r}"
        )
    if requested != "auto":
        return SolverChoice(requested, requested, f"{requested} (requested{_HOW[requested]})", {})
    n = 6 * m
    if sparse_estimate is None:
        sparse_estimate = lambda: sparse_cost(block_i, block_k, m)  # noqa: E731

    def sparse() -> float:
        flops, fronts = sparse_estimate()
        return o.rate_sparse * flops + o.front_cost * fronts

    costs = {"dense": o.rate_dense * n**3 / 3.0}
    if kd is not None:  # LAPACK's band Cholesky: Σ_j min(kd, n − j)² flops
        b = float(min(kd + 1, n))
        costs["banded"] = o.rate_banded * (n * b**2 - 2.0 * b**3 / 3.0)
    fill = (2 * block_i.size - m) / float(m * m)
    band = f", half-band {kd} of {n}" if kd is not None else ""
    if kd is not None and kd + 1 <= o.strip_band * n:
        # a narrow band (strips): banded, unless a sparse factor is clearly cheaper
        if costs["banded"] > o.sparse_considered_above_strips:
            costs["sparse"] = sparse()
        if costs.get("sparse", np.inf) >= o.sparse_clear_win * costs["banded"]:
            est = ", ".join(f"{k} {v:.2g}" for k, v in sorted(costs.items(), key=lambda t: t[1]))
            reason = f"banded (auto: {m} images{band}: a narrow band, strips; est. {est})"
            return SolverChoice("banded", "auto", reason, costs)
    if n > o.dense_max or min(costs.values()) > o.sparse_considered_above:
        costs["sparse"] = sparse()
    if n > o.dense_max:
        del costs["dense"]
    best = min(costs, key=costs.get)
    est = ", ".join(f"{k} {v:.2g}" for k, v in sorted(costs.items(), key=lambda t: t[1]))
    reason = (
        f"{best} (auto{_HOW[best]}: {m} images, {100 * fill:.0f} % of S's blocks non-zero{band}; "
        f"est. {est})"
    )
    return SolverChoice(best, "auto", reason, costs)


def choose_formation(
    solver: str, m: int, n_pt: int, n_pairs: int, options: ReducedOptions | None = None
) -> str:
    """``"dense"`` (BLAS products of the per-point couplings) or ``"pairs"`` (pairs of rays).

    Only a dense S can be formed densely; it is when (6m)²·3p/2 multiply-adds at BLAS
    speed cost less than the pairs of rays one by one (``options.dense_flop_ns``,
    ``options.dense_size_ns``, ``options.pair_ns``).
    """
    o = ReducedOptions() if options is None else options
    if solver != "dense":
        return "pairs"
    per_flop = o.dense_flop_ns + o.dense_size_ns / (6.0 * max(m, 1))
    dense_ns = per_flop * 2.0 * 54.0 * float(m) ** 2 * n_pt
    return "dense" if dense_ns < o.pair_ns * n_pairs else "pairs"
