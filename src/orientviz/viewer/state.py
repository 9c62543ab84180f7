"""The viewer's model of a block being adjusted: current state, history, residual scores.

:class:`BlockState` knows nothing about viser. It holds the block as it is *now* (after
slider moves, adjustment steps or a replayed iteration), the adjustment history that
the iteration scrubber replays, and computes the residuals the scene draws. Keeping it
free of GUI code makes the viewer's logic testable without a browser.

The user's actions on the adjustment — an observation, an image or a control point
switched off or on, a control point moved, a weight changed
(:mod:`orientviz.viewer.edits`) — re-solve warm-started from the current estimates and
are recorded in :attr:`BlockState.changes`, one :class:`Change` each with its σ̂0.
:meth:`BlockState.undo` and :meth:`BlockState.rewind` restore a recorded state exactly
(the stored arrays and result, not a new adjustment).

Units: object space m, image coordinates mm, angles rad inside (the block's rotation
sequence, ω-φ-κ by default: R = R_ω R_φ R_κ).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..adjust import Adjustment
from ..blas import blas_threads
from ..block import Block
from ..errors import InputError
from .adjuster import Adjuster, default_adjuster, image_normalized_residuals
from .edits import Edits, Mapping, effective_block, expand_result
from .history import Change, Snapshot
from .view_units import ViewUnits

F64 = NDArray[np.float64]


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
        ``adjuster(block, max_iter, precision=True) -> Adjustment``; default
        :func:`orientviz.viewer.adjuster.default_adjuster`. A problem file's adjuster is
        :class:`orientviz.viewer.solved.FileAdjuster` (the file's model and options).
    camera : object, optional
        ``camera.misclosure(block, ap) -> (n, 2)`` mm: the misclosures through the file's
        camera model with the camera terms ``ap`` (:class:`orientviz.viewer.solved.
        CameraTerms`); None: the block's pinhole projection.
    units : ViewUnits, optional
        How the panel names lengths, angles and image quantities (a problem file's
        units, :meth:`ViewUnits.of`); default m, gon, µm.
    """

    def __init__(
        self,
        block: Block,
        result: Adjustment | None = None,
        adjuster: Adjuster | None = None,
        camera: Any = None,
        units: ViewUnits | None = None,
    ) -> None:
        #: how the panel names lengths, angles and image quantities (the file's units)
        self.units = units or ViewUnits()
        self.block0 = block.copy()
        self.block = block.copy()
        self.adjuster = adjuster or default_adjuster()
        self.camera = camera
        #: camera terms of the current state (None: no camera model, or not yet estimated)
        self.ap: F64 | None = None
        self.ap0: F64 | None = None
        self._moved = False
        self.result: Adjustment | None = None
        self.history: list[Snapshot] = [self._snap("start", float("nan"))]
        #: index of the history record the state is at (steps truncate the history here)
        self.cursor = 0
        #: the viewer's changes to the block (observations/images/control on-off, weights)
        self.edits = Edits.of(block)
        #: where the last adjusted sub-block sat in the block (None: the whole block)
        self.mapping: Mapping | None = None
        #: what runs while the state shows the file's start values (a solve started at
        #: opening, :mod:`orientviz.viewer.background`); steps and actions wait for it
        self.pending: str | None = None
        if result is not None:
            self._start_from(result)
        #: the list of changes with their σ̂0; entry 0 is the state as loaded
        self.changes: list[Change] = [
            self._change("as loaded" if result is None else "as adjusted")
        ]
        #: index of the change the state is at (undo/rewind move it back)
        self.change_cursor = 0

    def _start_from(self, result: Adjustment) -> None:
        """Take ``result`` (an adjustment of :attr:`block0`) with its start record."""
        first = result.history[0] if result.history else None
        if first is not None and np.size(first.x) == np.size(result.x):
            self.ap0 = self.ap = _additional(result, first.x)
            self.history[0] = self._snap("start", float(first.sigma0))
        self._take_result(result, self.block0)

    def adopt(self, result: Adjustment) -> None:
        """Take the solve of :attr:`block0` that ran while the state showed its start values.

        The state becomes what it would be had it been built with ``result``: the start,
        the solve's iterations on the scrubber, the estimate; a hand move made meanwhile
        is dropped and the list of changes starts again ("as adjusted").
        """
        self.block = self.block0.copy()
        self.ap = self.ap0
        self.history = [self._snap("start", float("nan"))]
        self.cursor = 0
        self.edits = Edits.of(self.block0)
        self.mapping = None
        self._start_from(result)
        self.changes = [self._change("as adjusted")]
        self.change_cursor = 0
        self.pending = None

    # ------------------------------------------------------------------ snapshots
    def _snap(self, label: str, sigma0: float) -> Snapshot:
        b = self.block
        ap = None if self.ap is None else self.ap.copy()
        return Snapshot(
            label, b.images.X0.copy(), b.images.angles.copy(), b.points.xyz.copy(), sigma0, ap
        )

    def _take_result(self, result: Adjustment, start: Block) -> None:
        """Adopt ``result`` (computed from ``start``) and append its iterations to the history."""
        self.result = result
        del self.history[self.cursor + 1 :]
        kept = [it for it in result.history[1:] if np.size(it.x) == np.size(result.x)]
        for it in kept:
            self._put(start, result, it.x)
            self.history.append(self._snap(f"iteration {len(self.history)}", it.sigma0))
        self._put(start, result)
        if len(kept) < len(result.history) - 1:  # the solver kept no parameters per iteration
            self.history.append(self._snap("adjusted", result.sigma0))
        else:  # the last record is the result: its σ̂0 as the result states it
            self.history[-1] = self._snap(self.history[-1].label, float(result.sigma0))
        self.cursor = len(self.history) - 1
        self._at_result = True
        self._moved = False

    def _put(self, start: Block, result: Adjustment, x: F64 | None = None) -> None:
        """Set the estimates of the state from ``x`` (default ``result.x``; layout of
        ``result.groups``), those not in ``x`` from ``start`` (cf. ``apply_parameters``,
        without copying the whole block)."""
        x = result.x if x is None else np.asarray(x, dtype=float)
        b = self.block
        if "exterior" in result.groups:
            ext = x[result.groups["exterior"]].reshape(b.n_images, 6)
            b.images.X0, b.images.angles = ext[:, :3].copy(), ext[:, 3:].copy()
        else:
            b.images.X0, b.images.angles = start.images.X0.copy(), start.images.angles.copy()
        if "points" in result.groups:
            b.points.xyz = x[result.groups["points"]].reshape(b.n_points, 3).copy()
        else:
            b.points.xyz = start.points.xyz.copy()
        if self.camera is not None:
            self.ap = _additional(result, x)

    def replay(self, k: int) -> Snapshot:
        """Set the state to history record ``k`` (0 = start) and return it."""
        if not 0 <= k < len(self.history):
            raise InputError(f"iteration {k} is not in the history (0..{len(self.history) - 1})")
        s = self.history[k]
        self.cursor = k
        self.block.images.X0 = s.X0.copy()
        self.block.images.angles = s.angles.copy()
        self.block.points.xyz = s.xyz.copy()
        self.ap = None if s.ap is None else s.ap.copy()
        self._at_result = self.result is not None and k == len(self.history) - 1
        self._moved = False
        return s

    # ------------------------------------------------------------------ actions
    def set_exterior(self, i: int, X0: F64 | None = None, angles: F64 | None = None) -> None:
        """Change the exterior orientation of image ``i`` (X0 in m, angles in rad)."""
        if X0 is not None:
            self.block.images.X0[i] = np.asarray(X0, dtype=float)
        if angles is not None:
            self.block.images.angles[i] = np.asarray(angles, dtype=float)
        self._at_result = False
        self._moved = True

    def step(self, max_iter: int = 1, precision: bool = True) -> Adjustment:
        """Adjust from the current state with at most ``max_iter`` steps; record the steps.

        Only what :attr:`edits` leaves switched on is adjusted
        (:func:`~orientviz.viewer.edits.effective_block`); the result is laid out for the
        whole block. ``precision=False`` skips the cofactors (faster; no normalised
        residuals, redundancy numbers or ellipsoids until the next adjustment with them).
        Refused (InputError) while a solve started at opening runs (:attr:`pending`).
        """
        if self.pending:
            raise InputError(f"{self.pending}; this waits for its solution")
        b = self.block  # the start values (a shallow copy: only the estimates are new arrays)
        start = b.with_(
            images=replace(b.images, X0=b.images.X0.copy(), angles=b.images.angles.copy()),
            points=replace(b.points, xyz=b.points.xyz.copy()),
        )
        sub, mp = effective_block(start, self.edits)
        if precision:
            raw = self.adjuster(sub, max_iter)
        else:  # the quick answer: small BLAS calls, fastest on one thread
            with blas_threads(1):
                raw = self.adjuster(sub, max_iter, precision=False)  # type: ignore[call-arg]
        result = expand_result(raw, mp, start, self.effective_sigma(), self.ap)
        # a step from a replayed state discards the later history
        self._take_result(result, start)
        self.mapping = mp
        return result

    def run(self, max_iter: int = 50) -> Adjustment:
        """Adjust to convergence from the current state."""
        return self.step(max_iter)

    def reset(self) -> None:
        """Back to the start values; the history and the list of changes are cleared."""
        self.block = self.block0.copy()
        self.result = None
        self.ap = None if self.ap0 is None else self.ap0.copy()
        self.history = [self._snap("start", float("nan"))]
        self.cursor = 0
        self._at_result = False
        self._moved = False
        self.edits = Edits.of(self.block0)
        self.mapping = None
        self.changes = [self._change("as loaded")]
        self.change_cursor = 0

    # ------------------------------------------------------------------ changes
    def _change(self, label: str) -> Change:
        b, res = self.block, self.result
        return Change(
            label,
            float(res.sigma0) if res is not None and self.at_result else float("nan"),
            self.edits.copy(),
            b.images.X0.copy(),
            b.images.angles.copy(),
            b.points.xyz.copy(),
            res,
            list(self.history),
            self.cursor,
            self.at_result,
            self.mapping,
            None if self.ap is None else self.ap.copy(),
        )

    def _restore(self, c: Change) -> None:
        self.edits = c.edits.copy()
        self.block.images.X0 = c.X0.copy()
        self.block.images.angles = c.angles.copy()
        self.block.points.xyz = c.xyz.copy()
        self.result, self.mapping = c.result, c.mapping
        self.history, self.cursor = list(c.history), c.cursor
        self._at_result = c.at_result
        self.ap = None if c.ap is None else c.ap.copy()
        self._moved = False

    def record(self, label: str) -> Change:
        """Append the current state to :attr:`changes` (later entries are discarded)."""
        del self.changes[self.change_cursor + 1 :]
        self.changes.append(self._change(label))
        self.change_cursor = len(self.changes) - 1
        return self.changes[-1]

    def update_current_change(self) -> None:
        """Store the current state in the change the cursor is at (e.g. after the precision)."""
        label = self.changes[self.change_cursor].label
        self.changes[self.change_cursor] = self._change(label)

    def act(
        self, label: str, edit: Callable[[Edits], None], max_iter: int = 20, precision: bool = True
    ) -> Change:
        """Apply ``edit`` to :attr:`edits`, re-solve warm-started and record the change.

        If the adjustment fails (e.g. a datum defect after a control point was switched
        off) the state is restored exactly and the exception is raised.
        """
        before = self._change("")
        edit(self.edits)
        try:
            self.step(max_iter, precision=precision)
        except Exception:
            self._restore(before)
            raise
        return self.record(label)

    def undo(self) -> Change:
        """Back to the change before the current one (exactly as it was)."""
        if self.change_cursor == 0:
            raise InputError("nothing to undo")
        return self.rewind(self.change_cursor - 1)

    def rewind(self, k: int) -> Change:
        """Back (or forward again) to change ``k`` of :attr:`changes`, exactly as it was."""
        if not 0 <= k < len(self.changes):
            raise InputError(f"change {k} is not in the list (0..{len(self.changes) - 1})")
        self._restore(self.changes[k])
        self.change_cursor = k
        return self.changes[k]

    # ------------------------------------------------------------------ actions
    def toggle_observation(self, j: int, **kw) -> Change:
        """Switch observation ``j`` off (or on again) and re-solve."""
        on = not self.edits.obs_on[j]

        def edit(e: Edits) -> None:
            e.obs_on[j] = on

        return self.act(
            f"observation {self.observation_label(j)} {'on' if on else 'off'}", edit, **kw
        )

    def toggle_image(self, i: int, **kw) -> Change:
        """Switch image ``i`` (all its observations) off (or on again) and re-solve."""
        on = not self.edits.image_on[i]

        def edit(e: Edits) -> None:
            e.image_on[i] = on

        return self.act(f"image {self.block.images.ids[i]} {'on' if on else 'off'}", edit, **kw)

    def toggle_control(self, k: int, **kw) -> Change:
        """Use control point ``k`` as a check point (or as control again) and re-solve."""
        if self.block.points.role[k] != 1:
            raise InputError(f"point {self.block.points.ids[k]} is not a control point")
        on = not self.edits.control_on[k]

        def edit(e: Edits) -> None:
            e.control_on[k] = on

        word = "on" if on else "off (check point)"
        return self.act(f"control {self.block.points.ids[k]} {word}", edit, **kw)

    def move_control(self, k: int, xyz: F64, **kw) -> Change:
        """Give control point ``k`` the coordinates ``xyz`` (m) and re-solve."""
        if self.block.points.role[k] != 1:
            raise InputError(f"point {self.block.points.ids[k]} is not a control point")
        new = np.asarray(xyz, dtype=float).reshape(3)
        d = new - self.edits.known[k]
        d = np.where(np.isfinite(d), d, 0.0)

        def edit(e: Edits) -> None:
            given = np.isfinite(e.known[k])
            e.known[k] = np.where(given, new, e.known[k])

        label = (
            f"control {self.block.points.ids[k]} moved by ({d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}) "
            f"{self.units.length_name}"
        )
        return self.act(label, edit, **kw)

    def set_weight(self, j: int, factor: float, **kw) -> Change:
        """Multiply the weight of observation ``j`` by ``factor`` (σ / √factor) and re-solve."""
        f = float(factor)
        if not (np.isfinite(f) and f > 0):
            raise InputError(f"a weight factor must be a positive number, got {factor!r}")

        def edit(e: Edits) -> None:
            e.weight[j] = f

        return self.act(f"weight of {self.observation_label(j)} × {f:g}", edit, **kw)

    def effective_sigma(self) -> F64:
        """σ (n, 2) in mm of the image observations with the weight factors applied."""
        return self.block.observations.sigma / np.sqrt(self.edits.weight)[:, None]

    def active_observations(self) -> NDArray[np.bool_]:
        """Observations that are switched on (with their image), shape (n,)."""
        return self.edits.obs_on & self.edits.image_on[self.block.observations.image]

    # ------------------------------------------------------------------ residuals
    _at_result = False

    @property
    def at_result(self) -> bool:
        """True while the state equals the last adjustment's estimate."""
        return self._at_result

    @property
    def moved(self) -> bool:
        """True when an orientation was changed by hand since the last recorded state."""
        return self._moved

    def misclosure(self) -> F64:
        """Observed minus computed image coordinates (n, 2) in mm for the current state
        (through the file's camera model and the current camera terms, if any)."""
        if self.camera is not None and self.ap is not None:
            e = self._result_misclosure()
            return self.camera.misclosure(self.block, self.ap) if e is None else e
        return self.block.residuals()

    def _result_misclosure(self) -> F64 | None:
        """−v (n, 2) mm of the last adjustment while the state is its estimate, else None.

        At the estimate the misclosure through the camera model is the adjustment's own
        residual vector (the contract's order: x, y of each image observation first), so
        opening a self-calibrated block needs no second bundle problem for it.
        """
        n = self.block.n_observations
        v = None if not self.at_result or self.result is None else self.result.residuals
        if v is None or np.shape(v)[0] < 2 * n:
            return None
        e = -np.asarray(v[: 2 * n], dtype=float).reshape(n, 2)
        return e if np.all(np.isfinite(e)) else None

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
        s = np.max(np.abs(e) / self.effective_sigma(), axis=1)
        return np.where(self.active_observations(), s, np.nan), "|v|/σ"

    def redundancy(self) -> int:
        """Redundancy of the bundle: 2n − 6m − 3·(free points), or the result's."""
        if self.result is not None:
            return int(self.result.redundancy)
        pts = self.block.points
        fixed = (pts.role == 1)[:, None] & (pts.sigma == 0) & np.isfinite(pts.xyz_known)
        free = int(np.count_nonzero(~fixed))
        return 2 * self.block.n_observations - 6 * self.block.n_images - free

    def sigma0(self, misclosure: F64 | None = None) -> float:
        """σ0 of the current state, unitless.

        At a recorded state (the start, an iteration, the result) the adjustment's own
        σ̂0 of that state (all its observations and pseudo-observations); after a change
        by hand the image misclosures' √(Σ(e/σ)² / r).
        """
        if not self._moved and np.isfinite(self.history[self.cursor].sigma0):
            return float(self.history[self.cursor].sigma0)
        e = self.misclosure() if misclosure is None else misclosure
        r = self.redundancy()
        if r <= 0:
            return float("nan")
        on = self.active_observations()
        if self.result is not None and getattr(self.result, "used_obs", None) is not None:
            on = np.asarray(self.result.used_obs, bool)
        return float(np.sqrt(np.sum((e[on] / self.effective_sigma()[on]) ** 2) / r))

    def largest(self, k: int = 10, scores: F64 | None = None) -> NDArray[np.int64]:
        """Indices of the ``k`` observations with the largest scores, largest first."""
        s = self.scores()[0] if scores is None else scores
        s = np.nan_to_num(s, nan=0.0)
        k = min(k, s.shape[0])
        idx = np.argpartition(-s, k - 1)[:k] if 0 < k < s.shape[0] else np.arange(s.shape[0])
        return idx[np.argsort(-s[idx])]

    def image_label(self, i: int) -> str:
        """``"img3"``, with its strip where the block has strips (``"img3 (strip 2)"``)."""
        b = self.block
        s = int(b.images.strip[i])
        return f"{b.images.ids[i]}" + (f" (strip {s})" if s >= 0 else "")

    def observation_label(self, j: int) -> str:
        """``"image/point"`` ids of observation ``j``."""
        o = self.block.observations
        return f"{self.block.images.ids[o.image[j]]}/{self.block.points.ids[o.point[j]]}"


def _additional(result: Any, x: F64) -> F64 | None:
    """The camera terms (block ``"additional"``) of a parameter vector, or None."""
    sl = result.groups.get("additional")
    return None if sl is None else np.asarray(x, dtype=float)[sl].copy()
