"""The panel's "Camera (self-calibration)" folder: the estimated camera and its distortion.

Shown when the adjustment estimates camera terms (a lens model or additional parameters
of the problem file's ``cameras[]``): each parameter with its value and σ (σ̂0 applied;
"fixed" when held), the strongest correlations among the estimated ones, and — for the
backward (photogrammetric) lens model and for additional-parameter sets — the distortion
field of the estimated camera drawn on the image plane of the selected image's frustum,
as arrows from the measured to the corrected image point, exaggerated
(:func:`distortion_segments`; an additional-parameter set's field is −A(m)·a,
:func:`ap_distortion_vectors`).

Units: c, x0, y0 in mm (in px for a problem file in pixels); the lens terms in the units
:class:`orientviz.bundle.LensEstimates` states (mm⁻², mm⁻⁴, …); the arrows in mm of the
image, drawn × the factor in the panel (their size given in µm, or px).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..bundle import block_camera_options
from ..lens import BackwardLens, backward_ideal
from .legend import swatch

F64 = NDArray[np.float64]

#: Colour of the distortion arrows (RGB), outside the residuals' quality ramp.
DISTORTION_COLOUR = (120, 40, 160)


def camera_table(
    cam: Any, group: int = 0, strongest: int = 3, pixel_mm: float | None = None
) -> str:
    """Markdown lines: value ± σ of each parameter of ``cam`` (LensEstimates), then the
    ``strongest`` correlations among the estimated parameters (largest abs(ρ) first).

    ``pixel_mm`` (a problem file in pixels): c, x0, y0 in px as the file gives them
    (y0 in the pixel frame, y down), not in the importer's nominal millimetres."""
    lines = []
    for j, name in enumerate(cam.names):
        v, s, unit = cam.value[group, j], cam.sigma[group, j], cam.units[j]
        if pixel_mm and unit == "mm":
            v, s, unit = (-v if name == "y0" else v) / pixel_mm + 0.0, s / pixel_mm, "px"
        unit = "" if unit == "1" else f" {unit}"
        if cam.estimated[j]:
            sig = f"± {s:.2g}" if np.isfinite(s) else "(σ after the precision pass)"
            lines.append(f"{name} = {v:.6g} {sig}{unit}")
        else:
            lines.append(f"{name} = {v:.6g}{unit} (fixed)")
    R = cam.correlation[group]
    pairs = [
        (abs(R[a, b]), cam.names[a], cam.names[b], R[a, b])
        for a in range(len(cam.names))
        for b in range(a + 1, len(cam.names))
        if np.isfinite(R[a, b])
    ]
    pairs.sort(reverse=True)
    if pairs:
        lines.append(
            "strongest correlations: "
            + ", ".join(f"{a}\\~{b} ρ = {r:+.2f}" for _, a, b, r in pairs[:strongest])
        )
    return "  \n".join(lines)


def additional_table(result: Any, strongest: int = 3) -> str:
    """Markdown lines of an additional-parameter set: value ± σ per parameter (µm) and
    the strongest correlations (from the result's ``"additional"`` cofactor block)."""
    sl = result.groups["additional"]
    names = list(result.names[sl])
    x = np.asarray(result.x)[sl]
    Q = result.cofactor_groups.get("additional")
    s0 = float(result.sigma0) if np.isfinite(result.sigma0) else 1.0
    sig = s0 * np.sqrt(np.diag(Q)) if Q is not None and np.ndim(Q) == 2 else np.full(x.size, np.nan)
    lines = [f"{n} = {v:.4g} ± {s:.2g} µm" for n, v, s in zip(names, x, sig)]
    if Q is not None and np.ndim(Q) == 2 and x.size > 1:
        d = np.sqrt(np.clip(np.diag(Q), 1e-300, None))
        R = Q / np.outer(d, d)
        iu = np.triu_indices(x.size, 1)
        order = np.argsort(-np.abs(R[iu]))[:strongest]
        lines.append(
            "strongest correlations: "
            + ", ".join(f"{names[iu[0][k]]}\\~{names[iu[1][k]]} ρ = {R[iu][k]:+.2f}" for k in order)
        )
    return "  \n".join(lines)


def distortion_vectors(cam: Any, lo: F64, hi: F64, group: int = 0, n: int = 9) -> tuple[F64, F64]:
    """Grid points m (k, 2) mm over the rectangle ``lo``–``hi`` (the measured points'
    extent) and the lens's correction x̄(m) − (m − p) (k, 2) mm there: the backward
    model (:func:`orientviz.lens.backward_ideal`)."""
    v = dict(zip(cam.names, cam.value[group]))
    lens = BackwardLens(
        v["c"], v["x0"], v["y0"], K=(v["K1"], v["K2"], v["K3"]), P=(v["P1"], v["P2"]),
        aspect=v["as"], skew=v["sk"],
    )  # fmt: skip
    gx, gy = np.meshgrid(
        np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], max(3, n * 2 // 3))
    )
    m = np.column_stack([gx.ravel(), gy.ravel()])
    rel = m - [lens.px, lens.py]
    return m, backward_ideal(m, lens) - rel


def ap_group_values(result: Any, group: int) -> F64 | None:
    """The estimated additional parameters (k,) µm of parameter group ``group`` (a camera),
    from the result's ``"additional"`` block (names ``b1@g0``, …), or None if it has none."""
    sl = result.groups["additional"]
    names = [str(n) for n in result.names[sl]]
    x = np.asarray(result.x)[sl]
    mine = [j for j, n in enumerate(names) if n.rsplit("@g", 1)[-1] == str(group)]
    if "@g" not in "".join(names):  # one group: the names carry no group
        mine = list(range(len(names)))
    return x[mine] if mine else None


def ap_distortion_vectors(aps: Any, a: F64, lo: F64, hi: F64, n: int = 9) -> tuple[F64, F64]:
    """Grid points m (k, 2) mm over ``lo``–``hi`` and the correction of the estimated
    additional parameters there, from the measured to the corrected point: −A(m)·a (mm)
    (the set's model is x_obs + v = projection + A(x_obs)·a, ``a`` in µm)."""
    gx, gy = np.meshgrid(
        np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], max(3, n * 2 // 3))
    )
    m = np.column_stack([gx.ravel(), gy.ravel()])
    return m, -aps.correction(m, a)


def distortion_segments(
    m: F64, d: F64, X0: F64, R: F64, c: float, depth: float, factor: float
) -> F64:
    """Arrows (k, 2, 3) on the image plane of a frustum drawn ``depth`` m deep: from the
    grid point m to m + factor·d (mm), in object coordinates (m)."""
    s = depth / c

    def to_object(xy: F64) -> F64:
        local = np.column_stack([xy * s, np.full(xy.shape[0], -c * s)])
        return X0 + local @ np.asarray(R).T

    return np.stack([to_object(m), to_object(m + factor * d)], axis=1)


class CameraControls:
    """The camera folder bound to a :class:`~orientviz.viewer.panel.BlockPanel`."""

    def __init__(self, panel: Any) -> None:
        self.panel = panel
        self.state = panel.state
        self.handles: dict[str, Any] = {}
        self.node: Any = None
        self.text = ""

    def build(self) -> CameraControls:
        gui, h = self.panel.server.gui, self.handles
        with gui.add_folder("Camera (self-calibration)", visible=False) as h["folder"]:
            h["table"] = gui.add_markdown("")
            h["field"] = gui.add_checkbox(
                "distortion field (selected image)", True,
                hint="the estimated lens: arrows from the measured to the corrected point",
            )  # fmt: skip
        h["field"].on_update(self.panel.guard(lambda _e: self.refresh()))
        self.refresh()
        return self

    def refresh(self) -> None:
        """Update the table and the distortion arrows from the current adjustment."""
        res, h = self.state.result, self.handles
        cam = getattr(res, "camera", None) if res is not None else None
        has_ap = res is not None and "additional" in res.groups
        h["folder"].visible = cam is not None or has_ap
        if cam is not None:
            self.text = camera_table(cam, pixel_mm=self.state.units.pixel_mm)
        elif has_ap:
            self.text = additional_table(res)
        else:
            self.text = ""
        h["table"].content = self.text
        on = bool(h["field"].value)
        self._draw_field(cam if on else None, on and cam is None and has_ap)

    def _draw_field(self, cam: Any, ap: bool = False) -> None:
        scene = self.panel.scene
        scene.legend_extra = []
        if self.node is not None:
            self.node.remove()
            self.node = None
        if not ap and (cam is None or cam.kind != "backward"):
            return
        b, k = self.state.block, scene.selected
        ci = int(b.images.camera[k])
        xy = b.observations.xy[b.images.camera[b.observations.image] == ci]
        if xy.shape[0] < 2:
            return
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        if ap:  # an additional-parameter set of the file: its correction field
            opts = block_camera_options(b)
            a = ap_group_values(self.state.result, int(opts["ap_group"][k]))
            if a is None:
                return
            m, d = ap_distortion_vectors(opts["additional"], a, lo, hi)
            pp = np.array([b.cameras.x0[ci], b.cameras.y0[ci]])
            what = f"correction of the additional parameters ({opts['additional'].name})"
        else:
            m, d = distortion_vectors(cam, lo, hi, ci if cam.value.shape[0] > 1 else 0)
            g = ci if cam.value.shape[0] > 1 else 0
            pp, what = np.array([cam.get("x0", g)[0], cam.get("y0", g)[0]]), "lens distortion"
        big = float(np.max(np.linalg.norm(d, axis=1))) if d.size else 0.0
        if not big > 0:
            return
        factor = 0.12 * float(np.max(hi - lo)) / big  # the largest arrow an eighth of the format
        seg = distortion_segments(  # the image plane: rays through m − principal point
            m - pp, d, b.images.X0[k], b.rotations()[k], float(b.cameras.c[b.images.camera[k]]),
            scene.geo.frustum_depth, factor,
        )  # fmt: skip
        self.field_factor, self.field_max_um = factor, big * 1e3
        self.node = scene.scene.add_line_segments(
            f"{scene.root}/distortion", scene.geo.frame.to_scene(seg).astype(np.float32),
            DISTORTION_COLOUR, thickness=2.0, thickness_units="screen",
        )  # fmt: skip
        largest = self.state.units.image_text(big)
        self.handles["table"].content = (
            self.text + f"  \ndistortion arrows ×{factor:.3g} (largest {largest})"
        )
        scene.legend_extra = [
            f"{swatch(DISTORTION_COLOUR, '→')} {what} of the selected image "
            f"(×{factor:.3g}, largest {largest})"
        ]
