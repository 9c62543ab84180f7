"""The library stands in for a student's function while its blank is still empty.

In a lesson, the student's function is decorated with the library's equivalent::

    @stand_in(lambda xy1, xy2, b: rel.y_parallax(xy1, xy2, ...)[0])
    def y_parallax(xy1, xy2, b):
        ### BEGIN SOLUTION
        ...
        ### END SOLUTION

Called by the lesson's later cells, ``y_parallax`` runs the student's code; while that
code is still the blank ``raise NotImplementedError`` of the student release, it prints one
note and returns the library's result instead, so "Run All" reaches the end of the lesson.
A check never sees the stand-in: :func:`~orientviz.exercises._common.call` unwraps the
decorated function and answers a blank with "not written yet".
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["stand_in", "student_function"]

F = TypeVar("F", bound=Callable[..., Any])

_MARK = "__orientviz_student__"


def stand_in(library: Callable[..., Any]) -> Callable[[F], F]:
    """Decorate a student's function so that ``library`` answers while it is a blank.

    Parameters
    ----------
    library : callable
        Takes the same arguments as the student's function and returns the same kind of
        result (the library's way of computing it).

    Returns
    -------
    callable
        The decorator. The decorated function has the student's function as
        ``__wrapped__``; the checks call that one.
    """

    def decorate(student: F) -> F:
        noted = False

        @functools.wraps(student)
        def run(*args: Any, **kwargs: Any) -> Any:
            nonlocal noted
            try:
                return student(*args, **kwargs)
            except NotImplementedError:
                if not noted:
                    print(
                        f"({student.__name__} is not written yet: the library's result is "
                        "used here instead)"
                    )
                    noted = True
                return library(*args, **kwargs)

        setattr(run, _MARK, student)
        return run  # type: ignore[return-value]

    return decorate


def student_function(func: Any) -> Any:
    """The student's own function behind a :func:`stand_in` decoration (else ``func``)."""
    return getattr(func, _MARK, func)
