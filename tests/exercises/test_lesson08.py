"""Lesson 08's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson08 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson08


def test_checks():
    assert_module_checks(lesson08, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson08,
        answers,
        {
            ("check_adjust_models", "R transposed"): "R is returned transposed",
            ("check_adjust_models", "start R, T"): "start rotations",
            ("check_adjust_models", "T zero"): "not zeros",
            ("check_strip_polynomial", "degree"): "one degree too low",
            ("check_strip_polynomial", "no tilt"): "cross tilt",
            ("check_strip_polynomial", "tilt to d"): "takes up noise",
            ("check_strip_polynomial", "tilt too low"): "not to d_z − 2",
            ("check_strip_polynomial", "sign"): "wrong sign",
            ("check_strip_polynomial", "full control only"): "plan control only",
            ("check_compose", "order"): "order is wrong",
            ("check_compose", "no scale in t"): "scale m1 is missing",
            ("check_compose", "no rotation in t"): "rotation R1 is missing",
            ("check_intersect_many", "R transposed"): "R transposed",
            ("check_strip_degree", "complex r"): "real numbers",
            ("check_strip_degree", "two-sided"): "one-sided",
            ("check_strip_degree", "le1"): "not a rejection",
            ("check_strip_degree", "min"): "SMALLEST accepted",
            ("check_strip_degree", "no sigma"): "divide the residuals by σ",
            ("check_strip_degree", "level 0.9"): "not at 10 %",
            ("check_strip_degree", "level 0.975"): "not at 2.5 %",
            ("check_strip_degree", "fixed bound 1.2"): "fixed bound on σ̂0",
            ("check_strip_degree", "fixed bound 1.4"): "fixed bound on σ̂0",
            ("check_strips_for", "natural log"): "natural logarithm",
            ("check_strips_for", "a forgotten"): "a is missing",
            ("check_strips_for", "exponent only"): "log10 n_s, not n_s",
            ("check_strips_for", "b <= 0 not handled"): "never rises",
            ("check_intersect_many", "+c"): "z = −c",
            ("check_determined", "counting"): "seven known coordinates are not enough",
            ("check_determined", "two heights"): "three points with Z",
            ("check_determined", "plan points ignored"): "planimetric points",
            ("check_determined", "one plan point"): "two points with X, Y",
            ("check_intersect_many", "not normalised"): "not normalised",
            ("check_intersect_many", "pairwise midpoints"): "pairwise midpoints",
            ("check_model_jacobian", "sign"): "wrong sign",
            ("check_model_jacobian", "left increment"): "increment on the left",
            ("check_model_jacobian", "lambda column"): "λ column",
            ("check_model_jacobian", "own central differences, h 1e-6"): "finite difference",
            ("check_model_jacobian", "own central differences, h 1e-4"): "finite difference",
            ("check_adjust_models", "no weights"): "equal weights",
            ("check_adjust_models", "one step"): "not converged",
            ("check_adjust_models", "left update"): "not converged",
            ("check_adjust_models", "whole points"): "decide per coordinate",
            ("check_adjust_models", "r without points"): "lacks the",
        },
    )


def test_the_lessons_stand_ins_are_refused_and_named():
    """The numeric stand-in of model_jacobian, and a version that calls the library's
    independent_models, are refused by name."""
    from orientviz.exercises._common import rejection

    exc = rejection(lesson08.check_model_jacobian, lesson08.model_jacobian_numeric)
    assert exc is not None and "calls the library's model_jacobian_numeric" in str(exc)

    def by_library(m, model, point, X, free, sigma, R, T):
        import orientviz as ov

        ov.independent_models(None)

    exc = rejection(lesson08.check_adjust_models, by_library)
    assert exc is not None and "calls the library's independent_models" in str(exc)


def test_the_independent_models_module_ships_no_solution():
    """exercises/_independent_models.py (re-exported by lesson08) holds checks and a refused
    stand-in only: none of its functions passes one of its checks."""
    import contextlib
    import inspect
    import io

    from orientviz.exercises import _independent_models as module

    checks = [module.check_model_jacobian, module.check_adjust_models]
    own = [
        f
        for name, f in vars(module).items()
        if inspect.isfunction(f)
        and f.__module__ == module.__name__
        and not name.startswith("check_")
    ]
    assert own
    for check in checks:
        for f in own:
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                try:
                    check(f)
                except Exception:  # noqa: BLE001 - refused or wrong signature: not a solution
                    continue
            assert not out.getvalue().startswith("✓"), f"{check.__name__} accepts {f.__name__}"


def test_the_polynomial_strip_module_ships_no_solution():
    """exercises/_polynomial_strip.py (re-exported by lesson08): none of its functions passes
    its check, and the library's polynomial_adjust is refused by name."""
    import contextlib
    import inspect
    import io

    from orientviz.exercises import _polynomial_strip as module
    from orientviz.exercises._common import rejection

    own = [
        f
        for name, f in vars(module).items()
        if inspect.isfunction(f)
        and f.__module__ == module.__name__
        and not name.startswith("check_")
    ]
    assert own
    for f in own:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            try:
                module.check_strip_polynomial(f)
            except Exception:  # noqa: BLE001 - wrong signature or refused: not a solution
                continue
        assert not out.getvalue().startswith("✓"), f"check_strip_polynomial accepts {f.__name__}"

    def by_library(x, X, dxy, dz):
        from orientviz.polynomial import polynomial_adjust

        polynomial_adjust(None)

    exc = rejection(lesson08.check_strip_polynomial, by_library)
    assert exc is not None and "calls the library's polynomial_adjust" in str(exc)
