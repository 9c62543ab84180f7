"""The built-in demos build, and their special geometry (y-parallax, radar) is right."""

import numpy as np
import pytest

from orientviz.viewer.app import ViewerApp
from orientviz.viewer.demos import DEMOS, load_demo
from orientviz.viewer.pair_scene import pair_geometry, parallax_arrows
from orientviz.viewer.radar_scene import radar_geometry

pytest.importorskip("viser")


def test_parallax_arrows_run_from_left_to_right_ray():
    pts = np.array([[0.0, 10.0, -300.0], [50.0, -20.0, -310.0]])
    p = np.array([0.2, -0.1])  # p_y = Y_left − Y_right, mm
    seg = parallax_arrows(pts, p, 10.0)
    assert seg.shape == (6, 2, 3)
    shafts = seg[0::3]
    np.testing.assert_allclose(shafts[:, 0, 1], pts[:, 1] + 5.0 * p)  # left ray, × 10
    np.testing.assert_allclose(shafts[:, 1, 1], pts[:, 1] - 5.0 * p)  # right ray
    np.testing.assert_allclose(shafts[:, :, [0, 2]], np.repeat(pts[:, None, [0, 2]], 2, 1))


def test_pair_geometry_has_no_parallax_at_the_true_orientation():
    from orientviz.orientation.plotter import AnalogPlotter, PlotterConfig, true_pair

    pair = true_pair(PlotterConfig(sigma_by=0.0, sigma_z=0.0), rng=np.random.default_rng(1))
    pl = AnalogPlotter(pair)
    wrong = pair_geometry(pl)
    assert np.sqrt(np.mean(wrong["parallax"] ** 2)) > 1e-2  # start: 100-150 c off
    pl.settings[:] = pair.elements
    right = pair_geometry(pl)
    np.testing.assert_allclose(right["parallax"], 0.0, atol=1e-9)
    np.testing.assert_allclose(right["centres"][1], pl.state.base)


def test_radar_candidates_contain_the_station():
    geo = radar_geometry("fig7", 3, rounded=False)
    station = geo["stations"][3]
    d = np.linalg.norm(geo["candidates"] - station, axis=1)
    assert d.min() < 1e-3  # error-free image coordinates: exact up to rounding of floats
    # every projection circle passes through its object point and lies on its range sphere
    r = np.linalg.norm(geo["circles"] - station, axis=2)
    np.testing.assert_allclose(r, np.broadcast_to(r[:, :1], r.shape), rtol=1e-12)
    gap = np.min(np.linalg.norm(geo["circles"] - geo["points"][:, None], axis=2), axis=1)
    # on the circle: the nearest of 96 evenly spaced vertices is within half a chord
    assert np.all(gap <= r[:, 0] * np.sin(np.pi / 96) + 1e-6)


@pytest.mark.parametrize("name", sorted(DEMOS))
def test_demo_builds_in_the_viewer(name):
    app = ViewerApp(load_demo(name), port=0, verbose=False)
    try:
        assert app.messages == []
        assert app.server.scene.get_handle_by_name(f"/{'block' if name == 'block' else name}")
    finally:
        app.stop()


def test_pair_panel_passes_scrub_and_reset():
    app = ViewerApp(load_demo("pair"), port=0, verbose=False)
    try:
        pv = app.extra["pair"]
        pl = pv.plotter
        rms0 = pv.rms
        pv.h["pass"].value = None  # click "one pass"
        assert len(pl.history) == 1 and pv.rms < rms0
        # the dial sliders follow the plotter (ω in c)
        assert pv.h["omega [c]"].value == pytest.approx(round(pl.settings[2] * 20000 / np.pi, 2))
        pv.h["orient"].value = None  # to convergence
        assert pv.rms < 1e-3  # below 1 µm machine: no reading noise in the demo
        n = len(pv.snapshots)
        assert pv.h["scrub"].max == n - 1
        pv.h["scrub"].value = 0  # back to the start dials, history kept
        np.testing.assert_allclose(pl.settings, pv.start)
        assert len(pv.snapshots) == n
        pv.h["reset"].value = None
        assert pl.history == [] and len(pv.snapshots) == 1
        # a dial moved by hand changes the parallaxes at once
        before = np.asarray(pv.nodes["parallax"].points).copy()
        pv.h["kappa [c]"].value = 50.0
        assert pl.settings[4] == pytest.approx(50.0 * np.pi / 20000)
        assert np.any(np.asarray(pv.nodes["parallax"].points) != before)
        assert app.messages == []
    finally:
        app.stop()


def test_pair_selected_point_rays_gap_plane_and_normalised_images_follow_the_dials():
    app = ViewerApp(load_demo("pair"), port=0, verbose=False)
    try:
        pv = app.extra["pair"]
        assert pv.selected() == 4 and pv.nodes["gap"].visible
        gap0 = pv.point["gap_length"]
        seg = np.asarray(pv.nodes["gap"].points, dtype=float)[0] + pv.frame.origin
        assert np.linalg.norm(seg[1] - seg[0]) == pytest.approx(gap0, rel=1e-4)
        assert "shortest segment" in pv.h["point_info"].content
        pv.h["point"].value = "3"
        assert pv.selected() == 2 and pv.point["gap_length"] != gap0
        plane = np.asarray(pv.nodes["epipolar_plane"].vertices, dtype=float) + pv.frame.origin
        np.testing.assert_allclose(plane, pv.point["plane"], atol=1e-3)
        pv.h["plane"].value = False
        assert not pv.nodes["epipolar_plane"].visible
        # the normalised images appear on request and follow the dials
        assert not pv.h["picture"].visible
        pv.h["normalised"].value = True
        assert pv.h["picture"].visible and pv.h["picture_folder"].visible
        first = pv.picture.copy()
        pv.h["orient"].value = None  # to convergence: rows line up, the gap closes
        assert pv.point["gap_length"] < 1e-3  # from ~10 mm to below 1 µm (machine)
        np.testing.assert_allclose(pv.norm["p_y"], 0.0, atol=1e-3)
        assert pv.picture.shape == first.shape and np.any(pv.picture != first)
        pv.h["point"].value = "none"
        assert not pv.nodes["gap"].visible and pv.point is None
        assert app.messages == []
    finally:
        app.stop()


def test_radar_panel_follows_image_target_and_surface():
    app = ViewerApp(load_demo("radar"), port=0, verbose=False)
    try:
        rv = app.extra["radar"]
        rv.h["image"].value = "2"
        rv.h["surface"].value = "sphere150_convex"
        geo = radar_geometry("sphere150_convex", 2)
        pts = np.asarray(rv.nodes["points"].points, dtype=float) + rv.frame.origin
        np.testing.assert_allclose(pts, geo["points"], atol=0.02)  # float32 at ~50 km
        assert "image 2, surface sphere150_convex" in rv.h["info"].content
        # only the selected image is drawn in full, the others are faded
        assert rv.nodes["station_2"].opacity is None and rv.nodes["axis_2"].visible
        assert rv.nodes["station_1"].opacity < 1 and not rv.nodes["axis_1"].visible
        # the construction follows the target: the slant range runs station → target
        rv.h["target"].value = "7"
        seg = np.asarray(rv.nodes["slant_range"].points, dtype=float)[0] + rv.frame.origin
        np.testing.assert_allclose(seg[0], geo["stations"][2], atol=0.02)
        np.testing.assert_allclose(seg[1], geo["points"][6], atol=0.02)
        from orientviz.radar.ppi import sphere_radius

        # the slant range of the (rounded) image point: 4b
        assert rv.construction["s"] == pytest.approx(sphere_radius(geo["xy"][6:7], geo["image"])[0])
        assert "target 7" in rv.h["info"].content
        # the shaded caps lie on the trilateration spheres of the selected image
        cap = np.asarray(rv.nodes["sphere_0"].vertices, dtype=float) + rv.frame.origin
        r = np.linalg.norm(cap - geo["points"][geo["triangle"][0]], axis=1)
        np.testing.assert_allclose(r, geo["radii"][0], rtol=1e-5)
        rv.h["spheres"].value = False
        assert not rv.nodes["sphere_0"].visible and not rv.nodes["candidates"].visible
        rv.h["construction"].value = False
        assert not rv.nodes["circle"].visible and not rv.nodes["ground_plane"].visible
        assert "slant-range circle" in rv.h["legend"].content
        assert app.messages == []
    finally:
        app.stop()


def test_radar_legend_names_every_line_it_draws():
    """Issue 31: the radar legend missed the green range ring and the thin red line."""
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.radar_scene import ELEMENTS, legend_html

    app = ViewerApp("radar", port=0, verbose=False)
    try:
        nodes = app.extra["radar"].nodes
        drawn = {k.split("/")[-1] for k in nodes if hasattr(nodes[k], "points")}
        lines = {"slant_range", "circle", "arc", "h", "s_e", "reduced", "range_ring"}
        assert lines <= drawn
        html = legend_html()
        for key in lines:
            assert key in ELEMENTS and ELEMENTS[key][1].split(":")[0] in html
        assert "range ring" in html and "thin red" in html
    finally:
        app.stop()


def test_pair_scene_has_a_legend_with_the_scale_bar():
    """Issue 31 pt 8: the pair scene had the scale bar's text only."""
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.legend import swatch
    from orientviz.viewer.pair_scene import GAP, RIGHT_PROJECTOR

    app = ViewerApp("pair", port=0, verbose=False)
    try:
        pv = app.extra["pair"]
        text = pv.h["legend"].content
        assert pv.scale_bar_text in text and "y-parallax arrows" in text
        assert swatch(RIGHT_PROJECTOR, "△") in text and swatch(GAP, "▬") in text
        pv.k *= 10.0
        pv._scale_bar()
        assert pv.scale_bar_text in pv.h["legend"].content
    finally:
        app.stop()


def _screen(points, position, look_at, fov, aspect=1280 / 800):
    """Normalised window coordinates (x, y in [-1, 1], x right, y up) of scene points seen
    by a pinhole camera at ``position`` looking at ``look_at`` with Z up."""
    f = np.asarray(look_at, float) - np.asarray(position, float)
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    d = np.asarray(points, float) - np.asarray(position, float)
    depth = d @ f
    assert np.all(depth > 0), "a point behind the camera"
    t = np.tan(fov / 2)
    return np.column_stack([d @ right / (depth * t * aspect), d @ up / (depth * t)])


def _left_of_the_panel(xy):
    """Inside the window and left of the GUI panel (the right 28 % at 1280 × 800)."""
    from orientviz.viewer.geometry import VISIBLE_WIDTH

    return (xy[:, 0] > -1) & (xy[:, 0] < -1 + 2 * VISIBLE_WIDTH) & (np.abs(xy[:, 1]) < 1)


@pytest.mark.parametrize("name", ["pair", "radar"])
def test_first_view_shows_every_point_left_of_the_panel(name):
    """Issue 31 pt 8: radar target 25 lay behind the panel, the pair ran under it and the
    pair's scale-bar label sat half under it (1280 × 800)."""
    from orientviz.viewer.geometry import VIEW_FOV, VISIBLE_WIDTH

    app = ViewerApp(load_demo(name), port=0, verbose=False)
    try:
        cam = app.server.initial_camera
        view = app.extra[name]
        nodes = ["points", "target"] if name == "radar" else ["terrain", "scheme", "scale_bar"]
        pts = [np.asarray(view.nodes[k].points, float).reshape(-1, 3) for k in nodes]
        if name == "radar":
            pts += [np.asarray(view.nodes[f"station_{i}"].position, float)[None] for i in (1, 2, 3)]
        else:
            pts += [np.asarray(view.nodes[k].position, float)[None] for k in ("left", "right")]
            label = view.nodes["scale_label"]
            assert label.anchor == "top-center"
            # its text (~220 px wide at 1280 px: ±0.17 of the half-width) fits on the screen
            # left of the panel in the viewer's window and in the book's 1280 × 960 pictures
            for aspect in (1280 / 800, 1280 / 960):
                x = _screen(np.asarray(label.position, float)[None], cam.position,
                            cam.look_at, VIEW_FOV, aspect)[0, 0]  # fmt: skip
                assert -1 + 0.2 < x < -1 + 2 * VISIBLE_WIDTH - 0.2, (aspect, x)
        xy = _screen(np.vstack(pts), cam.position, cam.look_at, VIEW_FOV)
        assert _left_of_the_panel(xy).all(), xy[~_left_of_the_panel(xy)]
        if name == "radar":  # all 25 targets, 25 among them
            assert np.asarray(view.nodes["points"].points).shape == (25, 3)
    finally:
        app.stop()


def test_radar_sphere_cap_slider_redraws_the_caps_alone(monkeypatch):
    """The cap slider took ~12 s in software rendering: it re-sent every node. It now moves
    the three caps' vertices only (their triangles stay)."""
    app = ViewerApp(load_demo("radar"), port=0, verbose=False)
    try:
        rv = app.extra["radar"]
        calls = []
        monkeypatch.setattr(rv, "redraw", lambda: calls.append(1))
        faces = np.asarray(rv.nodes["sphere_1"].faces).copy()
        before = np.asarray(rv.nodes["sphere_1"].vertices, float).copy()
        circle = np.asarray(rv.nodes["circle"].points).copy()
        rv.h["extent"].value = 30.0
        after = np.asarray(rv.nodes["sphere_1"].vertices, float)
        assert calls == [] and not np.allclose(after, before)
        np.testing.assert_array_equal(rv.nodes["sphere_1"].faces, faces)
        np.testing.assert_array_equal(rv.nodes["circle"].points, circle)
        # the cap still lies on its range sphere, now 30° wide about the station
        geo = rv.geo
        c = geo["points"][geo["triangle"][1]]
        r = np.linalg.norm(after + rv.frame.origin - c, axis=1)
        np.testing.assert_allclose(r, geo["radii"][1], rtol=1e-5)
        w = geo["stations"][3] - c
        cos = (after + rv.frame.origin - c) @ w / (r * np.linalg.norm(w))
        assert np.degrees(np.arccos(cos.min())) == pytest.approx(30.0, abs=0.01)
        assert app.messages == []
    finally:
        app.stop()


def _label_box(xy, anchor: str, scale: float, size=(1280, 800)):
    """Pixel box (x0, y0, x1, y1; y down) of a station label ("image N", ~46 × 18 px at
    scale 1 as viser draws it) whose ``anchor`` point lies at window coordinates ``xy``."""
    w, h = 46.0 * scale, 18.0 * scale
    px, py = (xy[0] + 1) / 2 * size[0], (1 - xy[1]) / 2 * size[1]
    vert, horiz = anchor.split("-")
    x0 = {"left": px, "center": px - w / 2, "right": px - w}[horiz]
    y0 = {"top": py, "center": py - h / 2, "bottom": py - h}[vert]
    return x0, y0, x0 + w, y0 + h


@pytest.mark.parametrize("image", ["1", "2", "3"])
def test_radar_station_names_do_not_meet_in_the_first_view(image):
    """Lesson 14's snapshot (image 2 selected): "image 3" touched "image 2". The faded
    stations' names now sit beside their stations, away from the selected one."""
    from orientviz.viewer.geometry import VIEW_FOV

    app = ViewerApp(load_demo("radar"), port=0, verbose=False)
    try:
        cam, rv = app.server.initial_camera, app.extra["radar"]
        rv.h["image"].value = image
        for size in ((1280, 800), (1280, 860)):  # the viewer, the lesson's snapshot
            boxes = []
            for i in (1, 2, 3):
                label = rv.nodes[f"label_{i}"]
                at = np.asarray(rv.nodes[f"station_{i}"].position, float)
                at = at + np.asarray(label.position, float)
                xy = _screen(at[None], cam.position, cam.look_at, VIEW_FOV, size[0] / size[1])
                boxes.append(_label_box(xy[0], label.anchor, label.font_screen_scale, size))
            for a in range(3):
                for b in range(a + 1, 3):
                    A, B = boxes[a], boxes[b]
                    apart = A[2] < B[0] or B[2] < A[0] or A[3] < B[1] or B[3] < A[1]
                    assert apart, (image, size, a + 1, b + 1, A, B)
    finally:
        app.stop()
