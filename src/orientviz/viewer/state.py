"""The viewer's model of a block being adjusted: current state, history, residual scores.

:class:`BlockState` knows nothing about viser. It holds the block as it is *now* (after
slider moves, adjustment steps or a replayed iteration), the adjustment history that
the iteration scrubber replays, and computes the residuals the scene draws. Keeping it
free of GUI code makes the viewer's logic testable without a browser.

Units: object space m, image coordinates mm, angles rad inside (the block's rotation
sequence, ω-φ-κ by default: R = R_ω R_φ R_κ).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..adjust import Adjustment
from ..block import Block
from ..errors import InputError
from .adjuster import Adjuster, apply_parameters, default_adjuster, image_normalized_residuals

F64 = NDArray[np.float64]


@dataclass
class Snapshot:
    """One replayable state: orientations, points and the σ0 reported for it."""

    label: str
    X0: F64
    angles: F64
    xyz: F64
    sigma0: float


class BlockState:
    """A block, its adjustment and the history the viewer can scrub through.

    Parameters
    ----------
    block : Block
        Start values and observations. Not modified (the state works on a copy).
    result : Adjustment, optional
        An adjustment of ``block`` (layout ``"exterior"``/``"points"``); the state then
        starts at the adjusted values and its history is the result's history.
    adjuster : callable, optional
        ``adjuster(block, max_iter) -> Adjustment``; default
        :func:`orientviz.viewer.adjuster.default_adjuster`.
    """

    def __init__(
        self,
        block: Block,
        result: Adjustment | None = None,
        adjuster: Adjuster | None = None,
    ) -> None:
        self.block0 = block.copy()
        self.block = block.copy()
        self.adjuster = adjuster or default_adjuster()
        self.result: Adjustment | None = None
        self.history: list[Snapshot] = [self._snap("start", float("nan"))]
        #: index of the history record the state is at (steps truncate the history here)
        self.cursor = 0
        if result is not None:
            self._take_result(result, self.block0)

    # ------------------------------------------------------------------ snapshots
    def _snap(self, label: str, sigma0: float) -> Snapshot:
        b = self.block
        return Snapshot(
            label, b.images.X0.copy(), b.images.angles.copy(), b.points.xyz.copy(), sigma0
        )

    def _take_result(self, result: Adjustment, start: Block) -> None:
        """Adopt ``result`` (computed from ``start``) and append its iterations to the history."""
        self.result = result
        del self.history[self.cursor + 1 :]
        kept = [it for it in result.history[1:] if np.size(it.x) == np.size(result.x)]
        for it in kept:
            self.block = apply_parameters(start, result, it.x)
            self.history.append(self._snap(f"iteration {len(self.history)}", it.sigma0))
        self.block = apply_parameters(start, result)
        if len(kept) < len(result.history) - 1:  # the solver kept no parameters per iteration
            self.history.append(self._snap("adjusted", result.sigma0))
        self.cursor = len(self.history) - 1
        self._at_result = True

    def replay(self, k: int) -> Snapshot:
        """Set the state to history record ``k`` (0 = start) and return it."""
        if not 0 <= k < len(self.history):
            raise InputError(f"iteration {k} is not in the history (0..{len(self.history) - 1})")
        s = self.history[k]
        self.cursor = k
        self.block.images.X0 = s.X0.copy()
        self.block.images.angles = s.angles.copy()
        self.block.points.xyz = s.xyz.copy()
        self._at_result = self.result is not None and k == len(self.history) - 1
        return s

    # ------------------------------------------------------------------ actions
    def set_exterior(self, i: int, X0: F64 | None = None, angles: F64 | None = None) -> None:
        """Change the exterior orientation of image ``i`` (X0 in m, angles in rad)."""
        if X0 is not None:
            self.block.images.X0[i] = np.asarray(X0, dtype=float)
        if angles is not None:
            self.block.images.angles[i] = np.asarray(angles, dtype=float)
        self._at_result = False

    def step(self, max_iter: int = 1) -> Adjustment:
        """Adjust from the current state with at most ``max_iter`` steps; record the steps."""
        start = self.block.copy()
        result = self.adjuster(start, max_iter)
        # a step from a replayed state discards the later history
        self._take_result(result, start)
        return result

    def run(self, max_iter: int = 50) -> Adjustment:
        """Adjust to convergence from the current state."""
        return self.step(max_iter)

    def reset(self) -> None:
        """Back to the start values; the history is cleared."""
        self.block = self.block0.copy()
        self.result = None
        self.history = [self._snap("start", float("nan"))]
        self.cursor = 0
        self._at_result = False

    # ------------------------------------------------------------------ residuals
    _at_result = False

    @property
    def at_result(self) -> bool:
        """True while the state equals the last adjustment's estimate."""
        return self._at_result

    def misclosure(self) -> F64:
        """Observed minus computed image coordinates (n, 2) in mm for the current state."""
        return self.block.residuals()

    def scores(self, misclosure: F64 | None = None) -> tuple[F64, str]:
        """Per-observation size of the residual and what it is.

        At the adjusted state with normalised residuals available: max(``|w_x|``, ``|w_y|``),
        Baarda's w. Otherwise the misclosure in units of its a-priori σ,
        ``max(|e_x|/σ_x, |e_y|/σ_y)``.

        Returns
        -------
        scores : ndarray, shape (n,)
        kind : str
            ``"|w|"`` or ``"|v|/σ"``.
        """
        n = self.block.n_observations
        w = image_normalized_residuals(self.result, n) if self.at_result else None
        if w is not None:
            return np.fmax(np.abs(w[:, 0]), np.abs(w[:, 1])), "|w|"  # NaN where r_i = 0
        e = self.misclosure() if misclosure is None else misclosure
        return np.max(np.abs(e) / self.block.observations.sigma, axis=1), "|v|/σ"

    def redundancy(self) -> int:
        """Redundancy of the bundle: 2n − 6m − 3·(free points), or the result's."""
        if self.result is not None:
            return int(self.result.redundancy)
        pts = self.block.points
        fixed = (pts.role == 1)[:, None] & (pts.sigma == 0) & np.isfinite(pts.xyz_known)
        free = int(np.count_nonzero(~fixed))
        return 2 * self.block.n_observations - 6 * self.block.n_images - free

    def sigma0(self, misclosure: F64 | None = None) -> float:
        """σ0 of the current state from the image misclosures, √(Σ(e/σ)² / r), unitless."""
        e = self.misclosure() if misclosure is None else misclosure
        r = self.redundancy()
        if r <= 0:
            return float("nan")
        return float(np.sqrt(np.sum((e / self.block.observations.sigma) ** 2) / r))

    def largest(self, k: int = 10, scores: F64 | None = None) -> NDArray[np.int64]:
        """Indices of the ``k`` observations with the largest scores, largest first."""
        s = self.scores()[0] if scores is None else scores
        s = np.nan_to_num(s, nan=0.0)
        k = min(k, s.shape[0])
        idx = np.argpartition(-s, k - 1)[:k] if 0 < k < s.shape[0] else np.arange(s.shape[0])
        return idx[np.argsort(-s[idx])]

    def observation_label(self, j: int) -> str:
        """``"image/point"`` ids of observation ``j``."""
        o = self.block.observations
        return f"{self.block.images.ids[o.image[j]]}/{self.block.points.ids[o.point[j]]}"
