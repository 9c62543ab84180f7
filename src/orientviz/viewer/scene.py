"""The viser layer for a block: pushes :class:`BlockGeometry` arrays into scene nodes.

Scene tree (stable names; scene frame = object coordinates − origin, m, Z up)::

    /block/strip_<s>/image_<id>   camera frustum of each image (strip −1: /block/images/…);
                                  above FRUSTUM_NODE_LIMIT images one node per strip,
                                  /block/strip_<s>/frustums
    /block/selected               the selected image's frustum, highlighted
    /block/points/tie|control|check
    /block/rays/all               every ray, projection centre → point (hidden by default)
    /block/rays/selected          the rays of the selected image
    /block/residuals              residual vectors of all observations, × exaggeration
    /block/strips                 polylines through the projection centres of each strip
    /block/models                 ground outlines of the models
    /block/ellipsoids             error ellipsoids of the points (after an adjustment)
    /block/station_ellipsoids     error ellipsoids of projection centres (selected image, neighbours)
    /block/selected_point         the point chosen in the panel, and /block/rays/point its rays
    /block/control_drag           transform controls to drag a control point
    /block/labels/strip_<s>       strip labels

Everything that is per observation is one batched node (a few line-segment and point
cloud nodes), so a block of 2 000 images and 10⁵ observations builds in about a second.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from . import geometry as g
from .block_geometry import COLORS, BlockGeometry
from .geometry import frustum_segments
from .precision_view import confidence_factor, has_covariances, neighbour_correlations
from .shapes import vertex_colours

#: Blocks with more images draw their frustums batched per strip, not one node per image:
#: every node costs the page's start (one draw call, one scene object each; measured in
#: benchmarks/README.md). A click into the scene then
#: selects the image whose frustum passes nearest to the clicked ray
#: (:meth:`BlockScene.image_nearest_to_ray`).
FRUSTUM_NODE_LIMIT = 40

#: A click selects a batched frustum that its ray passes within this angle (rad) of,
#: seen from the eye: about 9 px of an 800 px high view with a 50° field of view.
CLICK_TOLERANCE = 0.01

#: A redraw after an adjustment moves a frustum node only if its apex moved by more than
#: this fraction of the frustum depth or its quaternion by more than this (≈ 0.2 mrad):
#: far below a pixel, and it spares viser hundreds of messages per re-solve.
POSE_TOLERANCE: float = 1e-4

#: Line widths in screen pixels.
WIDTH = {"frustum": 1.5, "ray": 1.0, "residual": 2.0, "strip": 2.0, "model": 1.0, "selected": 3.0}


def safe_name(ident: str) -> str:
    """A scene-tree-safe version of an id (no slashes or spaces)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", str(ident))


def image_node_name(strip: int, ident: str, root: str = "/block") -> str:
    """Stable scene name of an image's frustum, e.g. ``/block/strip_3/image_12``."""
    group = f"strip_{int(strip)}" if strip >= 0 else "images"
    return f"{root}/{group}/image_{safe_name(ident)}"


class BlockScene:
    """Viser nodes of a block; :meth:`update` redraws what depends on the state.

    Parameters
    ----------
    scene : viser.SceneApi
        ``server.scene``.
    geometry : BlockGeometry
        The scene content.
    root : str
        Root of the scene tree.
    exaggeration : float, optional
        Initial residual exaggeration (default: automatic).
    """

    def __init__(
        self,
        scene: Any,
        geometry: BlockGeometry,
        root: str = "/block",
        exaggeration: float | None = None,
    ) -> None:
        self.scene = scene
        self.geo = geometry
        self.root = root
        self.exaggeration = (
            exaggeration if exaggeration is not None else geometry.auto_exaggeration()
        )
        self.selected = 0
        self.rays_mode = "selected image"
        self.nodes: dict[str, Any] = {}
        self.image_nodes: list[Any] = []
        #: large blocks: strip → (line-segment node of its frustums, image indices)
        self.strip_frustums: dict[int, tuple[Any, np.ndarray]] = {}
        self.on_image_click = None
        self.selected_point: int | None = None
        #: what :meth:`update_ellipsoids` draws (the panel's "Precision" folder sets it)
        self.ellipsoid_options: dict[str, Any] = {
            "points": "all" if geometry.state.block.n_points <= 3000 else "selected image",
            "level": 0.95,
            "stations": True,
            "factor": 1.0,
        }
        self.ellipsoids_visible = True
        #: whether the points are shown (a role's node made later takes it)
        self.points_visible = True
        #: frustum colours (m, 3) uint8 as last drawn by :meth:`colour_images`
        self.image_colours: np.ndarray | None = None
        #: functions called after every redraw (e.g. parallax arrows, deformation)
        self.listeners: list = []

    # ------------------------------------------------------------------ building
    def build(self) -> BlockScene:
        """Create all nodes (in one atomic batch)."""
        geo, sc, r = self.geo, self.scene, self.root
        b = geo.state.block
        names = [image_node_name(s, i, r) for s, i in zip(b.images.strip, b.images.ids)]
        self.image_names = names
        if b.n_images <= FRUSTUM_NODE_LIMIT:
            self._build_image_nodes(names)
        else:
            self._build_strip_frustums()
        self._draw_points()
        self.nodes["rays/all"] = sc.add_line_segments(
            f"{r}/rays/all",
            np.zeros((1, 2, 3), np.float32),  # hidden: its rays are drawn when shown (set_rays)
            COLORS["ray"],
            thickness=0.6,
            thickness_units="screen",
            visible=False,
        )
        self.nodes["rays/selected"] = sc.add_line_segments(
            f"{r}/rays/selected", geo.rays(self.selected), COLORS["ray_selected"],
            thickness=WIDTH["ray"], thickness_units="screen",
        )  # fmt: skip
        seg, col = geo.residuals(self.exaggeration)
        self.nodes["residuals"] = sc.add_line_segments(
            f"{r}/residuals", seg, vertex_colours(col), thickness=WIDTH["residual"],
            thickness_units="screen",
        )  # fmt: skip
        self._scale_bar()
        strips = geo.strip_lines()
        if strips.shape[0]:
            self.nodes["strips"] = sc.add_line_segments(
                f"{r}/strips",
                strips,
                COLORS["strip"],
                thickness=WIDTH["strip"],
                thickness_units="screen",
            )
            self._strip_labels()
        models = geo.model_outlines()
        if models.shape[0]:
            self.nodes["models"] = sc.add_line_segments(
                f"{r}/models", models, COLORS["model"], thickness=WIDTH["model"],
                thickness_units="screen", visible=False,
            )  # fmt: skip
        self.nodes["selected"] = sc.add_line_segments(
            f"{r}/selected", self._selected_segments(), COLORS["selected"],
            thickness=WIDTH["selected"], thickness_units="screen",
        )  # fmt: skip
        self.update_ellipsoids()
        return self

    def _draw_points(self) -> None:
        """Point nodes by role; a role without points gets its node when it has some
        (an empty node would still cost the page a shader of its own)."""
        shapes = {"tie": ("circle", 1.0), "control": ("diamond", 2.0), "check": ("diamond", 2.0)}
        for role, P in self.geo.points_by_role().items():
            node = self.nodes.get(f"points/{role}")
            if node is not None:
                node.points = P.astype(np.float32)
            elif len(P):
                shape, f = shapes[role]
                self.nodes[f"points/{role}"] = self.scene.add_point_cloud(
                    f"{self.root}/points/{role}", P.astype(np.float32), COLORS[role],
                    point_size=self.geo.point_size * f, point_shape=shape, precision="float32",
                    visible=self.points_visible,
                )  # fmt: skip

    def _build_image_nodes(self, names: list[str]) -> None:
        """One clickable frustum node per image (small and medium blocks)."""
        geo, b = self.geo, self.geo.state.block
        pos, wxyz = geo.frustum_poses()
        #: the poses last sent to viser (a redraw skips frustums that did not visibly move)
        self.sent_pos, self.sent_wxyz = pos.copy(), wxyz.copy()
        for k, name in enumerate(names):
            fov, aspect, scale = geo.viser_frustum_args(int(b.images.camera[k]))
            h = self.scene.add_camera_frustum(
                name, fov=fov, aspect=aspect, scale=scale, color=COLORS["frustum"],
                thickness=WIDTH["frustum"], thickness_units="screen", wxyz=wxyz[k],
                position=pos[k], cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
            self.image_nodes.append(h)
            self._bind_click(h, k)

    def _build_strip_frustums(self) -> None:
        """Large blocks: the frustums of each strip batched into one line-segment node."""
        b = self.geo.state.block
        for s in np.unique(b.images.strip):
            idx = np.flatnonzero(b.images.strip == s)
            group = f"strip_{int(s)}" if s >= 0 else "images"
            rgb = np.tile(np.asarray(COLORS["frustum"], np.uint8), (idx.size, 1))
            h = self.scene.add_line_segments(
                f"{self.root}/{group}/frustums", self._frustum_segments(idx),
                self._frustum_colours(rgb), thickness=WIDTH["frustum"], thickness_units="screen",
            )  # fmt: skip
            self.strip_frustums[int(s)] = (h, idx)
        # viser's line segments take no clicks: the scene's own click finds the frustum
        self.scene.on_click()(self.scene_clicked)

    def image_nearest_to_ray(self, origin: Any, direction: Any) -> int | None:
        """The image whose frustum the ray (scene frame, m) passes within
        :data:`CLICK_TOLERANCE` of (the nearest such), or None."""
        seg = self._frustum_segments(np.arange(self.geo.state.block.n_images))
        dist = g.ray_segment_distances(origin, direction, seg)
        eye = np.linalg.norm(seg.mean(axis=1) - np.asarray(origin, float), axis=1)
        angle = (dist / np.maximum(eye, 1e-9)).reshape(-1, 8).min(axis=1)
        k = int(np.argmin(angle))
        return k if angle[k] <= CLICK_TOLERANCE else None

    def scene_clicked(self, event: Any) -> None:
        """A click into the scene (batched frustums): select the frustum it hit."""
        k = self.image_nearest_to_ray(event.ray_origin, event.ray_direction)
        if k is not None and self.on_image_click is not None:
            self.on_image_click(k)

    @staticmethod
    def _frustum_colours(rgb: np.ndarray) -> np.ndarray:
        """Per-vertex colours (k·8, 2, 3) of k batched frustums of colours ``rgb`` (k, 3):
        always per vertex (viser's page draws a node that switches from one colour to
        per-vertex colours without them), decoded as :func:`vertex_colours` says."""
        return np.repeat(vertex_colours(rgb), 16, axis=0).reshape(-1, 2, 3)

    def _frustum_segments(self, images: np.ndarray) -> np.ndarray:
        return frustum_segments(self.geo.frustum_corners(images)).astype(np.float32)

    def _bind_click(self, handle: Any, k: int) -> None:
        def clicked(_event: Any) -> None:
            if self.on_image_click is not None:
                self.on_image_click(k)

        try:
            handle.on_click(clicked)
        except Exception:  # older viser without clickable frustums: selection via GUI only
            pass

    def _strip_labels(self) -> None:
        b = self.geo.state.block
        X = self.geo.frame.to_scene(b.images.X0)
        strips = np.unique(b.images.strip[b.images.strip >= 0])
        every = max(1, int(np.ceil(strips.size / 8)))  # at most about eight labels
        for s in strips[::every]:
            first = X[b.images.strip == s][0]
            self.nodes[f"labels/strip_{s}"] = self.scene.add_label(
                f"{self.root}/labels/strip_{s}",
                f"strip {s}",
                position=first + [0, 0, 0.15 * self.geo.height],
            )

    def _selected_segments(self) -> np.ndarray:
        return frustum_segments(self.geo.frustum_corners(np.array([self.selected])))

    # ------------------------------------------------------------------ updates
    def update(self, images: list[int] | None = None) -> dict[str, float]:
        """Redraw after the state changed; returns the misclosure statistics used.

        Parameters
        ----------
        images : list of int, optional
            Images whose orientation changed (their frustums are moved); default all.
        """
        geo = self.geo
        e = geo.state.misclosure()
        scores, kind = geo.state.scores(e)
        seg, col = geo.residuals(self.exaggeration, e, scores)
        self._move_frustums(images)
        self.nodes["residuals"].points = seg.astype(np.float32)
        self.nodes["residuals"].colors = vertex_colours(col)
        self.nodes["selected"].points = self._selected_segments().astype(np.float32)
        if self.rays_mode == "selected image":
            self.nodes["rays/selected"].points = geo.rays(self.selected).astype(np.float32)
        if self.nodes["rays/all"].visible:  # hidden: drawn anew when shown (set_rays)
            self.nodes["rays/all"].points = geo.rays().astype(np.float32)
        if images is None:
            self._draw_points()
            if "strips" in self.nodes:
                self.nodes["strips"].points = geo.strip_lines().astype(np.float32)
        self.last_scores, self.score_kind = scores, kind
        if images is None and self.selected_point is not None:
            self.select_point(self.selected_point)
        for fn in self.listeners:
            fn()
        return {"sigma0": geo.state.sigma0(e), "max_score": float(np.nanmax(scores, initial=0.0))}

    def _move_frustums(self, images: list[int] | None) -> None:
        if self.image_nodes:
            pos, wxyz = self.geo.frustum_poses()
            ks = np.arange(len(self.image_nodes)) if images is None else np.asarray(images)
            if images is None:  # after an adjustment: send only poses that visibly moved
                tol = POSE_TOLERANCE * self.geo.frustum_depth
                moved = (np.linalg.norm(pos - self.sent_pos, axis=1) > tol) | (
                    np.abs(wxyz - self.sent_wxyz).max(axis=1) > POSE_TOLERANCE
                )
                ks = ks[moved]
            for k in ks:
                self.image_nodes[k].position = pos[k]
                self.image_nodes[k].wxyz = wxyz[k]
            self.sent_pos[ks], self.sent_wxyz[ks] = pos[ks], wxyz[ks]
            return
        strips = self.geo.state.block.images.strip
        touched = None if images is None else {int(strips[k]) for k in images}
        for s, (h, idx) in self.strip_frustums.items():
            if touched is None or s in touched:
                h.points = self._frustum_segments(idx)

    def set_exaggeration(self, k: float) -> None:
        """Redraw the residual vectors and the scale bar with exaggeration ``k``."""
        changed = float(k) != self.exaggeration
        self.exaggeration = float(k)
        seg, col = self.geo.residuals(self.exaggeration)
        self.nodes["residuals"].points = seg.astype(np.float32)
        self.nodes["residuals"].colors = vertex_colours(col)
        if changed:
            self._scale_bar()

    def _scale_bar(self) -> None:
        """(Re)draw the residuals' scale bar and its label (:meth:`BlockGeometry.scale_bar`)."""
        seg, at, text = self.geo.scale_bar(self.exaggeration)
        self.scale_bar_text = text
        self.nodes["scale_bar"] = self.scene.add_line_segments(
            f"{self.root}/scale_bar", seg.astype(np.float32), COLORS["scale_bar"],
            thickness=WIDTH["residual"] + 1.0, thickness_units="screen",
            visible=self.nodes["residuals"].visible,
        )  # fmt: skip
        self.nodes["labels/scale_bar"] = self.scene.add_label(
            f"{self.root}/labels/scale_bar", text, position=at.astype(np.float32),
            visible=self.nodes["residuals"].visible,
        )  # fmt: skip

    def select(self, image: int) -> None:
        """Highlight image ``image`` and show its rays (and its ellipsoids, if so chosen)."""
        changed = int(image) != self.selected
        self.selected = int(image)
        self.nodes["selected"].points = self._selected_segments().astype(np.float32)
        self.nodes["rays/selected"].points = self.geo.rays(self.selected).astype(np.float32)
        opt = self.ellipsoid_options
        if changed and (opt["points"] == "selected image" or opt["stations"]):
            self.update_ellipsoids(new_gain=False)

    def set_rays(self, mode: str) -> None:
        """``"none"``, ``"selected image"`` or ``"all"``."""
        self.rays_mode = mode
        self.nodes["rays/selected"].visible = mode == "selected image"
        self.nodes["rays/all"].visible = mode == "all"
        if mode == "all":
            self.nodes["rays/all"].points = self.geo.rays().astype(np.float32)

    def update_ellipsoids(self, new_gain: bool = True) -> float | None:
        """(Re)draw the confidence ellipsoids from the current adjustment.

        What is drawn follows :attr:`ellipsoid_options`: ``"points"`` (``"all"``,
        ``"selected image"`` or ``"none"``), ``"level"`` (confidence, 0–1),
        ``"stations"`` (the selected image's projection centre and its neighbours') and
        ``"factor"`` (× the automatic exaggeration, which is recomputed when ``new_gain``).
        Returns the exaggeration used (None if nothing has a covariance).
        """
        opt = self.ellipsoid_options
        for key in ("ellipsoids", "station_ellipsoids"):
            old = self.nodes.pop(key, None)
            if old is not None:
                old.remove()
        if self.geo.state.result is None or not self.geo.state.at_result:
            return None  # ellipsoids belong to the adjusted state (not to a replayed one)
        if not has_covariances(self.geo.state.result):
            return None  # solved without the precision (a large block at opening): none to draw
        k = confidence_factor(opt["level"])
        if new_gain or not getattr(self, "auto_ellipsoid_gain", None):
            self.auto_ellipsoid_gain = self.geo.ellipsoid_gain(k)
        gain = self.ellipsoid_scale = self.auto_ellipsoid_gain * float(opt["factor"])
        self.confidence_k = k
        pts = self.geo.shown_points(opt["points"], self.selected)
        self._mesh("ellipsoids", self.geo.ellipsoids(pts, k, gain) if pts.size else None, 0.55)
        if opt["stations"]:
            m = self.geo.state.block.n_images
            nb, _ = neighbour_correlations(self.geo.state.result, self.selected, m)
            imgs = np.concatenate([[self.selected], nb])
            if new_gain or not getattr(self, "station_gain", None):
                self.station_gain = self.geo.station_gain(k)
            sg = self.station_gain * float(opt["factor"])
            self._mesh("station_ellipsoids", self.geo.station_ellipsoids(imgs, k, sg), 0.6)
        return gain

    def _mesh(self, key: str, mesh: tuple | None, opacity: float) -> None:
        """Add the ellipsoid mesh ``(vertices, faces)`` as node ``key`` (nothing for None)."""
        if mesh is None:
            return
        colour = COLORS["ellipsoid" if key == "ellipsoids" else "station"]
        self.nodes[key] = self.scene.add_mesh_simple(
            f"{self.root}/{key}", mesh[0].astype(np.float32), mesh[1], color=colour,
            opacity=opacity, flat_shading=False, cast_shadow=False, receive_shadow=False,
            visible=self.ellipsoids_visible,
        )  # fmt: skip

    # ------------------------------------------------------------------ colours by quality
    def colour_images(self, rgb: np.ndarray | None) -> None:
        """Colour each image's frustum (rgb (m, 3) uint8; None: the default colour)."""
        m = self.geo.state.block.n_images
        rgb = np.tile(COLORS["frustum"], (m, 1)) if rgb is None else np.asarray(rgb)
        rgb = rgb.astype(np.uint8)
        last = self.image_colours
        for k, h in enumerate(self.image_nodes):
            if last is None or not np.array_equal(last[k], rgb[k]):
                h.color = tuple(int(c) for c in rgb[k])
        for h, idx in self.strip_frustums.values():
            h.colors = self._frustum_colours(rgb[idx])
        self.image_colours = rgb

    def colour_points(self, rgb: np.ndarray | None) -> None:
        """Colour the points (rgb (p, 3) uint8; None: by role)."""
        role = self.geo.state.block.points.role
        for r, name in ((0, "tie"), (1, "control"), (2, "check")):
            h = self.nodes.get(f"points/{name}")
            if h is None:
                continue
            n = int(np.count_nonzero(role == r))
            if rgb is None:
                h.colors = np.tile(np.asarray(COLORS[name], np.uint8), (n, 1))
            else:
                h.colors = np.asarray(rgb, np.uint8)[role == r]

    def select_point(self, k: int | None) -> None:
        """Mark point ``k`` (None: no point) and draw its rays."""
        geo, b = self.geo, self.geo.state.block
        for key in ("selected_point", "rays/point"):
            old = self.nodes.pop(key, None)
            if old is not None:
                old.remove()
        self.selected_point = k
        if k is None:
            return
        P = geo.frame.to_scene(b.points.xyz[k : k + 1])
        self.nodes["selected_point"] = self.scene.add_point_cloud(
            f"{self.root}/selected_point", P.astype(np.float32), COLORS["selected"],
            point_size=geo.point_size * 3.0, point_shape="circle", precision="float32",
        )  # fmt: skip
        o = b.observations
        sel = np.flatnonzero(o.point == k)
        rays = geo.frame.to_scene(
            g.ray_segments(b.images.X0[o.image[sel]], b.points.xyz[o.point[sel]])
        )
        self.nodes["rays/point"] = self.scene.add_line_segments(
            f"{self.root}/rays/point", rays.astype(np.float32), COLORS["ray_selected"],
            thickness=WIDTH["ray"], thickness_units="screen",
        )  # fmt: skip

    def set_visible(self, key: str, visible: bool) -> None:
        """Show or hide a group: ``"frustums"``, ``"points"``, ``"residuals"``, ``"strips"``, …"""
        if key == "ellipsoids":
            self.ellipsoids_visible = visible
            for name in ("ellipsoids", "station_ellipsoids"):
                if name in self.nodes:
                    self.nodes[name].visible = visible
            return
        if key == "frustums":
            for h in self.image_nodes + [h for h, _ in self.strip_frustums.values()]:
                h.visible = visible
            return
        if key == "points":
            self.points_visible = visible
        names = (key, "scale_bar", "labels/scale_bar") if key == "residuals" else (key,)
        for name, h in self.nodes.items():
            if name in names or name.startswith(key + "/"):
                h.visible = visible
