"""A released lesson checks that the installed orientviz has the checks it calls.

``tools/make_student_release.py`` appends one call of :func:`release_check` to the first
code cell of every student copy, with the names of the checks the lesson calls and the
orientviz commit it was made from. A release made from another orientviz than the one
installed (a lesson changed, a check renamed) then stops at its first cell with a message
that says what to do, instead of an ``AttributeError`` half-way through the lesson.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable

from ._common import CheckFailed

__all__ = ["release_check"]


def release_check(lesson: str, checks: Iterable[str], made_with: str = "") -> None:
    """Raise :class:`CheckFailed` unless every check a released lesson calls exists.

    Parameters
    ----------
    lesson : str
        The lesson's number, e.g. ``"05"`` (its checks live in ``orientviz.exercises.lesson05``
        and :mod:`orientviz.exercises.sliders`).
    checks : iterable of str
        The ``check_*`` names the lesson calls.
    made_with : str, optional
        The orientviz commit (or version) the release was made from, for the message.
    """
    found: set[str] = set()
    for name in (f"lesson{lesson}", "sliders", "_common"):
        module = importlib.import_module(f"orientviz.exercises.{name}")
        found |= {k for k in vars(module) if k.startswith("check_")}
    missing = sorted(set(checks) - found)
    if missing:
        made = f" (made from orientviz {made_with})" if made_with else ""
        raise CheckFailed(
            f"this copy of lesson {lesson}{made} calls {', '.join(missing)}, which the installed "
            "orientviz does not have: the lesson and the library are of different versions. Ask "
            "for a release made from the installed orientviz (tools/make_student_release.py), "
            "or install the orientviz the release was made from."
        )
