"""Lesson 13's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson13 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson13


def test_checks():
    assert_module_checks(lesson13, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson13,
        answers,
        {
            ("check_statoscope_normals", "no weight"): "weight 1/σ² is missing",
            ("check_statoscope_normals", "X0 column"): "not 6k (X0)",
            ("check_statoscope_normals", "one offset"): "each strip has its own",
            ("check_statoscope_normals", "reading"): "the misclosure s − (Z0 + o)",
            ("check_statoscope_normals", "sign"): "the misclosure's sign",
            ("check_statoscope_normals", "no offset"): "current offsets are missing",
            ("check_gnss_lever_rows", "no arm"): "the lever arm turns with the camera",
            ("check_gnss_lever_rows", "transposed"): "Rᵀe",
            ("check_gnss_lever_rows", "sign"): "wrong sign",
            ("check_gnss_lever_rows", "kappa left"): "R[e_Z]×",
            ("check_gnss_lever_rows", "the library's derivatives"): "calls the library's "
            "matrix_derivatives",
            ("check_difference_covariance", "independent"): "not independent",
            ("check_from_differences", "independent"): "taken as independent",
            ("check_from_differences", "C as weight"): "covariance itself used as the weight",
            ("check_from_differences", "no offset"): "without the offset",
            ("check_from_differences", "the offset model again"): "is the offset model again",
            ("check_from_differences", "the offset model by QR"): "matrix to np.linalg.qr",
        },
    )


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls the library's statoscope_row_library", "stand-in"]:
        assert_diagnoses(lesson13, answers, {("check_statoscope_row", "the stand-in"): text})


def test_the_bundles_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson13,
        answers,
        {
            (
                "check_statoscope_normals",
                "the stand-in",
            ): "calls the library's statoscope_normals_library"
        },
    )
