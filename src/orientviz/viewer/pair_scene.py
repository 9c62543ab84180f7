"""The stereo-pair demo: Kovarik's analog plotter in 3D, with y-parallax arrows.

The pair comes from :mod:`orientviz.orientation.plotter` (a dependent pair: the left
projector fixed at the origin with R = I, the right one at the base (b, by, bz) turned
by its dials ω, φ, κ through the instrument's axes, φ-ω-κ by default:
R = R_φ R_ω R_κ). Model frame: X along the base, Y left, Z up, terrain at Z < 0, all in
*machine millimetres*.

Scene tree::

    /pair/left, /pair/right        the two projectors (frustums)
    /pair/terrain                  model points of a grid over the model area
    /pair/scheme                   the points read in a pass (Kovarik's nine by default)
    /pair/rays                     rays of both projectors to the scheme points
    /pair/parallax                 y-parallax arrows, from the left ray to the right
                                   ray (p_y = Y_left − Y_right), × exaggeration
    /pair/selected/rays            the two rays of the selected scheme point
    /pair/selected/gap             their shortest connecting segment (to scale)
    /pair/selected/closest         its two ends
    /pair/selected/epipolar_plane  the epipolar plane of the left ray (O1, O2, d1)

The panel has the five dials (by, bz in mm; ω, φ, κ in centesimal minutes c), one
pass / orient to convergence with a chosen formula, a pass scrubber and reset; a chosen
point with its gap and plane (:func:`~orientviz.viewer.pair_rays.point_rays`), and on
request the normalised (epipolar) images of the pair as a picture beside the scene
(:func:`~orientviz.viewer.epipolar_picture.normalised_picture`). Everything follows the
dials live.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..orientation.plotter import AnalogPlotter, PlotterConfig, true_pair
from ..rotation import matrix_from_opk
from ..units import RHO_C
from . import geometry as g
from .block_geometry import COLORS
from .demo import Demo
from .epipolar_picture import normalised_picture
from .legend import swatch
from .pair_rays import normalised_pair, plane_mesh, point_rays
from .shapes import vertex_colours
from .sliders import Sliders

F64 = NDArray[np.float64]

DIALS = ("by [mm]", "bz [mm]", "omega [c]", "phi [c]", "kappa [c]")
LEFT_RAY, RIGHT_RAY, GAP = (40, 70, 160), (250, 130, 0), (200, 0, 130)


def pair_geometry(plotter: Any, n_grid: int = 15) -> dict[str, F64]:
    """Arrays of the pair scene under the plotter's current dials (machine mm).

    Returns
    -------
    dict
        ``centres`` (2, 3), ``rotations`` (2, 3, 3) image → model, ``terrain`` (g, 3)
        model points of a grid, ``parallax`` (g,) p_y in mm at them, ``scheme`` (k, 3)
        model points of the scheme and ``scheme_parallax`` (k,).
    """
    cfg = plotter.config
    st = plotter.state
    R2 = matrix_from_opk(*st.angles_right, sequence=st.sequence)
    b, d = cfg.model_base, cfg.k * cfg.projection_distance
    X, Y = np.meshgrid(np.linspace(0.0, b, n_grid), np.linspace(-d, d, n_grid))
    P = np.column_stack([X.ravel(), Y.ravel(), plotter.pair.height(X, Y).ravel()])
    p, pts = plotter.parallax_at(P)
    Xs, Ys, Zs = plotter.scheme_points()
    ps, spts = plotter.parallax_at(np.column_stack([Xs, Ys, Zs]))
    return {
        "centres": np.array([np.zeros(3), st.base]),
        "rotations": np.array([np.eye(3), R2]),
        "terrain": pts,
        "parallax": p,
        "scheme": spts,
        "scheme_parallax": ps,
    }


#: Colour of the right projector (the left one has the frustum colour).
RIGHT_PROJECTOR = (250, 130, 0)


def length_text(mm: float) -> str:
    """A length in machine mm as µm below 1 mm, else in mm (signed, e.g. ``+957 µm``)."""
    return f"{mm * 1000:+.0f} µm" if abs(mm) < 1.0 else f"{mm:+.2f} mm"


def parallax_arrows(points: F64, parallax: F64, exaggeration: float) -> F64:
    """Arrows from the left ray (Y + p/2) to the right ray (Y − p/2), × exaggeration.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Model points (the mean Y of the two rays), machine mm.
    parallax : ndarray, shape (n,)
        p_y = Y_left − Y_right in machine mm.
    exaggeration : float

    Returns
    -------
    ndarray, shape (3n, 2, 3)
        Line segments (shaft and two head strokes per arrow).
    """
    half = np.zeros_like(points)
    half[:, 1] = 0.5 * exaggeration * parallax
    return g.arrow_segments(points + half, -2.0 * half, head=0.3)


def pair_demo(rng: np.random.Generator | int = 7) -> Demo:
    """The ``pair`` demo (see the module docstring)."""
    gen = np.random.default_rng(rng) if isinstance(rng, int) else rng
    cfg = PlotterConfig(sigma_by=0.0, sigma_z=0.0)
    pair = true_pair(cfg, rng=gen)
    plotter = AnalogPlotter(pair)
    desc = (
        f"A dependent pair on a simulated analog plotter (c = {cfg.c} mm, model base "
        f"{cfg.model_base} mm, relief {cfg.relief:.0%}). The right projector starts at zero "
        "dials, about 100-150 c from the truth. Arrows: y-parallax from the left to the "
        "right ray. Move the dials, or run passes with Kovarik's nine points."
    )
    return Demo(
        "pair",
        "Relative orientation of a pair",
        desc,
        None,
        lambda app: PairView(app, plotter).build(),
    )


def pair_legend(scale_bar_text: str) -> str:
    """The pair scene's legend (Markdown): every colour drawn, and the arrows' scale."""
    return "  \n".join([
        f"{swatch(COLORS['frustum'], '△')} left projector, {swatch(RIGHT_PROJECTOR, '△')} right "
        "projector (its dials turn it)",
        f"{swatch(COLORS['tie'], '●')} model points, {swatch(COLORS['control'], '◆')} the "
        "scheme's points (the passes clear their y-parallax)",
        f"{swatch(COLORS['ray'], '▬')} rays of the scheme points",
        f"y-parallax arrows by size: {swatch((40, 160, 80))} small {swatch((240, 170, 20))} "
        f"{swatch((210, 30, 30))} the largest now; {swatch((30, 30, 30), '▬')} " + scale_bar_text,
        f"selected point: {swatch(LEFT_RAY, '▬')} left ray, {swatch(RIGHT_RAY, '▬')} right ray, "
        f"{swatch(GAP, '▬')} their gap (closest points {swatch(LEFT_RAY, '●')}"
        f"{swatch(RIGHT_RAY, '●')}), {swatch(LEFT_RAY, '■')} epipolar plane of the left ray",
    ])  # fmt: skip


class PairView:
    """Nodes and controls of the pair demo."""

    def __init__(self, app: Any, plotter: Any) -> None:
        self.app, self.plotter = app, plotter
        self.start = plotter.settings.copy()
        self.snapshots = [plotter.settings.copy()]
        self._syncing = False

    def build(self) -> dict:
        app, pl = self.app, self.plotter
        sc, gui, cfg = app.server.scene, app.server.gui, pl.config
        geo = pair_geometry(pl)
        self.frame = g.SceneFrame.around(np.vstack([geo["terrain"], geo["centres"]]))
        H = cfg.projection_distance
        self.depth = 0.22 * H
        fov, aspect, scale = g.viser_frustum(cfg.c, (cfg.format_mm, cfg.format_mm), self.depth)
        self.spacing = g.typical_spacing(geo["terrain"])
        #: the arrows' scale, fixed while the dials turn (re-fitted only on request)
        self.base_k = self.k = self.auto_k(geo["parallax"])
        self.terrain_box = (geo["terrain"].min(axis=0), geo["terrain"].max(axis=0))
        self.nodes: dict[str, Any] = {}
        for name, color in (("left", COLORS["frustum"]), ("right", RIGHT_PROJECTOR)):
            self.nodes[name] = sc.add_camera_frustum(
                f"/pair/{name}", fov=fov, aspect=aspect, scale=scale, color=color,
                thickness=2.0, thickness_units="screen", cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
        ps = 0.15 * self.spacing
        self.nodes["terrain"] = sc.add_point_cloud(
            "/pair/terrain", np.zeros((1, 3), np.float32), COLORS["tie"], point_size=ps,
            point_shape="circle", precision="float32",
        )  # fmt: skip
        self.nodes["scheme"] = sc.add_point_cloud(
            "/pair/scheme", np.zeros((1, 3), np.float32), COLORS["control"], point_size=2.2 * ps,
            point_shape="diamond", precision="float32",
        )  # fmt: skip
        z2 = np.zeros((1, 2, 3), np.float32)
        self.nodes["rays"] = sc.add_line_segments(
            "/pair/rays", z2, COLORS["ray"], thickness=1.0, thickness_units="screen"
        )
        self.nodes["parallax"] = sc.add_line_segments(
            "/pair/parallax", z2, COLORS["deformation"], thickness=2.0, thickness_units="screen"
        )
        self._build_selection_nodes(sc, ps)
        h: dict[str, Any] = {}
        sliders = self.sliders = Sliders(gui, h)  # the server sets these too
        with gui.add_folder("Dials of the right projector") as folder:
            for i, label in enumerate(DIALS):
                lim, step = (5.0, 0.01) if i < 2 else (250.0, 1.0)
                sliders.add(label, folder, label, -lim, lim, step, self._dial(i))
        with gui.add_folder("Passes") as folder:
            h["formula"] = gui.add_dropdown("formula", ("exact", "kovarik9", "flat", "preorient"))
            h["pass"] = gui.add_button("one pass")
            h["orient"] = gui.add_button("orient to convergence")
            h["reset"] = gui.add_button("reset")
            sliders.add("scrub", folder, "pass", 0, 1, 1, 0, disabled=True)
            h["stats"] = gui.add_markdown("")
        with gui.add_folder("Selected point"):
            names = tuple(str(i + 1) for i in range(len(geo["scheme"])))
            h["point"] = gui.add_dropdown("scheme point", ("none", *names), initial_value="5")
            h["plane"] = gui.add_checkbox("epipolar plane of the left ray", True)
            h["point_info"] = gui.add_markdown("")
        with gui.add_folder("Legend"):
            h["legend"] = gui.add_markdown("")
        with gui.add_folder("Display"):
            h["exaggeration"] = gui.add_slider(
                "parallax × (log10)", -2.0, 2.0, 0.05, 0.0,
                hint="× 10^value of the fixed arrow scale (see the scale bar in the scene)",
            )  # fmt: skip
            h["rescale"] = gui.add_button(
                "fit the arrow scale to this state",
                hint="the scale stays fixed while the dials turn; this chooses it anew",
            )
            h["normalised"] = gui.add_checkbox(
                "normalised images", False,
                hint="the pair re-projected to the normal case: epipolar lines are rows",
            )  # fmt: skip
        with gui.add_folder("Normalised (epipolar) images", visible=False) as h["picture_folder"]:
            h["picture"] = gui.add_image(np.full((8, 8, 3), 255, np.uint8), visible=False)
            h["picture_info"] = gui.add_markdown("", visible=False)
        self.h = h
        h["legend"].content = pair_legend(getattr(self, "scale_bar_text", "scale bar"))
        guard = app.guard
        for label in DIALS:
            sliders.on_update(label, guard(lambda _e: self._from_sliders()))
        h["pass"].on_click(guard(lambda _e: self._passes(1)))
        h["orient"].on_click(guard(lambda _e: self._passes(30)))
        h["reset"].on_click(guard(lambda _e: self._set(self.start, reset=True)))
        sliders.on_update(
            "scrub", guard(lambda _e: self._set(self.snapshots[int(h["scrub"].value)], keep=True))
        )
        h["exaggeration"].on_update(guard(lambda _e: self._exaggerate()))
        h["rescale"].on_click(guard(lambda _e: self.rescale()))
        for key in ("point", "plane", "normalised"):
            h[key].on_update(guard(lambda _e: self.redraw()))
        self.redraw()
        # the whole pair (terrain, both projectors and their frustums) left of the panel
        top = geo["centres"] + [0.0, 0.0, self.depth]
        seen = self.frame.to_scene(np.vstack([geo["terrain"], geo["centres"], top]))
        b = cfg.model_base
        pos, look = g.framing(seen, direction=(1.4 * b, 1.1 * b, -1.5 * H), margin=0.9)
        return {"camera": (pos, look, self.frame.size), "pair": self}

    def _build_selection_nodes(self, sc: Any, ps: float) -> None:
        z2 = np.zeros((2, 2, 3), np.float32)
        self.nodes["sel_rays"] = sc.add_line_segments(
            "/pair/selected/rays", z2, np.array([[LEFT_RAY] * 2, [RIGHT_RAY] * 2], np.uint8),
            thickness=3.0, thickness_units="screen",
        )  # fmt: skip
        self.nodes["gap"] = sc.add_line_segments(
            "/pair/selected/gap", z2[:1], GAP, thickness=5.0, thickness_units="screen"
        )
        self.nodes["closest"] = sc.add_point_cloud(
            "/pair/selected/closest", np.zeros((2, 3), np.float32),
            np.array([LEFT_RAY, RIGHT_RAY], np.uint8), point_size=1.5 * ps,
            point_shape="circle", precision="float32",
        )  # fmt: skip
        V, F = plane_mesh(np.eye(4, 3))
        self.nodes["epipolar_plane"] = sc.add_mesh_simple(
            "/pair/selected/epipolar_plane", V.astype(np.float32), F, color=LEFT_RAY,
            opacity=0.22, side="double", cast_shadow=False, receive_shadow=False,
        )  # fmt: skip

    # ------------------------------------------------------------------ state
    def _dial(self, i: int) -> float:
        v = self.plotter.settings[i]
        return round(float(v if i < 2 else v * RHO_C), 2)

    def _from_sliders(self) -> None:
        if self._syncing:
            return
        s = np.array([float(self.h[lab].value) for lab in DIALS])
        s[2:] /= RHO_C
        self.plotter.settings[:] = s
        self.redraw()

    def _sync_sliders(self) -> None:
        self._syncing = True
        try:
            for i, lab in enumerate(DIALS):
                self.sliders.set(lab, self._dial(i))
        finally:
            self._syncing = False

    def _set(self, settings: F64, reset: bool = False, keep: bool = False) -> None:
        if self._syncing:
            return
        self.plotter.settings[:] = settings
        if reset:
            self.plotter.history.clear()
            self.snapshots = [settings.copy()]
        self._sync_sliders()
        if not keep:
            self._sync_scrubber()
        self.redraw()

    def _passes(self, n: int) -> None:
        formula = str(self.h["formula"].value)
        if n == 1:
            self.plotter.run_pass(formula)
            self.snapshots.append(self.plotter.settings.copy())
        else:
            run = self.plotter.orient(formula, max_passes=n)
            self.snapshots += [p.settings_after.copy() for p in run.passes]
            if not run.converged:
                self.app.report(f"no convergence after {run.n_passes} passes with {formula!r}")
        self._sync_sliders()
        self._sync_scrubber()
        self.redraw()

    def _sync_scrubber(self) -> None:
        self._syncing = True
        try:
            n = len(self.snapshots)
            self.h["scrub"].max = max(n - 1, 1)
            self.sliders.set("scrub", n - 1)
            self.h["scrub"].disabled = n < 2
        finally:
            self._syncing = False

    def auto_k(self, parallax: F64) -> float:
        """Exaggeration drawing the 90th percentile of ``|p_y|`` as 0.8 of a grid spacing.

        Kept within [1, 10⁵] so that a parallax-free model (rounding noise) shows no arrows.
        """
        p90 = float(np.percentile(np.abs(parallax), 90))
        return float(np.clip(0.8 * self.spacing / p90, 1.0, 1e5)) if p90 > 0 else 1.0

    def _exaggerate(self) -> None:
        self.redraw()

    def rescale(self) -> None:
        """Fit the arrow scale to the current parallaxes (it stays fixed otherwise)."""
        self.base_k = self.auto_k(pair_geometry(self.plotter)["parallax"])
        self.redraw()

    def _scale_bar(self) -> None:
        """A bar for a round y-parallax (1, 2 or 5 × 10ⁿ mm) at the arrows' scale."""
        target = 1.5 * self.spacing / self.k
        e = np.floor(np.log10(target))
        m = target / 10**e
        value = float((5 if m >= 5 else 2 if m >= 2 else 1) * 10**e)  # machine mm
        lo, hi = self.terrain_box
        # along Y (the parallax's direction) at the terrain's edge X = 0 ending at its far
        # side +Y: the corner farthest from the GUI panel in the first view
        end = np.array([lo[0] - 0.6 * self.spacing, hi[1], lo[2]])
        start = end - [0.0, value * self.k, 0.0]
        tick = np.array([0.25 * self.spacing, 0.0, 0.0])
        seg = np.array([[start, end], [start - tick, start + tick], [end - tick, end + tick]])
        sc, f = self.app.server.scene, self.frame
        key = (round(value, 15), round(self.k, 6))
        if getattr(self, "_bar_key", None) == key:
            return
        self._bar_key = key
        size = f"{value * 1000:g} µm" if value < 1 else f"{value:g} mm"
        text = f"y-parallax ×{self.k:.3g}: bar = {size} (machine)"
        self.scale_bar_text = text
        if getattr(self, "h", None) is not None:
            self.h["legend"].content = pair_legend(text)
        self.nodes["scale_bar"] = sc.add_line_segments(
            "/pair/scale_bar", f.to_scene(seg).astype(np.float32), (30, 30, 30),
            thickness=3.0, thickness_units="screen",
        )  # fmt: skip
        self.nodes["scale_label"] = sc.add_label(
            "/pair/labels/scale_bar", text, anchor="top-center",
            position=f.to_scene((start + end) / 2 - 3 * tick).astype(np.float32),
        )  # fmt: skip

    # ------------------------------------------------------------------ drawing
    def redraw(self) -> None:
        """Re-project under the current dials and update every node."""
        geo = pair_geometry(self.plotter)
        f = self.frame
        q = g.wxyz_from_matrix(geo["rotations"] @ g.FLIP)
        for k, name in enumerate(("left", "right")):
            self.nodes[name].position = f.to_scene(geo["centres"][k])
            self.nodes[name].wxyz = q[k]
        self.nodes["terrain"].points = f.to_scene(geo["terrain"]).astype(np.float32)
        self.nodes["scheme"].points = f.to_scene(geo["scheme"]).astype(np.float32)
        S = geo["scheme"]
        rays = np.concatenate(
            [g.ray_segments(np.broadcast_to(c, S.shape), S) for c in geo["centres"]]
        )
        self.nodes["rays"].points = f.to_scene(rays).astype(np.float32)
        slider = self.h.get("exaggeration") if hasattr(self, "h") else None
        extra = 10 ** float(slider.value) if slider is not None else 1.0
        self.k = self.base_k * extra
        self._scale_bar()
        arrows = parallax_arrows(geo["terrain"], geo["parallax"], self.k)
        col = g.ramp(
            np.repeat(np.abs(geo["parallax"]), 3), max(np.abs(geo["parallax"]).max(), 1e-9)
        )
        self.nodes["parallax"].points = f.to_scene(arrows).astype(np.float32)
        self.nodes["parallax"].colors = np.repeat(vertex_colours(col)[:, None, :], 2, axis=1)
        err = self.plotter.error
        rms = float(np.sqrt(np.mean(geo["parallax"] ** 2)))
        self.h["stats"].content = (
            f"RMS y-parallax over the model: **{rms * 1000:.1f} µm** (machine)  \n"
            f"{self.dials_text()}  \n"
            f"dials − truth: by {err[0]:+.3f}, bz {err[1]:+.3f} mm; "
            f"ω {err[2] * RHO_C:+.1f}, φ {err[3] * RHO_C:+.1f}, κ {err[4] * RHO_C:+.1f} c  \n"
            f"arrows ×{self.k:.3g} (left ray → right ray)"
        )
        self.rms = rms
        if hasattr(self, "h"):
            self._draw_selection(geo)
            self._draw_picture(geo)

    def dials_text(self) -> str:
        """Where the dials stand against the pass the scrubber shows.

        ``"dials at pass 5 of 5"`` when they equal that pass; ``"dials at pass 5 of 5,
        turned by κ +2.0 c"`` once a dial (by hand or from a notebook) moved them away
        from it, so that the scrubber and the read-out never contradict each other.
        Differences below half a dial's step (0.005 mm, 0.5 c: the sliders' rounding) are
        not counted as turns.
        """
        n = len(self.snapshots) - 1
        k = min(int(self.h["scrub"].value), n) if hasattr(self, "h") else n
        where = f"dials at pass {k} of {n}" if n else "dials at the start"
        d = self.plotter.settings - self.snapshots[k]
        moved = [
            f"{name} {d[i]:+.3f} mm" if i < 2 else f"{name} {d[i] * RHO_C:+.1f} c"
            for i, name in enumerate(("by", "bz", "ω", "φ", "κ"))
            if abs(d[i]) >= (0.005 if i < 2 else 0.5 / RHO_C)  # half a dial's step
        ]
        return f"{where}, turned by {', '.join(moved)}" if moved else where

    def selected(self) -> int | None:
        """Index of the selected scheme point, or None."""
        v = str(self.h["point"].value)
        return None if v == "none" else int(v) - 1

    def _draw_selection(self, geo: dict) -> None:
        i = self.selected()
        nodes = ("sel_rays", "gap", "closest", "epipolar_plane")
        if i is None:
            for key in nodes:
                self.nodes[key].visible = False
            self.h["point_info"].content = "Choose a scheme point to see its two rays."
            self.point = None
            return
        X, Y, Z = self.plotter.scheme_points()
        self.point = pr = point_rays(self.plotter, (X[i], Y[i], Z[i]))
        f = self.frame
        self.nodes["sel_rays"].points = f.to_scene(pr["rays"]).astype(np.float32)
        self.nodes["gap"].points = f.to_scene(pr["closest"][None]).astype(np.float32)
        self.nodes["closest"].points = f.to_scene(pr["closest"]).astype(np.float32)
        self.nodes["epipolar_plane"].vertices = f.to_scene(pr["plane"]).astype(np.float32)
        for key in nodes[:3]:
            self.nodes[key].visible = True
        self.nodes["epipolar_plane"].visible = bool(self.h["plane"].value)
        gap = ", ".join(length_text(v) for v in pr["gap"])
        self.h["point_info"].content = (
            f"point {i + 1}: left ray (blue), right ray (orange), the shortest segment between "
            f"them (magenta) **{length_text(pr['gap_length']).lstrip('+')}** = ({gap}); "
            f"y-parallax p_y = {length_text(pr['p_y'])} (machine).  \n"
            f"The right ray passes {length_text(pr['right_off_plane'])} off the epipolar plane "
            "of the left ray (through O1, O2 and the left ray): 0 when the pair is oriented."
        )

    def _draw_picture(self, geo: dict) -> None:
        show = bool(self.h["normalised"].value)
        for key in ("picture_folder", "picture", "picture_info"):
            self.h[key].visible = show
        if not show:
            return
        X, Y, Z = self.plotter.scheme_points()
        norm = normalised_pair(self.plotter, np.column_stack([X, Y, Z]))
        pic, k = normalised_picture(norm, self.selected())
        self.h["picture"].image = pic
        rms = float(np.sqrt(np.mean(norm["p_y"] ** 2)))
        self.h["picture_info"].content = (
            f"The scheme points in the normalised images (c = {norm['c']} mm): epipolar lines "
            f"are rows (orange: the selected point's). Bars: y₁′ − y₂′ × {k:.3g}, "
            f"RMS {length_text(rms).lstrip('+')} (image)."
        )
        self.picture = pic
        self.norm = norm
