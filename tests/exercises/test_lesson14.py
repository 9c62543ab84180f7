"""Lesson 14's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson14 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson14


def test_checks():
    assert_module_checks(lesson14, answers)


def test_ppi_image_without_h_is_named():
    import numpy as np

    from orientviz.exercises._common import rejection

    def slant(P, X0, R, h, m, x0, y0):  # the slant range plotted: h forgotten
        abc = (P - X0) @ R
        s = np.linalg.norm(P - X0, axis=1)
        horiz = np.hypot(abc[:, 0], abc[:, 1])
        return np.column_stack([x0 + m * s * abc[:, 0] / horiz, y0 + m * s * abc[:, 1] / horiz])

    exc = rejection(lesson14.check_ppi_image, slant)
    assert exc is not None and "h is missing" in str(exc)


def test_steep_pair_misreadings_are_named():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson14,
        answers,
        {
            ("check_steep_pair", "plan"): "geometric rule",
            ("check_steep_pair", "far from the three"): "which rays change most",
            ("check_steep_pair", "spread"): "farthest apart",
            ("check_steep_pair", "the stand-in"): "calls the library's best_pair_library",
            ("check_steep_pair", "trial"): "geometric rule",
        },
    )


def test_radius_change_mistakes_are_named():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson14,
        answers,
        {
            ("check_radius_change", "s_e"): "the change of s_e",
            ("check_radius_change", "sign"): "the sign",
            ("check_radius_change", "relative"): "relative change",
            ("check_radius_change", "s/s_e"): "chain rule",
            ("check_radius_change", "exact"): "not linear in dm",
        },
    )


def test_radius_change_refuses_the_library_sphere_radius():
    from orientviz.exercises._common import rejection
    from orientviz.radar import geier1973 as G
    from orientviz.radar.ppi import sphere_radius

    def numeric(xy, x0, y0, m, h, dm):  # the library's sphere radius differenced
        image = G.images()[2].with_(x0=x0, y0=y0, m=m, h=h)
        return sphere_radius(xy, image.with_(m=m + dm)) - sphere_radius(xy, image)

    exc = rejection(lesson14.check_radius_change, numeric)
    assert exc is not None and "calls the library's sphere_radius" in str(exc)
