"""The shared checker helpers diagnose the mistakes they claim to."""

from __future__ import annotations

import math

import numpy as np
import pytest

from orientviz.exercises._common import (
    CheckFailed,
    NotWrittenError,
    angle_unit_diagnosis,
    call,
    compare,
    diagnose,
    rejection,
    rng_for,
    show_mistake,
)


def test_rng_for_is_reproducible_and_distinct():
    a = rng_for("lesson02.check_rotation").normal(size=3)
    b = rng_for("lesson02.check_rotation").normal(size=3)
    c = rng_for("lesson02.check_rotation", salt=1).normal(size=3)
    d = rng_for("lesson04.check_rotation").normal(size=3)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c) and not np.allclose(a, d)


def test_call_reports_blanks():
    def unwritten(x):
        raise NotImplementedError

    def no_return(x):
        x + 1

    for f in (None, ..., unwritten, no_return):
        with pytest.raises(NotWrittenError, match="not written yet"):
            call(f, 1)
    with pytest.raises(CheckFailed, match="expected a function"):
        call(3.0, 1)
    assert call(lambda x: x + 1, 1) == 2


@pytest.mark.parametrize(
    ("factor", "unit", "words"),
    [
        (180 / 200, "gon", "degrees instead of gon"),
        (200 / np.pi, "rad", "gon instead of radians"),
        (180 / np.pi, "rad", "degrees instead of radians"),
        (np.pi / 200, "gon", "radians instead of gon"),
        (200 / 180, "deg", "gon instead of degrees"),
    ],
)
def test_angle_unit_diagnosis(factor, unit, words):
    expected = np.array([12.0, -31.0, 57.0])
    text = angle_unit_diagnosis(expected * factor, expected, unit)
    assert text is not None and words in text


def test_angle_unit_diagnosis_stays_silent_on_other_errors():
    expected = np.array([12.0, -31.0, 57.0])
    assert angle_unit_diagnosis(expected + 1.0, expected, "gon") is None
    assert angle_unit_diagnosis(expected * 0.5, expected, "gon") is None


def test_diagnose_transpose_sign_scale_and_custom():
    R = np.array([[0.0, -1.0, 0.2], [1.0, 0.0, 0.3], [0.1, 0.4, 1.0]])
    assert "transpose" in diagnose(R.T, R)
    assert "opposite sign" in diagnose(-R, R)
    assert "common factor 2" in diagnose(2 * R, R)
    assert diagnose(R + 1, R, wrong=[("weights forgotten", R + 1)]) == "weights forgotten"
    assert diagnose(R + np.eye(3), R) == ""


def test_compare_passes_within_tolerance_and_carries_the_error():
    x = np.array([1.0, 2.0, 3.0])
    assert compare("x", x * (1 + 1e-9), x) < 1e-8
    with pytest.raises(CheckFailed) as info:
        compare("angles", x * 0.9, x, rtol=1e-6, unit="gon")
    assert "degrees instead of gon" in str(info.value)
    assert info.value.error == pytest.approx(0.3 / 3.0)
    assert info.value.tolerance == 1e-6
    with pytest.raises(CheckFailed, match="shape"):
        compare("x", x[:2], x)
    with pytest.raises(CheckFailed) as info:
        compare("x", [np.nan, 1, 2], x)
    assert math.isinf(info.value.error)


def test_rejection_and_show_mistake(capsys):
    def check(v):
        compare("v", v, [1.0, 2.0])
        print("✓ fine")

    assert rejection(check, [1.0, 2.0]) is None
    assert isinstance(rejection(check, [2.0, 1.0]), CheckFailed)
    show_mistake(check, [-1.0, -2.0])
    assert capsys.readouterr().out.startswith("✗ v: wrong")


def test_stand_in_uses_the_library_only_while_the_blank_is_empty(capsys):
    from orientviz.exercises import stand_in
    from orientviz.exercises._common import NotWrittenError, call

    @stand_in(lambda x: x + 100)
    def blank(x):
        raise NotImplementedError

    @stand_in(lambda x: x + 100)
    def written(x):
        return x + 1

    assert blank(1) == 101 and blank(2) == 102
    assert capsys.readouterr().out.count("not written yet") == 1  # one note, not one per call
    assert written(1) == 2
    with pytest.raises(NotWrittenError, match="not written yet"):
        call(blank, 1)  # a check sees the student's blank, not the stand-in
    assert call(written, 1) == 2


def test_a_numpy_shape_error_is_explained():
    from orientviz.exercises._common import CheckFailed, call

    def forgot_the_transpose(W, V):
        return W @ V  # Wᵀ V was meant

    with pytest.raises(CheckFailed, match=r"transposed.*inputs: argument 1 \(4, 6\)"):
        call(forgot_the_transpose, np.ones((4, 6)), np.ones((4, 4)), what="reduce")


def test_a_failed_check_reads_with_a_cross_once():
    """Every CheckFailed (in a traceback as in show_mistake) begins with one "✗"."""
    assert str(CheckFailed("v: wrong")) == "✗ v: wrong"
    assert str(CheckFailed("✗ v: wrong")) == "✗ v: wrong"
    assert str(NotWrittenError("f: not written yet")).startswith("✗ f: not written yet")


def test_complex_step_is_exact_and_the_gate_names_finite_differences():
    """The complex step gives derivatives to round-off; exact_derivatives passes them and names
    a central difference, whatever its step."""
    import numpy as np
    import pytest

    from orientviz.exercises._common import CheckFailed, complex_step, exact_derivatives

    def f(x):  # (2,) → (2,), complex-safe
        return np.array([x[0] ** 3 * np.sin(x[1]), np.exp(x[0]) / (1.0 + x[1] ** 2)])

    x = np.array([0.7, -1.3])
    exact = np.array(
        [
            [3 * x[0] ** 2 * np.sin(x[1]), x[0] ** 3 * np.cos(x[1])],
            [np.exp(x[0]) / (1 + x[1] ** 2), -2 * x[1] * np.exp(x[0]) / (1 + x[1] ** 2) ** 2],
        ]
    )
    J = complex_step(f, x)
    assert np.abs(J - exact).max() < 1e-15 * np.abs(exact).max()
    assert exact_derivatives("J", exact, J) < 1e-15
    for h in (1e-3, 1e-5, 1e-7):
        fd = np.stack([(f(x + e) - f(x - e)) / (2 * h) for e in np.eye(2) * h], axis=1)
        with pytest.raises(CheckFailed, match="finite difference"):
            exact_derivatives("J", fd, J)
