"""Lesson 05 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

import numpy as np
from answers import lesson05 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson05


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson05, answers)


def test_oracle_agrees_with_the_library():
    """The checker's rigorous-parallax derivatives and the library's design matrix are independent; they agree."""
    from orientviz.orientation.relative import design_dependent

    P = lesson05._points(np.random.default_rng(3), 9, 92.0)
    assert np.allclose(
        lesson05._numeric_design(P, 92.0),
        design_dependent(P[:, 0], P[:, 1], P[:, 2], 92.0),
        rtol=1e-5,
        atol=1e-6,
    )


def test_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson05,
        answers,
        {
            ("check_middle_users", "design"): "influence matrix G",
            ("check_middle_users", "first three"): "points 7, 8, 9",
            ("check_kovarik_iteration", "one_step"): "one linear solution is not the iteration",
            ("check_kovarik_iteration", "pok"): "φ-ω-κ sequence of the plotter",
            ("check_kovarik_iteration", "sign"): "runs away",
            ("check_kovarik_iteration", "R_transposed"): "runs away",
            ("check_design", "y'' - y'"): "opposite sign",
            ("check_relative_from_exterior", "R_transposed"): "R transposed",
            ("check_relative_from_exterior", "object_frame"): "object frame",
            ("check_relative_from_exterior", "base_not_rotated"): "rotate it into the left image",
            ("check_relative_from_exterior", "not_scaled"): "not scaled",
            ("check_relative_from_exterior", "degrees"): "degrees",
            ("check_design", "Kovarik signs"): "Kovarik",
            ("check_design", "own central differences"): "finite difference",
            ("check_design", "1 - Y^2/Z^2"): "sign inside the bracket",
            (
                "check_design",
                "the stand-in (the library's)",
            ): "calls the library's design_dependent",
            ("check_parallax", "the stand-in (the library's)"): "calls the library's y_parallax",
            ("check_six_point_residuals", "p - Ad"): "v = A d̂ − p",
            ("check_six_point_residuals", "hat diagonal"): "1 minus that",
            ("check_six_point_residuals", "mean share"): "the mean share",
            ("check_six_point_residuals", "no wTw"): "dividing by wᵀw",
            ("check_six_point_residuals", "one array"): "two arrays",
            ("check_parallax", "image difference"): "scale it to the model",
            ("check_condition", "flat form with relief"): "flat-terrain form",
            ("check_scheme_sigma", "inverse of the diagonal"): "diagonal of (AᵀA)⁻¹",
            ("check_scheme_sigma", "variances"): "square root is missing",
            ("check_scheme_sigma", "spread"): "not the distance between",
        },
    )


def test_angle_reader_inverts_the_rotation():
    """The checker's own ω-φ-κ reader (an oracle of check_relative_from_exterior) inverts R."""
    from orientviz.exercises.lesson02 import _rodrigues_opk

    a = np.array([0.03, -0.02, 1.6])
    assert np.allclose(lesson05._opk(_rodrigues_opk(*a, unit=1.0)), a, atol=1e-12)


def test_design_from_differences_of_the_library_is_refused():
    """Central differences of the library's rigorous y-parallax skip the derivation: refused."""
    import numpy as np

    from orientviz.exercises._common import rejection
    from orientviz.orientation import relative as rel

    def design_by_differences(X, Y, Z, b):
        state = rel.PairState.from_elements(np.zeros(5), b)
        xy1 = np.column_stack([X, Y]) * (-152.7 / Z)[:, None]
        out = np.zeros((len(X), 5))
        for k in range(5):
            e = np.zeros(5)
            e[k] = 1e-6
            out[:, k] = (
                rel.y_parallax(xy1, xy1 - [90.0, 0.0], 152.7, rel.PairState.from_elements(e, b))[0]
                - rel.y_parallax(xy1, xy1 - [90.0, 0.0], 152.7, state)[0]
            ) / 1e-6
        return out

    exc = rejection(lesson05.check_design, design_by_differences)
    assert exc is not None and "calls the library's y_parallax" in str(exc)
