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
            ("check_k1_alone", "the lens's K1"): "takes over what K2 and K3 describe",
            ("check_k1_alone_format", "no area element"): "area element",
            ("check_k1_alone_format", "rim"): "rim",
            ("check_k1_alone_format", "sampled"): "sampled points",
            ("check_k1_alone_format", "grid"): "numerical integral",
            ("check_k1_alone", "K3 forgotten"): "K3 forgotten",
            ("check_k1_alone", "plain means"): "weigh with r⁶",
            ("check_k1_alone", "weights r⁴"): "not r⁴",
            ("check_per_test_alpha", "Bonferroni"): "Bonferroni's bound",
            ("check_per_test_alpha", "the family's level"): "each test at the family's level",
            ("check_per_test_alpha", "not rejecting"): "does not reject",
            ("check_per_test_alpha", "turned round"): "turned round",
            ("check_trough_term", "a scale (in the span)"): "adds nothing",
            ("check_trough_term", "x² in x (in the span too)"): "adds nothing",
            ("check_trough_term", "x⁵ in x"): "which power of x",
            ("check_trough_term", "x³ in y"): "a term in y only",
            ("check_trough_term", "radial r²"): "a radial r² term (K1)",
            ("check_trough_term", "the trough itself"): "the trough itself",
            ("check_trough_term", "the library's trough"): "calls the library's unflatness",
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
    from orientviz.exercises._common import rejection

    exc = rejection(lesson11.check_inflation, lesson11.inflation_library)
    assert exc is not None and "calls np.linalg.inv" in str(exc) and "stand-in" in str(exc)


def test_inflation_check_refuses_solving_with_q_too():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson11, answers, {("check_inflation", "solve instead of inv"): "calls np.linalg.solve"}
    )
