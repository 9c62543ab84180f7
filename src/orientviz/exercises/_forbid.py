"""Checks that a student's function does not call the library function it is to replace.

A lesson shows the library's way beside the student's blank (as the stand-in that keeps the
released lesson running), so "return datum_solve(N, b, G)" would pass a check that only
compares results. :func:`without_library` runs the student's function while a profiler
watches for calls into the given library functions and raises :class:`CheckFailed`
naming the one called.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import CodeType
from typing import Any

from ._common import CheckFailed

__all__ = ["without_library"]


def _code(func: Any) -> CodeType | None:
    """The code object behind a function, method or ``functools.wraps`` wrapper."""
    while hasattr(func, "__wrapped__"):
        func = func.__wrapped__
    func = getattr(func, "__func__", func)
    return getattr(func, "__code__", None)


@contextmanager
def without_library(what: str, *library: Callable[..., Any]) -> Iterator[None]:
    """Raise :class:`CheckFailed` after the block if it called one of the ``library`` functions.

    Parameters
    ----------
    what : str
        The exercise, for the message (e.g. ``"inner_solve"``).
    *library : callable
        The library functions (or methods) the student's code must not call.
    """
    codes = {c: getattr(f, "__qualname__", str(f)) for f in library if (c := _code(f))}
    called: list[str] = []
    previous = sys.getprofile()

    def watch(frame: Any, event: str, arg: Any) -> None:
        if event == "call" and frame.f_code in codes and not called:
            called.append(codes[frame.f_code])

    sys.setprofile(watch)
    try:
        yield
    finally:
        sys.setprofile(previous)
    if called:
        raise CheckFailed(
            f"{what}: your function calls the library's {called[0]} — that is the answer the "
            "lesson compares with; write the steps yourself in numpy"
        )
