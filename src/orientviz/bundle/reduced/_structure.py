"""The structure of the reduced camera system S: what stays fixed over the iterations.

S (6 unknowns per image, the points eliminated) has a 6 × 6 block (i, k) wherever images
i and k see a common unknown point. :class:`ReducedStructure` holds that pattern, the
observations grouped by image and by point, the chosen solver (:mod:`._choice`) and
what it needs: the band-minimising image order and the band layout (``"banded"``), or
the nested dissection and its fronts (``"sparse"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ._choice import choose_formation, choose_solver, image_blocks
from ._dissection import image_adjacency, nested_dissection
from ._multifrontal import front_layout
from ._options import SOLVER_CHOICES, ReducedOptions
from ._orderings import geometric_orderings
from ._tracks import track_groups

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def stable_order(keys: I64, n: int) -> I64:
    """``np.argsort(keys, kind="stable")`` for keys in [0, n): as 16-bit keys (NumPy's
    radix sort, O(len)) when n allows; a stable order is unique, so the same indices."""
    if n <= np.iinfo(np.int16).max:
        return np.argsort(keys.astype(np.int16), kind="stable")
    return np.argsort(keys, kind="stable")


def _segments(keys: I64, n: int) -> tuple[I64, I64, I64]:
    """Stable order by ``keys`` and the start of each non-empty segment, plus its key."""
    order = stable_order(keys, n)
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
        (:func:`._choice.choose_solver`). After construction
        ``solver`` is the one chosen, ``choice`` says why.
    orderings : list of ndarray
        Candidate image orders for ``"banded"`` (e.g. from :func:`geometric_orderings`);
        the one with the smallest bandwidth among these and reverse Cuthill-McKee wins.
    positions : ndarray, shape (m, 3), optional
        Projection centres (m): adds the two :func:`geometric_orderings` as candidates.
    options : ReducedOptions
        Rates and thresholds of the solver's choice, the dense diagnosis limit.
    formation : {"auto", "pairs", "dense"}
        How the Schur complement is formed (:mod:`._schur`);
        ``"auto"``: :func:`._choice.choose_formation`.
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
    options: ReducedOptions = field(default_factory=ReducedOptions)

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
        self._tracks = None
        self._setup_solver()

    @property
    def tracks(self):
        """The rays grouped by track length (:class:`._tracks.TrackGroups`),
        formed on first use."""
        if self._tracks is None:
            self._tracks = track_groups(self)
        return self._tracks

    def release_maps(self) -> None:
        """Drop the Schur formation's sparse maps and work arrays and the sparse factor's
        work arena (formed again when needed)."""
        if self._tracks is not None:
            self._tracks._maps = {}
            self._tracks.work = {}
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
            options=self.options,
        )
        self.solver = self.choice.solver
        if self.formation == "auto":
            self.formation = choose_formation(self.solver, m, self.n_pt, self.n_pairs, self.options)
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
        (:class:`._dissection.Dissection`; formed on first use, with
        geometric separators when ``positions`` are given)."""
        if getattr(self, "_diss", None) is None:
            o = self.options
            self._diss = nested_dissection(
                self.block_i, self.block_k, self.n_cam, self.positions,
                leaf=o.leaf_images, merge=o.merge_images, balance=o.balance,
            )  # fmt: skip
        return self._diss

    @property
    def n_reduced(self) -> int:
        return 6 * self.n_cam
