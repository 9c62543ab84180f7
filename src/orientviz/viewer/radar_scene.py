"""The radar demo: Geier's (1973) panorama images in 3D.

Data from :mod:`orientviz.radar.geier1973` (Fig. 7: 25 grid points, three images;
Fig. 8 surfaces); geometry from :mod:`orientviz.radar.ppi` and
:mod:`orientviz.radar.trilateration`. Object frame in m, Z up; the stations fly at
Z ≈ 0 and the terrain lies near Z = −15 500 m. Rotations φ-ω-κ (R = R_φ R_ω R_κ), κ the
reference direction about the antenna axis k.

Scene tree::

    /radar/points                the 25 object points of the chosen surface
    /radar/station_<i>           the three stations (small spheres) with their axis
    /radar/circles               projection circles of the selected image: the azimuth
                                 plane (4c) cuts the range sphere (4b) in a great circle
                                 through the object point
    /radar/spheres               range spheres about the three points of the largest
                                 triangle, radius = slant range from the image (4b)
    /radar/candidates            the two points common to the three spheres (the true
                                 station and its mirror image in the points' plane)

A scene-size note: the spheres have radii of 15-60 km; everything is drawn to scale.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import geometry as g
from .block_geometry import COLORS

STATION_COLORS = {1: (40, 70, 160), 2: (250, 130, 0), 3: (20, 150, 60)}


#: The three grid corners (points 1, 5 and 21 of Fig. 7) whose range spheres are drawn:
#: a large, well-shaped triangle for the trilateration.
TRIANGLE: tuple[int, int, int] = (0, 4, 20)


def radar_geometry(surface: str = "fig7", image: int = 1, rounded: bool = True) -> dict[str, Any]:
    """Arrays of the radar scene (object metres), from :mod:`orientviz.radar.scene`.

    Returns
    -------
    dict
        ``points`` (25, 3); ``stations`` {i: (3,)}; ``axes`` {i: (3,)} unit antenna axes;
        ``references`` {i: (2, 3)} reference-direction segments; ``circles`` (25, v, 3)
        projection circles of ``image``; ``triangle`` indices of the three sphere
        centres; ``radii`` (3,) their slant ranges from the image (4b); ``candidates``
        (2, 3) lower/upper; ``discriminant`` (m²).
    """
    from ..radar import geier1973 as G
    from ..radar import scene as RS
    from ..radar.trilateration import sphere_ranges

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
        "stations": {i: s["station"] for i, s in stations.items()},
        "axes": {i: s["axis"][1] - s["axis"][0] for i, s in stations.items()},
        "references": {i: s["reference"] for i, s in stations.items()},
        "circles": circles,
        "triangle": tri,
        "radii": trila["radii"],
        "candidates": trila["candidates"],
        "discriminant": trila["discriminant"],
    }


def radar_demo() -> Any:
    """The ``radar`` demo (see the module docstring)."""
    from .demos import Demo

    desc = (
        "Geier's test: 25 grid points 15 km below three airborne radar stations. "
        "Choose an image and a surface of Fig. 8; the projection circles, the range "
        "spheres about three points and their two common points (trilateration) follow."
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

    def build(self) -> dict:
        from ..radar import geier1973 as G

        app = self.app
        sc, gui = app.server.scene, app.server.gui
        geo = radar_geometry()
        allp = np.vstack([geo["points"], *geo["stations"].values()])
        self.frame = f = g.SceneFrame.around(allp)
        self.size = f.size
        r_station = 0.012 * f.size
        for i, X in geo["stations"].items():
            self.nodes[f"station_{i}"] = sc.add_icosphere(
                f"/radar/station_{i}", radius=r_station, color=STATION_COLORS[i],
                position=f.to_scene(X), cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
            axis = np.array([[X, X + 0.15 * f.size * geo["axes"][i]]])
            self.nodes[f"axis_{i}"] = sc.add_line_segments(
                f"/radar/station_{i}/axis", f.to_scene(axis) - f.to_scene(X), STATION_COLORS[i],
                thickness=3.0, thickness_units="screen",
            )  # fmt: skip
            self.nodes[f"label_{i}"] = sc.add_label(
                f"/radar/station_{i}/label", f"image {i}", position=(0.0, 0.0, 2.0 * r_station)
            )
        z2 = np.zeros((1, 2, 3), np.float32)
        self.nodes["points"] = sc.add_point_cloud(
            "/radar/points", np.zeros((1, 3), np.float32), COLORS["control"],
            point_size=0.02 * f.size, point_shape="diamond", precision="float32",
        )  # fmt: skip
        self.nodes["circles"] = sc.add_line_segments(
            "/radar/circles", z2, (150, 175, 215), thickness=0.8, thickness_units="screen"
        )
        self.nodes["spheres"] = sc.add_line_segments(
            "/radar/spheres", z2, COLORS["ellipsoid"], thickness=1.0, thickness_units="screen"
        )
        self.nodes["candidates"] = sc.add_point_cloud(
            "/radar/candidates", np.zeros((2, 3), np.float32), (0, 0, 0),
            point_size=0.04 * f.size, point_shape="sparkle", precision="float32",
        )  # fmt: skip
        h: dict[str, Any] = {}
        with gui.add_folder("Radar"):
            h["image"] = gui.add_dropdown("image", ("1", "2", "3"), initial_value="3")
            h["surface"] = gui.add_dropdown("surface (Fig. 8)", G.COLUMNS, initial_value="fig7")
            h["rounded"] = gui.add_checkbox("image coordinates rounded to 1 m", True)
            h["circles"] = gui.add_checkbox("projection circles", True)
            h["spheres"] = gui.add_checkbox("range spheres", True)
            h["info"] = gui.add_markdown("")
        self.h = h
        for key in ("image", "surface", "rounded"):
            h[key].on_update(app.guard(lambda _e: self.redraw()))
        h["circles"].on_update(app.guard(lambda _e: self._show("circles")))
        h["spheres"].on_update(app.guard(lambda _e: self._show("spheres")))
        self.redraw()
        centre = f.to_scene(np.array([15000.0, 0.0, -12000.0]))
        pos = centre + np.array([-0.55, -1.5, 0.75]) * 1.6 * f.size
        return {"camera": (pos, centre, f.size), "radar": self}

    def _show(self, key: str) -> None:
        vis = bool(self.h[key].value)
        self.nodes[key].visible = vis
        if key == "spheres":
            self.nodes["candidates"].visible = vis

    def redraw(self) -> None:
        """Recompute the circles, spheres and candidates for the chosen image and surface."""
        image, surface = int(self.h["image"].value), str(self.h["surface"].value)
        geo = radar_geometry(surface, image, bool(self.h["rounded"].value))
        f = self.frame
        self.geo = geo
        self.nodes["points"].points = f.to_scene(geo["points"]).astype(np.float32)
        C = geo["circles"]
        seg = np.stack([C[:, :-1], C[:, 1:]], axis=2).reshape(-1, 2, 3)
        self.nodes["circles"].points = f.to_scene(seg).astype(np.float32)
        centres = geo["points"][geo["triangle"]]
        sph = g.sphere_wire_segments(centres, geo["radii"], n_lat=3, n_lon=4, n=72)
        self.nodes["spheres"].points = f.to_scene(sph).astype(np.float32)
        self.nodes["candidates"].points = f.to_scene(geo["candidates"]).astype(np.float32)
        self.nodes["candidates"].colors = np.array([[120, 120, 120], [0, 0, 0]], np.uint8)
        true = geo["stations"][image]
        err = np.linalg.norm(geo["candidates"] - true, axis=1)
        self.h["info"].content = (
            f"image {image}, surface {surface}: trilateration from points "
            f"{', '.join(str(i + 1) for i in geo['triangle'])} — candidates "
            f"Z = {geo['candidates'][0, 2]:.0f} m and {geo['candidates'][1, 2]:.0f} m; "
            f"the upper one lies {err[1]:.1f} m from the true station"
        )
