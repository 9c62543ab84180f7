"""Lesson 09 (the datum): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson09 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson09


def test_lesson09_checks():
    assert_module_checks(lesson09, answers)


def test_lesson09_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson09,
        answers,
        {
            ("check_inner_solve", "ridge"): "regularises",
            ("check_inner_solve", "whole_inverse"): "whole bordered inverse",
            ("check_inner_solve", "sign"): "sign of dx",
            (
                "check_similarity_columns",
                "distance defect (3 columns)",
            ): "a change of scale is free",
            ("check_similarity_columns", "shear for scale"): "is a shear",
            ("check_similarity_columns", "rotation sign"): "changes the angles",
            ("check_similarity_columns", "scale twice"): "not independent",
            ("check_best_datum", "farthest apart"): "farthest apart",
            ("check_best_datum", "central"): "lie in the middle",
            ("check_estimable", "measured"): "estimable in both",
            ("check_estimable", "distance everywhere"): "the scale is free",
            ("check_estimable", "azimuth"): "turns every azimuth",
            ("check_null_space", "relative tolerance"): "too large",
            ("check_null_space", "largest jump"): "largest jump",
            ("check_null_space", "absolute tolerance"): "round-off",
            ("check_null_space", "rows"): "columns are the basis vectors",
            ("check_null_space", "largest"): "LARGEST",
        },
    )


def test_largest_ellipse_check_finds_the_pair_and_names_misreadings(capsys):
    import itertools

    import numpy as np
    import pytest

    from orientviz.adjust.datum import datum_solve, helmert_basis, s_transformation
    from orientviz.adjust.ellipse import error_ellipse
    from orientviz.adjust.network2d import all_pairs_within, distance_equations
    from orientviz.exercises._common import CheckFailed, NotWrittenError

    truth = np.array([[0, 0], [420, 40], [830, -30], [50, 430], [460, 390], [870, 450],
                      [280, 780], [690, 820]], dtype=float)  # fmt: skip
    f, J = distance_equations(all_pairs_within(truth, 750.0))(truth.reshape(-1))
    N = J.T @ J / 0.003**2
    G = helmert_basis(truth)
    _, Q = datum_solve(N, np.zeros(len(N)), G)
    sigma0 = 0.9
    # an independent look: the library's S-transformation and ellipse for every pair
    a = {
        pr: error_ellipse((S @ Q @ S.T)[8:10, 8:10][None]).a[0] * sigma0 * 1000
        for pr in itertools.combinations(range(8), 2)
        for S in [s_transformation(G, datum_points=list(pr))]
    }
    largest, smallest = max(a.values()), min(a.values())
    assert largest > 2 * smallest  # the datum matters for point 5
    lesson09.check_largest_ellipse(lambda: round(largest, 2), G, Q, sigma0, point=5)
    assert capsys.readouterr().out.startswith("✓")
    with pytest.raises(CheckFailed, match="SMALLEST"):
        lesson09.check_largest_ellipse(round(smallest, 2), G, Q, sigma0, point=5)
    with pytest.raises(CheckFailed, match="without σ̂0"):
        lesson09.check_largest_ellipse(round(largest / sigma0, 2), G, Q, sigma0, point=5)
    with pytest.raises(CheckFailed, match="in m, not mm"):
        lesson09.check_largest_ellipse(largest / 1000, G, Q, sigma0, point=5)
    with pytest.raises(NotWrittenError):
        lesson09.check_largest_ellipse(None, G, Q, sigma0, point=5)


def test_inner_solve_check_refuses_the_library():
    from orientviz.adjust.datum import datum_solve
    from orientviz.exercises._common import rejection

    exc = rejection(lesson09.check_inner_solve, datum_solve)
    assert exc is not None and "calls the library's datum_solve" in str(exc)


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls scipy.linalg.null_space", "stand-in"]:
        assert_diagnoses(
            lesson09, answers, {("check_null_space", "the stand-in (scipy's null_space)"): text}
        )


def test_the_new_stand_ins_are_refused():
    from orientviz.exercises._common import rejection

    exc = rejection(lesson09.check_similarity_columns, lesson09.similarity_basis_library)
    assert exc is not None and "calls the library's" in str(exc)
    exc = rejection(lesson09.check_best_datum, lesson09.best_datum_library)
    assert exc is not None and "calls the library's best_datum_library" in str(exc)
