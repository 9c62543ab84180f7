"""The one test every lesson's checker module gets: solutions pass, mutants fail by far.

``tests/exercises/test_lessonNN.py`` calls :func:`assert_module_checks` on the checker module
(``orientviz.exercises.lessonNN``, installed) and its answers (``answers/lessonNN.py`` here in
the tests: ``SOLUTIONS`` and ``MUTANTS``, which the installed package does not ship).
"""

from __future__ import annotations

import contextlib
import io
import math
from types import ModuleType

from orientviz.exercises._common import CheckFailed, NotWrittenError

#: A mutant must miss by at least this many times the checker's tolerance.
MARGIN = 100.0


def assert_module_checks(module: ModuleType, answers: ModuleType) -> None:
    """Every ``SOLUTIONS`` entry passes its checker, every ``MUTANTS`` entry is rejected.

    A rejection must be a :class:`CheckFailed` (not a crash) whose relative error is at least
    ``MARGIN`` times the tolerance; a blank (``None`` / ``raise NotImplementedError``) must
    get "not written yet".
    """
    assert not hasattr(module, "SOLUTIONS") and not hasattr(module, "MUTANTS"), (
        f"{module.__name__} ships its solutions"
    )
    solutions, mutants = answers.SOLUTIONS, answers.MUTANTS
    assert solutions, f"{module.__name__}: no SOLUTIONS"
    assert set(mutants) <= set(solutions), "a mutant without a solution"
    for name, solution in solutions.items():
        check = getattr(module, name)
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            check(solution)
        assert buf.getvalue().startswith("✓"), f"{name}: the solution passes without the ✓ line"
        assert mutants.get(name), f"{name}: no mutants"

        def blank(*args, **kwargs):
            raise NotImplementedError

        for empty in (None, blank):
            try:
                check(empty)
            except NotWrittenError as exc:
                assert "not written yet" in str(exc)
            else:  # pragma: no cover - the assertion message is the report
                raise AssertionError(
                    f"{name}: an empty blank is not answered with 'not written yet'"
                )
        for label, mutant in mutants[name].items():
            with contextlib.redirect_stdout(io.StringIO()):
                try:
                    check(mutant)
                except NotWrittenError:  # pragma: no cover
                    raise AssertionError(
                        f"{name}/{label}: a mutant is reported as 'not written'"
                    ) from None
                except CheckFailed as exc:
                    assert math.isinf(exc.error) or exc.error >= MARGIN * exc.tolerance, (
                        f"{name}/{label}: rejected only by {exc.error:.3g} (tolerance {exc.tolerance:.3g})"
                    )
                    continue
            raise AssertionError(f"{name}/{label}: the mutant passes the check")


def assert_diagnoses(
    module: ModuleType, answers: ModuleType, expected: dict[tuple[str, str], str]
) -> None:
    """Each named mutant is rejected with a message containing the expected diagnosis.

    ``expected`` maps (checker name, mutant label) to a piece of the message.
    """
    from orientviz.exercises._common import rejection

    for (name, label), text in expected.items():
        exc = rejection(getattr(module, name), answers.MUTANTS[name][label])
        assert exc is not None and text in str(exc), f"{name}/{label}: expected {text!r} in {exc}"
