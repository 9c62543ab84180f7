"""A "your version" check rejects an answer that calls the library the lesson shows above it.

Each case is the stand-in of the lesson (the library's way, shown right above the blank in
the student's release) handed to the check as if it were the student's function: the check
must answer "✗ … calls the library's …", not ✓.
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.adjust.engine import gauss_newton
from orientviz.exercises import (
    lesson01,
    lesson02,
    lesson03,
    lesson04,
    lesson05,
    lesson06,
    lesson07,
    lesson08,
    rejection,
)
from orientviz.exercises._common import call, own_work
from orientviz.orientation.absolute import similarity_closed_form
from orientviz.orientation.essential import eight_point
from orientviz.orientation.interior import fiducial_transformation
from orientviz.orientation.intersection import intersect_rays


def _line_fit(X, l, sigma):
    A = np.column_stack([np.ones_like(X), X])
    res = gauss_newton(lambda x: (A @ x, A), [0.0, 1.0], l, sigma)
    return res.x, res.residuals, res.sigma0, res.cofactor


def _affine(machine, calibrated):
    res = fiducial_transformation(machine, calibrated, model="affine", sigma=0.002)
    return res.x, res.residuals, res.sigma0 * 0.002


def _resection(xy, X, c, sigma, p0, n_iter=10):
    res = ov.resection(xy, X, c, sigma=sigma)
    return res.x, res.sigma0


def _two_rays(X01, d1, X02, d2):
    return intersect_rays(np.array([X01, X02]), np.array([d1, d2]), np.zeros(2, int), 1)[0][0]


def _kovarik(xy1, xy2, c, b, tol=1e-9, max_iter=20):
    return ov.relative_orientation(xy1, xy2, c, b=b).x, [1.0, 1.0, 1.0]


def _similarity(x, X):
    t = similarity_closed_form(x, X)
    return t.scale, t.R, t.t


def _intersect_many(X0, R, xy, c):
    out = ov.intersect_points(xy, np.arange(len(xy)), np.zeros(len(xy), int), X0, R, c)
    return out.xyz[0]


CASES = [
    (lesson01.check_line_fit, _line_fit, "gauss_newton"),
    (lesson02.check_rotation,
     lambda w, p, k: ov.matrix_from_opk(*ov.to_rad(np.array([w, p, k]), "gon")), "matrix_from_opk"),
    (lesson02.check_collinearity, ov.project, "project"),
    (lesson03.check_affine_fit, _affine, "fiducial_transformation"),
    (lesson04.check_resection, _resection, "resection"),
    (lesson04.check_two_rays, _two_rays, "intersect_rays"),
    (lesson05.check_kovarik_iteration, _kovarik, "relative_orientation"),
    (lesson06.check_eight_point, eight_point, "eight_point"),
    (lesson07.check_similarity, _similarity, "similarity_closed_form"),
    (lesson08.check_intersect_many, _intersect_many, "intersect_points"),
]  # fmt: skip


@pytest.mark.parametrize(
    "check,answer,name", CASES, ids=[c[2] + "-" + c[0].__module__[-8:] for c in CASES]
)
def test_a_check_rejects_the_library_standing_in_for_the_student(check, answer, name):
    exc = rejection(check, answer)
    assert exc is not None, f"{check.__name__} passes the library's {name}"
    assert f"calls the library's {name}" in str(exc), str(exc)


def test_own_work_sees_through_aliases_and_leaves_other_calls_alone():
    def library(x):
        return 2 * x

    alias = library
    with own_work(library=library):
        with pytest.raises(AssertionError, match="calls the library's library"):
            call(lambda x: alias(x) + 0, 1.0, what="f")
        assert call(lambda x: 2 * x, 1.0, what="f") == 2.0
    assert call(lambda x: alias(x), 1.0, what="f") == 2.0  # outside the block: allowed


def test_kovarik_check_demands_shrinking_steps():
    from answers import lesson05 as answers

    good = answers.SOLUTIONS["check_kovarik_iteration"]

    def constant_steps(*a, **k):
        e, steps = good(*a, **k)
        return e, [1.0] * len(steps)

    exc = rejection(lesson05.check_kovarik_iteration, constant_steps)
    assert exc is not None and "do not shrink" in str(exc)


def test_small_matrices_lets_a_small_inverse_through_and_names_a_large_one():
    from orientviz.exercises._common import small_matrices

    with small_matrices(3, "too large here", inv=np.linalg.inv):
        assert call(lambda a: np.linalg.inv(a)[0, 0], 2.0 * np.eye(3), what="f") == 0.5
        with pytest.raises(AssertionError, match="f hands a 4 × 4 matrix to inv: too large here"):
            call(lambda a: np.linalg.inv(a)[0, 0], np.eye(4), what="f")
    assert call(lambda a: np.linalg.inv(a)[0, 0], np.eye(4), what="f") == 1.0  # outside


def test_own_work_says_the_reason_it_is_given():
    def library(x):
        return 2 * x

    with own_work("why not", library=library):
        with pytest.raises(AssertionError, match="f calls the library's library: why not"):
            call(library, 1.0, what="f")
