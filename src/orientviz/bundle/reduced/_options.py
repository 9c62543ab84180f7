"""The reduced system's knobs: how the solver is chosen and when a dense diagnosis runs."""

from __future__ import annotations

from dataclasses import dataclass

#: Names accepted for the reduced-system solver; ``"auto"`` chooses from the structure.
SOLVER_CHOICES: tuple[str, ...] = ("auto", "banded", "dense", "sparse")


@dataclass(frozen=True)
class ReducedOptions:
    """How the reduced camera system S is solved (a value; every field has a default).

    Attributes
    ----------
    rate_dense, rate_banded, rate_sparse : float
        Relative time per flop of each factorisation (dense LAPACK = 1): the band
        Cholesky runs at about 0.65-0.85 × the dense speed for wide bands and far
        slower for narrow ones, the multifrontal one at about half the dense speed
        (fronts of 50-400 unknowns, most flops in low-rank updates).
    front_cost : float
        Fixed cost of one front of the multifrontal factorisation, in dense-flop
        equivalents (its extend-adds and LAPACK/BLAS calls from Python).
    pair_ns, dense_flop_ns, dense_size_ns : float
        Nanoseconds per pair of rays of the pair-wise Schur formation, and per multiply-add
        of the dense one ``dense_flop_ns + dense_size_ns / 6m`` (BLAS's speed grows with
        the size of S) (:func:`~orientviz.bundle.reduced._choice.choose_formation`).
    strip_band : float
        A band with half-bandwidth + 1 ≤ ``strip_band`` · 6m is a block of strips: banded,
        unless the sparse factor is clearly cheaper.
    sparse_clear_win : float
        With a narrow band the sparse factorisation is taken only when its estimate is
        below this fraction of the banded one (its solves cost more, and the precision's
        inverse needs the band).
    dense_max : int
        Dense systems only up to this many unknowns (6m; 8000² doubles = 512 MB).
    sparse_considered_above : float
        Below this many flops of the cheaper of dense/banded the sparse estimate (a nested
        dissection of the image graph) is not made.
    sparse_considered_above_strips : float
        A narrow band (strips) is compared with the sparse estimate only above this cost
        (dense-flop equivalents).
    dense_diagnosis_limit : int
        A singular S of up to this many unknowns is diagnosed by its dense null space
        (which parameters); larger ones by the failing pivot.
    gram_pad_max : float
        The images' Gram matrices are formed from one padded stack when padding adds at
        most this fraction of the rays, else image by image (same numbers).
    leaf_images, merge_images : int
        Nested dissection: parts of at most ``leaf_images`` images are not dissected
        further (one dense front); separators of at most ``merge_images`` images join
        their parent's (0: none).
    balance : float
        A level-structure separator (no projection centres) leaves at least this fraction
        of a part on each side.
    """

    rate_dense: float = 1.0
    rate_banded: float = 1.5
    rate_sparse: float = 2.0
    front_cost: float = 1.5e6
    pair_ns: float = 105.0
    dense_flop_ns: float = 0.0223
    dense_size_ns: float = 2.44
    strip_band: float = 0.5
    sparse_clear_win: float = 0.25
    dense_max: int = 8000
    sparse_considered_above: float = 2e8
    sparse_considered_above_strips: float = 5e10
    dense_diagnosis_limit: int = 3000
    gram_pad_max: float = 0.5
    leaf_images: int = 12
    merge_images: int = 0
    balance: float = 0.3
