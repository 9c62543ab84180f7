"""Model deformation: how far an estimated block is from a reference, exaggerated and animated.

The reference is the truth of a simulation (or any second state of the same points).
Two displacement fields A (t = 0) and B (t = 1), both relative to the reference, are
morphed: points are drawn at reference + k·((1 − t)·A + t·B). Two comparisons:

* *reference → current estimate*: A = 0, B = estimate − reference;
* *without → with self-calibration*: A and B are the point errors of two bundle
  adjustments of the start block, without and with an additional-parameter set
  (Ebner's 12 by default, :mod:`orientviz.bundle`) — Ackermann's "model
  deformation" removed (or not) by self-calibration.

Scene nodes: ``/block/deformation/vectors`` (reference → morphed point) and
``/block/deformation/points``. k draws the larger median displacement as half a point
spacing; the panel prints k and the RMS of both fields in m.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..bundle import ap_set, bundle_adjust
from ..errors import InputError
from ..io.kinds.block import adjust_block
from .block_geometry import COLORS
from .legend import swatch
from .sliders import Sliders
from .state import BlockState

F64 = NDArray[np.float64]

MODES = ("reference → current estimate", "without → with self-calibration")


def auto_scale(*displacements: F64, spacing: float) -> float:
    """Exaggeration drawing the larger median displacement length as half of ``spacing`` (1 if none)."""
    meds = []
    for d in displacements:
        n = np.linalg.norm(np.asarray(d, dtype=float), axis=1)
        n = n[np.isfinite(n)]
        meds.append(float(np.median(n)) if n.size else 0.0)
    med = max(meds, default=0.0)
    return 0.5 * spacing / med if med > 0 else 1.0


def morph(reference: F64, A: F64, B: F64, t: float, k: float) -> F64:
    """Points at reference + k·((1 − t)·A + t·B), shape (p, 3) m, t ∈ [0, 1]."""
    return np.asarray(reference, float) + k * (
        (1.0 - t) * np.asarray(A, float) + t * np.asarray(B, float)
    )


def rms(d: F64) -> F64:
    """RMS per coordinate (3,) of displacements (p, 3), ignoring NaN rows."""
    return np.sqrt(np.nanmean(np.asarray(d, float) ** 2, axis=0))


def self_calibration_fields(
    start: Block, reference: Block, ap: str = "ebner12"
) -> tuple[F64, F64, str]:
    """Point errors (p, 3) m of bundles without and with self-calibration, and a summary line."""
    p = start.n_points
    out = []
    for add in (None, ap_set(ap)):
        res = bundle_adjust(start, additional=add)
        out.append((res.x[res.groups["points"]].reshape(p, 3) - reference.points.xyz, res.sigma0))
    tie = start.points.role == 0
    a, b = rms(out[0][0][tie]), rms(out[1][0][tie])
    line = (
        f"tie-point RMS error X, Y, Z: without {a[0]:.3f}, {a[1]:.3f}, {a[2]:.3f} m "
        f"(σ̂0 {out[0][1]:.3f}); with {ap} {b[0]:.3f}, {b[1]:.3f}, {b[2]:.3f} m (σ̂0 {out[1][1]:.3f})"
    )
    return out[0][0], out[1][0], line


def self_calibration_comparison(
    start: Block, reference: Block, systematic_only: Block | None = None, ap: str = "ebner12"
) -> tuple[F64, F64, str]:
    """The fields to morph and the panel's text of "without → with self-calibration".

    With ``systematic_only`` (the same block's observations carrying only its systematic
    image errors, no random errors or blunders) the fields are that block's: the model
    deformation the systematic errors cause, and what self-calibration leaves of it.
    The text then also gives the comparison on ``start`` (with its random errors), where
    the random errors' effect on the points may hide the gain, and says so.
    """
    if systematic_only is None:
        return self_calibration_fields(start, reference, ap)
    A, B, line = self_calibration_fields(systematic_only, reference, ap)
    _, _, noisy = self_calibration_fields(start, reference, ap)
    tie = systematic_only.points.role == 0
    a, b = float(np.linalg.norm(rms(A[tie]))), float(np.linalg.norm(rms(B[tie])))
    text = (
        f"**the systematic image errors alone** (same images, no random errors or blunders): "
        f"{line}; the model deformation drops from {a:.3f} to {b:.3f} m "
        f"({100 * (1 - b / a):.0f} % removed).  \n"
        f"With the demo's random errors and blunders: {noisy} — the random errors' effect on "
        "the tie points is many times the deformation, so the gain does not show there."
    )
    return A, B, text


def deformation_extra(state: BlockState, reference: Block, systematic_only: Block | None = None):
    """An ``extra`` builder (see :class:`~orientviz.viewer.demo.Demo`) for the deformation view.

    ``systematic_only``: the block's observations with only their systematic errors, for
    the self-calibration comparison (:func:`self_calibration_comparison`).
    """
    ref = reference.points.xyz.copy()

    def build(app: Any) -> dict:
        scene = app.scene
        frame, spacing = scene.geo.frame, scene.geo.spacing
        gui, sc = app.server.gui, app.server.scene
        ctl: dict[str, Any] = {}
        fields: dict[str, Any] = {"selfcal": None, "line": ""}
        R = frame.to_scene(ref)
        vec = sc.add_line_segments(
            "/block/deformation/vectors", np.zeros((1, 2, 3), np.float32),
            COLORS["deformation"], thickness=2.0, thickness_units="screen", visible=False,
        )  # fmt: skip
        pts = sc.add_point_cloud(
            "/block/deformation/points", R.astype(np.float32), COLORS["deformation"],
            point_size=scene.geo.point_size, point_shape="circle", precision="float32", visible=False,
        )  # fmt: skip
        sliders = Sliders(gui, ctl)  # "play" moves the morph slider from the server
        with gui.add_folder("Deformation", expand_by_default=False) as folder:
            ctl["show"] = gui.add_checkbox("show deformation", False)
            ctl["mode"] = gui.add_dropdown("compare", MODES, initial_value=MODES[0])
            sliders.add("t", folder, "morph t", 0.0, 1.0, 0.01, 1.0)
            ctl["play"] = gui.add_button("play")
            ctl["info"] = gui.add_markdown("")

        def current() -> tuple[F64, F64]:
            if ctl["mode"].value == MODES[1]:
                if fields["selfcal"] is None:
                    A, B, fields["line"] = self_calibration_comparison(
                        state.block0, reference, systematic_only
                    )
                    fields["selfcal"] = (A, B)
                return fields["selfcal"]
            return np.zeros_like(ref), state.block.points.xyz - ref

        def name_in_legend(k: float | None) -> None:
            """The legend names the deformation's arrows and points while they are shown."""
            text = None if k is None else deformation_legend(str(ctl["mode"].value), k)
            if text != getattr(scene, "legend_deformation", None):
                scene.legend_deformation = text
                if app.panel is not None:
                    app.panel.update_legend()

        def redraw() -> None:
            A, B = current()
            k = auto_scale(A, B, spacing=spacing)
            t = float(ctl["t"].value)
            M = morph(ref, A, B, t, k)
            vec.points = frame.to_scene(np.stack([ref, M], axis=1)).astype(np.float32)
            pts.points = frame.to_scene(M).astype(np.float32)
            fields["k"] = k
            if ctl["show"].value:
                name_in_legend(k)
            a, b = rms(A), rms(B)
            ctl["info"].content = (
                f"drawn ×{k:.3g}, t = {t:.2f}  \n"
                f"RMS at t = 0: {np.linalg.norm(a):.3g} m, at t = 1: {np.linalg.norm(b):.3g} m"
                + (f"  \n{fields['line']}" if ctl["mode"].value == MODES[1] else "")
            )

        def show(_e: Any = None) -> None:
            on = bool(ctl["show"].value)
            vec.visible = pts.visible = on
            for key in ("points", "residuals", "ellipsoids"):
                box = app.panel.handles.get(f"show_{key}") if app.panel else None
                scene.set_visible(key, (not on) and (box is None or bool(box.value)))
            scene.legend_deformation = ""  # the legend is written anew (what is drawn now)
            name_in_legend(fields.get("k", 1.0) if on else None)

        def play(_e: Any = None) -> None:
            def run() -> None:
                for t in np.concatenate([np.linspace(0, 1, 40), np.linspace(1, 0, 40), [1.0]]):
                    sliders.set("t", round(float(t), 2))
                    time.sleep(0.04)

            if not ctl["show"].value:
                ctl["show"].value = True
            threading.Thread(target=run, daemon=True).start()

        ctl["show"].on_update(app.guard(show))
        ctl["mode"].on_update(app.guard(lambda _e: redraw()))
        sliders.on_update("t", app.guard(lambda _e: redraw()))
        ctl["play"].on_click(app.guard(play))
        scene.listeners.append(redraw)
        redraw()
        return {"deformation": ctl, "deformation_nodes": (vec, pts), "deformation_reference": ref}

    return build


def deformation_legend(mode: str, k: float) -> str:
    """The legend line of the deformation view in ``mode`` (one of :data:`MODES`), drawn ×k."""
    arrows, dots = swatch(COLORS["deformation"], "▬"), swatch(COLORS["deformation"], "●")
    if mode == MODES[1]:
        what = (
            "each point's error as adjusted without (t = 0) and with (t = 1) "
            "self-calibration, from its true position"
        )
    else:
        what = "each point from its true position (t = 0) to its estimate (t = 1)"
    return f"{arrows} {dots} model deformation: {what}, ×{k:.3g} (see *Deformation*)"


def without_lens_terms(problem: Any, block: Block) -> tuple[F64, float]:
    """Points (p, 3) m and σ̂0 of the file's bundle of ``block`` with the cameras' lens
    models or additional parameters left out (pinhole cameras at the file's c, x0, y0)."""
    pinhole = block.copy()
    pinhole.cameras.model = [{} for _ in pinhole.cameras.ids]
    adj, _ = adjust_block(problem, pinhole, precision=False)
    p = block.n_points
    return adj.x[adj.groups["points"]].reshape(p, 3), float(adj.sigma0)


def camera_terms_name(block: Block) -> str:
    """What the cameras of a problem file estimate, as the panel names it: ``"lens
    terms"`` (a lens model) or ``"additional parameters (ebner12)"`` (a set)."""
    models = [m for m in (getattr(block.cameras, "model", None) or []) if m]
    if models and "additional" in models[0]:
        return f"additional parameters ({models[0]['additional']})"
    return "lens terms"


def lens_deformation_extra(problem: Any, state: BlockState):
    """An ``extra`` builder for a problem file whose cameras have a lens model or an
    additional-parameter set: the model deformation those terms remove — the block
    adjusted without them against with them (:func:`camera_terms_name` names them).

    Vectors from each point as adjusted with the lens terms (the file's solution) to the
    same point adjusted without them, × k (the median drawn half a point spacing), morphed
    by t; the panel gives k, the RMS displacement and both σ̂0. The second bundle runs
    when the view is first shown. While a solve started at opening still runs
    (``state.pending``) there is no solution to compare with yet: the view waits for it.
    """
    start = state.block0.copy()
    solution: dict[str, Any] = {}
    if not state.pending:
        solution["xyz"] = state.block.points.xyz.copy()
        solution["sigma0"] = (
            float(state.result.sigma0) if state.result is not None else float("nan")
        )
    terms = camera_terms_name(start)

    def build(app: Any) -> dict:
        scene = app.scene
        frame, spacing = scene.geo.frame, scene.geo.spacing
        gui, sc = app.server.gui, app.server.scene
        ctl: dict[str, Any] = {}
        field: dict[str, Any] = {}
        vec = sc.add_line_segments(
            "/block/lens_deformation/vectors", np.zeros((1, 2, 3), np.float32),
            COLORS["deformation"], thickness=2.0, thickness_units="screen", visible=False,
        )  # fmt: skip
        with gui.add_folder(f"Model deformation ({terms})", expand_by_default=False):
            ctl["show"] = gui.add_checkbox(f"without → with the {terms}", False)
            ctl["t"] = gui.add_slider("morph t", 0.0, 1.0, 0.01, 0.0)
            ctl["info"] = gui.add_markdown("*tick the box: the block is adjusted once more "
                                           f"without the cameras' {terms}*")  # fmt: skip

        def redraw() -> None:
            if state.pending:
                raise InputError(f"{state.pending}: the model deformation follows its solution")
            if not solution:  # the solve ran in the background: its solution ("as adjusted")
                solution.update(xyz=state.changes[0].xyz.copy(), sigma0=state.changes[0].sigma0)
            with_lens, sigma_with = solution["xyz"], solution["sigma0"]
            if "A" not in field:
                xyz, s0 = without_lens_terms(problem, start)
                field["A"], field["sigma0"] = xyz - with_lens, s0
            A = field["A"]
            k = auto_scale(A, spacing=spacing)
            t = float(ctl["t"].value)
            M = morph(with_lens, A, np.zeros_like(A), t, k)
            vec.points = frame.to_scene(np.stack([with_lens, M], axis=1)).astype(np.float32)
            d = np.linalg.norm(rms(A))
            ctl["info"].content = (
                f"each point adjusted **without** the {terms} (t = 0) against **with** them "
                f"(t = 1, the solution): RMS {d:.3g} {state.units.length_name}, drawn ×{k:.3g}, "
                f"t = {t:.2f}  \n"
                f"σ̂0 without {field['sigma0']:.4g}, with {sigma_with:.4g}"
            )

        def show(_e: Any = None) -> None:
            on = bool(ctl["show"].value)
            if on:
                redraw()
            vec.visible = on
            for key in ("residuals", "ellipsoids"):
                box = app.panel.handles.get(f"show_{key}") if app.panel else None
                scene.set_visible(key, (not on) and (box is None or bool(box.value)))
            scene.legend_deformation = (
                f"{swatch(COLORS['deformation'], '▬')} model deformation: each point adjusted "
                f"without the {terms} → with them (see its folder)"
                if on
                else None
            )
            if app.panel is not None:
                app.panel.update_legend()

        ctl["show"].on_update(app.guard(show))
        ctl["t"].on_update(app.guard(lambda _e: redraw() if ctl["show"].value else None))
        return {"lens_deformation": ctl, "lens_deformation_node": vec, "lens_field": field}

    return build
