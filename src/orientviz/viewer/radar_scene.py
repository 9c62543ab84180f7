"""The radar demo: Geier's (1973) panorama images in 3D, drawn to teach.

Data from :mod:`orientviz.radar.geier1973` (Fig. 7: 25 grid points, three images;
Fig. 8 surfaces); geometry from :mod:`orientviz.radar.ppi`,
:mod:`orientviz.radar.trilateration` and :mod:`orientviz.viewer.radar_geometry`. Object
frame in m, Z up; the stations fly at Z ≈ 0 and the terrain lies near Z = −15 500 m.
Rotations φ-ω-κ (R = R_φ R_ω R_κ), κ the reference direction about the antenna axis k.

Only the **selected image** is drawn in full; the other two stations are faded. For a
chosen **target** point the scene draws Geier's construction (Fig. 4,
:func:`~orientviz.viewer.radar_geometry.geier_construction`): the slant range s, the
slant-range circle in which the azimuth plane (4c) cuts the range sphere (4b), the
ground plane ⟂ k at the distance h below the station, and in it the image point at
the approximate horizontal range s_e — the triangle h, s_e, s of the reduction.

Scene tree::

    /radar/points                the 25 object points of the chosen surface
    /radar/target                the chosen target
    /radar/station_<i>           the three stations with their axis (others faded)
    /radar/sphere_<j>            shaded, semi-transparent caps of the range spheres about
                                 three points of the largest triangle, radius = slant
                                 range from the selected image (trilateration)
    /radar/candidates            the two points common to the three spheres
    /radar/geier/...             the construction of the target: slant_range, circle,
                                 arc, ground_plane, h, s_e, reduced, image_point,
                                 range_ring, azimuth_plane, target_sphere, labels
    /radar/circles               projection circles of all points (off by default)

A legend in the panel names every element with its colour.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..radar import geier1973 as G
from ..radar import scene as RS
from ..radar.trilateration import sphere_ranges
from . import geometry as g
from . import radar_geometry as rg
from .demo import Demo

STATION_COLORS = {1: (40, 70, 160), 2: (250, 130, 0), 3: (20, 150, 60)}
FADED = (175, 175, 175)
#: Shades of the three range spheres' caps (about Fig. 7's points 1, 5 and 21).
SPHERE_COLORS = ((110, 150, 225), (235, 150, 90), (120, 195, 130))

#: Colours of the construction and their legend text (one place for both).
ELEMENTS: dict[str, tuple[tuple[int, int, int], str]] = {
    "stations": (
        STATION_COLORS[3],
        "the selected image's station with its antenna axis k (the other two faded grey)",
    ),
    "points": ((70, 80, 100), "object points (Fig. 7 grid on the chosen surface)"),
    "target": ((200, 0, 130), "the chosen target"),
    "spheres": (
        SPHERE_COLORS[0],
        "shaded caps of the range spheres (4b) about points 1, 5, 21, radius = slant range",
    ),
    "candidates": ((0, 0, 0), "their two common points: the station and its mirror image"),
    "slant_range": ((200, 30, 30), "slant range s, station → target"),
    "circle": ((30, 90, 200), "slant-range circle: range sphere ∩ azimuth plane (4c)"),
    "arc": ((140, 60, 190), "the target turned on the circle into the ground plane"),
    "ground_plane": ((205, 180, 120), "ground plane ⟂ axis k, distance h below the station"),
    "h": ((90, 90, 90), "h: station → foot of the axis"),
    "s_e": ((20, 140, 60), "s_e = √(s² − h²): the image point in the ground plane"),
    "reduced": (
        (200, 30, 30),
        "thin red: station → image point, the slant range s turned into the ground plane",
    ),
    "range_ring": ((20, 140, 60), "thin green: the range ring, radius s_e about the foot"),
    "azimuth_plane": ((30, 90, 200), "azimuth plane (4c) of the target (option)"),
    "target_sphere": ((30, 90, 200), "range sphere (4b) of the target (option)"),
    "circles": ((150, 175, 215), "projection circles of all points (option)"),
}

#: The grid corners (points 1, 5 and 21 of Fig. 7) whose range spheres are drawn.
TRIANGLE: tuple[int, int, int] = (0, 4, 20)
#: (rings, vertices per ring) of a shaded cap: its triangles never change.
CAP_MESH: tuple[int, int] = (10, 48)
#: Material of the shaded surfaces: toon shading costs a software renderer (a projector
#: laptop without GPU, headless Chromium) a fraction of the standard PBR material.
MESH_MATERIAL = "toon3"
#: Direction the first view looks along (object frame, Z up): steep from the south, so
#: that the stations (15 km above the grid) do not stand in front of the grid's far rows.
VIEW_DIRECTION = (0.2, 1.0, -1.2)


def radar_geometry(surface: str = "fig7", image: int = 1, rounded: bool = True) -> dict[str, Any]:
    """Arrays of the radar scene (object metres), from :mod:`orientviz.radar.scene`.

    Returns
    -------
    dict
        ``points`` (25, 3); ``xy`` (25, 2) image coordinates in ``image``; ``stations``
        {i: (3,)}; ``axes`` {i: (3,)} unit antenna axes; ``references`` {i: (2, 3)};
        ``circles`` (25, v, 3) projection circles of ``image``; ``triangle`` indices of
        the three sphere centres; ``radii`` (3,) their slant ranges from the image (4b);
        ``candidates`` (2, 3) lower/upper; ``discriminant`` (m²); ``image`` the
        :class:`~orientviz.radar.ppi.RadarImage`.
    """
    P = G.points(surface)
    imgs = G.images()
    xy = G.image_coordinates(surface, image, rounded=rounded)
    im = imgs[image]
    circles = RS.circle_scene(xy, im, n_vertices=97)["polylines"]
    tri = list(TRIANGLE)
    trila = RS.trilateration_scene(P[tri], sphere_ranges(xy[tri], im))
    stations = {i: RS.station_scene(r, f"image {i}", axis_length=1.0) for i, r in imgs.items()}
    return {
        "points": P,
        "xy": xy,
        "image": im,
        "stations": {i: s["station"] for i, s in stations.items()},
        "axes": {i: s["axis"][1] - s["axis"][0] for i, s in stations.items()},
        "references": {i: s["reference"] for i, s in stations.items()},
        "circles": circles,
        "triangle": tri,
        "radii": trila["radii"],
        "candidates": trila["candidates"],
        "discriminant": trila["discriminant"],
    }


def faded_label_place(away: np.ndarray, offset: float) -> tuple[str, tuple[float, float, float]]:
    """Anchor and position (m, from the station) of a faded station's name.

    The name goes beside its station on the side away from the selected one (``away`` =
    this station − the selected, m), as seen along the first view (:data:`VIEW_DIRECTION`),
    ``offset`` m off, so that it does not meet the selected station's name above it even
    where the two stations lie close together on the screen.
    """
    d = np.asarray(VIEW_DIRECTION, float)
    right = np.cross(d, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    side = 1.0 if float(np.dot(away, right)) >= 0.0 else -1.0
    pos = side * offset * right
    return ("center-left" if side > 0 else "center-right"), (pos[0], pos[1], pos[2])


def _swatch_html(col: tuple[int, int, int]) -> str:
    return (
        '<span style="display:inline-block;width:0.9em;height:0.9em;'
        f'background:rgb{col};border-radius:2px;margin-right:0.25em;vertical-align:-0.1em"></span>'
    )


def legend_html() -> str:
    """The legend: colour swatches and a name for every element of the scene.

    Elements drawn in several colours (the stations, the three spheres' caps) get a
    swatch per colour.
    """
    several = {
        "stations": (*STATION_COLORS.values(), FADED),
        "spheres": SPHERE_COLORS,
    }
    rows = "".join(
        '<div style="margin:1px 0">'
        + "".join(_swatch_html(c) for c in several.get(key, (col,)))
        + f"{text}</div>"
        for key, (col, text) in ELEMENTS.items()
    )
    return f'<div style="font-size:0.8em;line-height:1.3">{rows}</div>'


def radar_demo() -> Demo:
    """The ``radar`` demo (see the module docstring)."""
    desc = (
        "Geier's test: 25 grid points 15 km below three airborne radar stations. Choose an "
        "image and a target: the image keeps only the azimuth and s_e = √(s² − h²), the "
        "target lies somewhere on its slant-range circle. Three range spheres meet in the "
        "station (trilateration)."
    )
    return Demo(
        "radar",
        "Radar panorama images (Geier 1973)",
        desc,
        None,
        lambda app: RadarView(app).build(),
    )


class RadarView:
    """Nodes and controls of the radar demo."""

    def __init__(self, app: Any) -> None:
        self.app = app
        self.nodes: dict[str, Any] = {}

    # ------------------------------------------------------------------ building
    def build(self) -> dict:
        app = self.app
        sc, gui = app.server.scene, app.server.gui
        geo = radar_geometry()
        allp = np.vstack([geo["points"], *geo["stations"].values()])
        self.frame = f = g.SceneFrame.around(allp)
        self.size = f.size
        self._build_stations(sc, geo)
        col = {k: v[0] for k, v in ELEMENTS.items()}
        z1, z2 = np.zeros((1, 3), np.float32), np.zeros((1, 2, 3), np.float32)
        pts = dict(precision="float32", point_shape="diamond")
        self.nodes["points"] = sc.add_point_cloud(
            "/radar/points", z1, col["points"], point_size=0.015 * f.size, **pts
        )
        self.nodes["target"] = sc.add_point_cloud(
            "/radar/target", z1, col["target"], point_size=0.035 * f.size, **pts
        )
        mesh = dict(opacity=0.3, side="double", cast_shadow=False, receive_shadow=False,
                    material=MESH_MATERIAL)  # fmt: skip
        v0, f0 = rg.disc_mesh(np.zeros(3), (0.0, 0.0, 1.0), 1.0, 8)
        for j, c in enumerate(SPHERE_COLORS):
            vc, fc = rg.cap_mesh(np.zeros(3), 1.0, (0.0, 0.0, 1.0), 0.1, *CAP_MESH)
            self.nodes[f"sphere_{j}"] = sc.add_mesh_simple(
                f"/radar/sphere_{j}", vc.astype(np.float32), fc, color=c, **mesh
            )
        self.nodes["candidates"] = sc.add_point_cloud(
            "/radar/candidates", np.zeros((2, 3), np.float32), col["candidates"],
            point_size=0.03 * f.size, point_shape="sparkle", precision="float32",
        )  # fmt: skip
        lines = {"slant_range": 4.0, "circle": 2.5, "arc": 3.0, "h": 2.5, "s_e": 4.0,
                 "reduced": 1.5, "range_ring": 1.5}  # fmt: skip
        for key, width in lines.items():  # every line has its own legend entry
            color = col[key]
            self.nodes[key] = sc.add_line_segments(
                f"/radar/geier/{key}", z2, color, thickness=width, thickness_units="screen"
            )
        self.nodes["image_point"] = sc.add_point_cloud(
            "/radar/geier/image_point", z1, col["s_e"], point_size=0.03 * f.size, **pts
        )
        self.nodes["ground_plane"] = sc.add_mesh_simple(
            "/radar/geier/ground_plane", v0, f0, color=col["ground_plane"],
            **{**mesh, "opacity": 0.35},
        )  # fmt: skip
        self.nodes["azimuth_plane"] = sc.add_mesh_simple(
            "/radar/geier/azimuth_plane", v0, f0, color=col["azimuth_plane"],
            **{**mesh, "opacity": 0.18}, visible=False,
        )  # fmt: skip
        self.nodes["target_sphere"] = sc.add_mesh_simple(
            "/radar/geier/target_sphere", v0, f0, color=col["circle"],
            **{**mesh, "opacity": 0.15}, visible=False,
        )  # fmt: skip
        anchors = {"s": "bottom-right", "h": "center-left", "s_e": "top-center",
                   "target": "bottom-right", "image point": "top-left"}  # fmt: skip
        for key, anchor in anchors.items():
            self.nodes[f"label_{key}"] = sc.add_label(
                f"/radar/geier/label_{key.replace(' ', '_')}", key, anchor=anchor
            )
        self.nodes["circles"] = sc.add_line_segments(
            "/radar/circles", z2, (150, 175, 215), thickness=0.8, thickness_units="screen",
            visible=False,
        )  # fmt: skip
        self._build_panel(gui, G)
        self.redraw()
        pos, look = g.framing(f.to_scene(allp), direction=VIEW_DIRECTION, margin=0.95)
        return {"camera": (pos, look, f.size), "radar": self}

    def _build_stations(self, sc: Any, geo: dict) -> None:
        f = self.frame
        self.r_station = r_station = 0.012 * f.size
        for i, X in geo["stations"].items():
            self.nodes[f"station_{i}"] = sc.add_icosphere(
                f"/radar/station_{i}", radius=r_station, color=STATION_COLORS[i],
                position=f.to_scene(X), cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
            axis = np.array([[np.zeros(3), 0.15 * f.size * geo["axes"][i]]])
            self.nodes[f"axis_{i}"] = sc.add_line_segments(
                f"/radar/station_{i}/axis", axis.astype(np.float32), STATION_COLORS[i],
                thickness=3.0, thickness_units="screen",
            )  # fmt: skip
            self.nodes[f"label_{i}"] = sc.add_label(
                f"/radar/station_{i}/label", f"image {i}", anchor="bottom-center",
                position=(0.0, 0.0, 3.0 * r_station),
            )  # fmt: skip

    def _build_panel(self, gui: Any, G: Any) -> None:
        h: dict[str, Any] = {}
        with gui.add_folder("Radar"):
            h["image"] = gui.add_dropdown("image", ("1", "2", "3"), initial_value="3")
            h["target"] = gui.add_dropdown(
                "target point", tuple(str(i) for i in range(1, 26)), initial_value="15"
            )
            h["surface"] = gui.add_dropdown("surface (Fig. 8)", G.COLUMNS, initial_value="fig7")
            h["rounded"] = gui.add_checkbox("image coordinates rounded to 1 m", True)
            h["info"] = gui.add_markdown("")
        with gui.add_folder("Legend"):
            h["legend"] = gui.add_html(legend_html())
        with gui.add_folder("Show"):
            h["construction"] = gui.add_checkbox("construction of the target (Fig. 4)", True)
            h["ground_plane"] = gui.add_checkbox("ground plane", True)
            h["azimuth_plane"] = gui.add_checkbox("azimuth plane (4c)", False)
            h["target_sphere"] = gui.add_checkbox("range sphere of the target (4b)", False)
            h["spheres"] = gui.add_checkbox("trilateration spheres", True)
            h["extent"] = gui.add_slider(
                "sphere cap [°]", 2.0, 180.0, 1.0, 8.0,
                hint="angular radius of the shaded caps about the station; 180 = whole sphere",
            )  # fmt: skip
            h["circles"] = gui.add_checkbox("projection circles of all points", False)
        self.h = h
        guard = self.app.guard
        for key in ("image", "target", "surface", "rounded"):
            h[key].on_update(guard(lambda _e: self.redraw()))
        h["extent"].on_update(guard(lambda _e: self.draw_caps()))
        for key in ("construction", "ground_plane", "azimuth_plane", "target_sphere",
                    "spheres", "circles"):  # fmt: skip
            h[key].on_update(guard(lambda _e: self.apply_visibility()))

    # ------------------------------------------------------------------ drawing
    def apply_visibility(self) -> None:
        """Show or hide the nodes after the checkboxes."""
        on = {k: bool(self.h[k].value) for k in ("construction", "ground_plane", "azimuth_plane",
                                                 "target_sphere", "spheres", "circles")}  # fmt: skip
        geier = ("slant_range", "circle", "arc", "h", "s_e", "reduced", "range_ring",
                 "image_point", "label_s", "label_h", "label_s_e", "label_image point")  # fmt: skip
        for key in geier:
            self.nodes[key].visible = on["construction"]
        self.nodes["ground_plane"].visible = on["construction"] and on["ground_plane"]
        self.nodes["azimuth_plane"].visible = on["construction"] and on["azimuth_plane"]
        self.nodes["target_sphere"].visible = on["construction"] and on["target_sphere"]
        for j in range(3):
            self.nodes[f"sphere_{j}"].visible = on["spheres"]
        self.nodes["candidates"].visible = on["spheres"]
        self.nodes["circles"].visible = on["circles"]

    def _mesh(self, key: str, verts: np.ndarray, faces: np.ndarray) -> None:
        node = self.nodes[key]
        node.vertices = self.frame.to_scene(verts).astype(np.float32)
        if not np.array_equal(node.faces, faces):  # the triangles rarely change: sent once
            node.faces = faces.astype(np.uint32)

    def draw_caps(self) -> None:
        """The shaded caps of the three range spheres about the selected station.

        Only their vertices change (the triangles stay: :data:`CAP_MESH`), so that a move
        of the *sphere cap* slider sends three arrays and nothing else.
        """
        geo, half = self.geo, np.radians(float(self.h["extent"].value))
        station = geo["stations"][int(self.h["image"].value)]
        P = geo["points"][geo["triangle"]]
        for j, (centre, radius) in enumerate(zip(P, geo["radii"], strict=True)):
            verts, _ = rg.cap_mesh(centre, radius, station - centre, half, *CAP_MESH)
            self.nodes[f"sphere_{j}"].vertices = self.frame.to_scene(verts).astype(np.float32)

    def redraw(self) -> None:
        """Recompute everything for the chosen image, target and surface."""
        image, surface = int(self.h["image"].value), str(self.h["surface"].value)
        target = int(self.h["target"].value) - 1
        geo = radar_geometry(surface, image, bool(self.h["rounded"].value))
        f = self.frame
        self.geo = geo
        for i in geo["stations"]:
            sel = i == image
            self.nodes[f"station_{i}"].color = STATION_COLORS[i] if sel else FADED
            self.nodes[f"station_{i}"].opacity = None if sel else 0.35
            self.nodes[f"axis_{i}"].visible = sel
            label, up = self.nodes[f"label_{i}"], 3.0 * self.r_station
            label.anchor, label.position = ("bottom-center", (0.0, 0.0, up)) if sel else (
                faded_label_place(geo["stations"][i] - geo["stations"][image], up)
            )  # fmt: skip
            label.font_screen_scale = 1.0 if sel else 0.85
        P = geo["points"]
        self.nodes["points"].points = f.to_scene(P).astype(np.float32)
        self.nodes["target"].points = f.to_scene(P[target : target + 1]).astype(np.float32)
        C = geo["circles"]
        seg = np.stack([C[:, :-1], C[:, 1:]], axis=2).reshape(-1, 2, 3)
        self.nodes["circles"].points = f.to_scene(seg).astype(np.float32)
        station = geo["stations"][image]
        self.draw_caps()
        self.nodes["candidates"].points = f.to_scene(geo["candidates"]).astype(np.float32)
        self.construction = con = rg.geier_construction(P[target], geo["xy"][target], geo["image"])
        self._draw_construction(con, P[target], geo)
        self.apply_visibility()
        err = np.linalg.norm(geo["candidates"] - station, axis=1)
        self.h["info"].content = (
            f"image {image}, surface {surface}, target {target + 1}: slant range "
            f"s = {con['s']:,.1f} m, h = {con['h']:,.2f} m, s_e = {con['s_e']:,.1f} m "
            f"(image distance m·s_e = {geo['image'].m * con['s_e']:,.1f} m); the target lies "
            f"{np.degrees(con['elevation']):+.1f}° from the plane ⟂ k on its circle.  \n"
            f"Trilateration from points {', '.join(str(i + 1) for i in geo['triangle'])}: "
            f"the upper candidate lies {err[1]:.1f} m from the station, the lower one "
            f"{err[0] / 1000:,.1f} km (its mirror image)."
        )

    def _draw_construction(self, con: dict, target: np.ndarray, geo: dict) -> None:
        f = self.frame
        X0, foot, ip = con["station"], con["foot"], con["image_point"]

        def put(key: str, seg: np.ndarray) -> None:
            self.nodes[key].points = f.to_scene(seg).astype(np.float32)

        put("slant_range", np.array([[X0, target]]))
        put("reduced", np.array([[X0, ip]]))
        put("h", np.array([[X0, foot]]))
        put("s_e", np.array([[foot, ip]]))
        put("circle", rg.polyline_to_segments(con["circle"]))
        put("arc", rg.polyline_to_segments(con["arc"]))
        put("range_ring", rg.polyline_to_segments(con["range_ring"]))
        self.nodes["image_point"].points = f.to_scene(ip[None]).astype(np.float32)
        across = geo["points"] - foot
        across -= np.outer(across @ con["axis"], con["axis"])  # distances ⟂ k from the foot
        reach = np.linalg.norm(across, axis=1)
        self._mesh("ground_plane", *rg.disc_mesh(foot, con["axis"], 1.1 * reach.max(), 96))
        self._mesh("azimuth_plane", *rg.disc_mesh(X0, con["normal"], 1.05 * con["s"], 96))
        self._mesh("target_sphere", *rg.cap_mesh(X0, con["s"], -con["axis"], np.pi, 24, 64))
        labels = {"s": 0.35 * X0 + 0.65 * target, "h": 0.5 * (X0 + foot), "s_e": 0.5 * (foot + ip),
                  "target": target, "image point": ip}  # fmt: skip
        for key, X in labels.items():
            self.nodes[f"label_{key}"].position = f.to_scene(X)
