"""Lesson 11's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson11 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson11


def test_checks():
    assert_module_checks(lesson11, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson11,
        answers,
        {
            ("check_inflation", "variance"): "ratio of the VARIANCES",
            ("check_inflation", "inverted"): "cannot make the first more precise",
            ("check_inflation", "rho"): "ρ itself",
            ("check_inflation", "abs rho"): "ρ enters squared",
            ("check_significant", "signed"): "the sign was kept",
            ("check_described_share", "remainder"): "remainder's share",
        },
    )


def test_fit_k1_check_refuses_the_engine():
    import numpy as np

    from orientviz.adjust import gauss_newton
    from orientviz.exercises._common import rejection

    def fit_k1_engine(xy, d):  # the engine on the K1 column, as the lesson's stand-in
        a = (xy * np.sum(xy**2, axis=1)[:, None]).ravel()
        res = gauss_newton(lambda p: (a * p[0], a[:, None]), [0.0], d.ravel(), 1.0)
        return res.x[0], res.sigma0

    exc = rejection(lesson11.check_fit_k1, fit_k1_engine)
    assert exc is not None and "calls the library's gauss_newton" in str(exc)


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls np.linalg.inv", "stand-in"]:
        assert_diagnoses(
            lesson11, answers, {("check_inflation", "the stand-in (Q inverted)"): text}
        )


def test_inflation_check_refuses_solving_with_q_too():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson11, answers, {("check_inflation", "solve instead of inv"): "calls np.linalg.solve"}
    )
