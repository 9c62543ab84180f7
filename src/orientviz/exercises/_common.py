"""Shared helpers for the lesson checkers (see :mod:`orientviz.exercises`).

Every checker follows one recipe: build fresh inputs from its own seeded generator
(:func:`rng_for`), call the student's function through :func:`call`, compare the answer
with an independent oracle through :func:`compare` (which names the plausible mistake:
transpose, sign, angle unit, scale), and print :func:`success` when all is well.

A failed check raises :class:`CheckFailed`, an :class:`AssertionError` that also carries
the relative error found and the tolerance used, so that the tests in
``tests/exercises`` can demand that each mutant misses by far more than the tolerance.
"""

from __future__ import annotations

import contextlib
import contextvars
import inspect
import math
import sys
import zlib
from collections.abc import Callable, Iterable, Iterator
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from ._standin import student_function

__all__ = [
    "ANGLE_FACTORS",
    "INVERTERS",
    "CheckFailed",
    "NotWrittenError",
    "angle_unit_diagnosis",
    "call",
    "compare",
    "complex_step",
    "diagnose",
    "exact_derivatives",
    "is_sign_flip",
    "is_transpose",
    "own_work",
    "relative_error",
    "rejection",
    "rng_for",
    "scale_diagnosis",
    "show_mistake",
    "small_matrices",
    "success",
    "check_determined_table",
]

#: Size of one unit in radians (rad, deg, gon, c, cc), for the angle-unit diagnosis.
ANGLE_FACTORS: dict[str, float] = {
    "rad": 1.0,
    "deg": math.pi / 180.0,
    "gon": math.pi / 200.0,
}


#: numpy's and scipy's functions that invert a matrix or solve with it, by the name a message
#: uses (for :func:`own_work` / :func:`small_matrices` in exercises that avoid an inverse).
INVERTERS: dict[str, Callable[..., Any]] = {
    "np.linalg.inv": np.linalg.inv,
    "np.linalg.solve": np.linalg.solve,
    "np.linalg.pinv": np.linalg.pinv,
    "np.linalg.lstsq": np.linalg.lstsq,
    "scipy.linalg.inv": scipy.linalg.inv,
    "scipy.linalg.solve": scipy.linalg.solve,
    "scipy.linalg.pinv": scipy.linalg.pinv,
    "scipy.linalg.lstsq": scipy.linalg.lstsq,
}


class CheckFailed(AssertionError):
    """A check found a wrong answer; its message begins with "✗".

    Attributes
    ----------
    error : float
        Relative error of the answer against the oracle (``inf`` for a wrong shape,
        a missing answer or a non-finite value).
    tolerance : float
        The relative tolerance the check allowed.
    """

    def __init__(self, message: str, error: float = math.inf, tolerance: float = 0.0) -> None:
        # every failed check reads "✗ …" (a passed one prints "✓ …"), in a traceback too
        super().__init__(message if message.startswith("✗") else f"✗ {message}")
        self.error = float(error)
        self.tolerance = float(tolerance)


class NotWrittenError(CheckFailed):
    """The exercise's blank is still empty (``raise NotImplementedError``, ``...`` or ``None``)."""


def rng_for(name: str, salt: int = 0) -> np.random.Generator:
    """A generator seeded from a checker's name: fresh inputs, the same on every run.

    Parameters
    ----------
    name : str
        The checker's name, e.g. ``"lesson02.check_rotation"``.
    salt : int, optional
        A further integer to draw a second, independent set of inputs.

    Returns
    -------
    numpy.random.Generator
    """
    return np.random.default_rng([zlib.crc32(name.encode("utf-8")), int(salt)])


class _Guard(NamedTuple):
    """One forbidden library function: its name in messages, why it is forbidden and the
    most columns of a matrix it may still be given (None: not called at all)."""

    name: str
    reason: str | None
    limit: int | None


#: The library functions the running check forbids, by code object (see :func:`own_work`).
_FORBIDDEN: contextvars.ContextVar[dict[Any, _Guard] | None] = contextvars.ContextVar(
    "orientviz_exercises_forbidden", default=None
)


@contextlib.contextmanager
def _forbid(guards: dict[Any, _Guard]) -> Iterator[None]:
    token = _FORBIDDEN.set({**(_FORBIDDEN.get() or {}), **guards})
    try:
        yield
    finally:
        _FORBIDDEN.reset(token)


def own_work(reason: str | None = None, /, **library: Callable[..., Any]) -> Any:
    """Within the block, :func:`call` rejects a student's function that runs ``library``.

    A "your version" exercise asks for the student's own numpy; the lesson shows the
    library's equivalent right above the blank (it stands in while the blank is empty).
    Inside ``with own_work(resection=resection): …`` every :func:`call` watches the
    student's function with a profile hook and raises :class:`CheckFailed` naming the library
    function if its code runs — whatever name or wrapper (a stand-in, a lambda, an alias)
    it was called through.

    Parameters
    ----------
    reason : str, optional
        What the message says after naming the function (default: the exercise asks for
        your own numpy; the library stands in only while the blank is empty).
    **library : callable
        The forbidden library functions, keyed by the name the message uses.

    Returns
    -------
    context manager
        Usable as ``with own_work(...):`` and as a decorator of a check.
    """
    return _forbid(
        {inspect.unwrap(f).__code__: _Guard(name, reason, None) for name, f in library.items()}
    )


def small_matrices(limit: int, reason: str, /, **library: Callable[..., Any]) -> Any:
    """Within the block, :func:`call` rejects a student's function that hands ``library``
    (e.g. ``np.linalg.inv``) a matrix with more than ``limit`` columns.

    For exercises whose point is to avoid a large inverse (an update formula that needs only
    a small one): the first argument of each watched call is measured.

    Parameters
    ----------
    limit : int
        The most columns still allowed (e.g. 3 for a 3 × 3 inverse; for a least-squares
        fit the columns are its unknowns).
    reason : str
        What the message says after naming the call and the size.
    **library : callable
        The watched functions, keyed by the name the message uses.

    Returns
    -------
    context manager
        Usable as ``with small_matrices(...):`` and as a decorator of a check.
    """
    return _forbid(
        {
            inspect.unwrap(f).__code__: _Guard(name, reason, int(limit))
            for name, f in library.items()
        }
    )


def _library_message(what: str, hit: tuple[_Guard, tuple[int, ...] | None]) -> str:
    guard, shape = hit
    if shape is not None:
        size = " × ".join(str(k) for k in shape)
        return f"{what} hands a {size} matrix to {guard.name}: {guard.reason}"
    reason = guard.reason or (
        "this exercise asks for your own numpy (the library stands in above only while your "
        "blank is empty)"
    )
    whose = "" if "." in guard.name else "the library's "  # np.linalg.inv: numpy, not ours
    return f"{what} calls {whose}{guard.name}: {reason}"


def _too_large(frame: Any, limit: int) -> tuple[int, ...] | None:
    """The shape of the watched call's first argument if its columns (the unknowns of an
    inverse, a solve or a least-squares fit) exceed ``limit``."""
    code = frame.f_code
    if not code.co_argcount:
        return None
    try:
        shape = tuple(int(k) for k in np.shape(frame.f_locals.get(code.co_varnames[0])))
    except (TypeError, ValueError):  # pragma: no cover - not an array-like
        return None
    return shape if shape and shape[-1] > limit else None


def _run_watched(func: Callable[..., Any], args: tuple, kwargs: dict, what: str) -> Any:
    """Run ``func``; raise :class:`CheckFailed` if it ran a library function :func:`own_work`
    forbids or handed one of :func:`small_matrices` too large a matrix (also when it then
    failed)."""
    forbidden = _FORBIDDEN.get() or {}
    if not forbidden:
        return func(*args, **kwargs)
    hits: list[tuple[_Guard, tuple[int, ...] | None]] = []

    def hook(frame: Any, event: str, arg: Any) -> None:
        if event != "call" or hits:
            return
        guard = forbidden.get(frame.f_code)
        if guard is None:
            return
        if guard.limit is None:
            hits.append((guard, None))
        else:
            shape = _too_large(frame, guard.limit)
            if shape is not None:
                hits.append((guard, shape))

    previous = sys.getprofile()
    sys.setprofile(hook)
    try:
        out = func(*args, **kwargs)
    except Exception:
        sys.setprofile(previous)
        if hits:
            raise CheckFailed(_library_message(what, hits[0])) from None
        raise
    sys.setprofile(previous)
    if hits:
        raise CheckFailed(_library_message(what, hits[0]))
    return out


def call(func: Any, *args: Any, what: str = "your function", **kwargs: Any) -> Any:
    """Call the student's function and turn an unwritten blank into a clear message.

    Parameters
    ----------
    func : callable or None or Ellipsis
        The student's answer.
    *args, **kwargs
        Passed to ``func``.
    what : str, optional
        How the message names the function.

    Returns
    -------
    Any
        What ``func`` returned.

    Raises
    ------
    NotWrittenError
        If ``func`` is ``None``/``...``, raises ``NotImplementedError`` or returns ``None``
        or ``...``.
    CheckFailed
        If ``func`` is not callable.
    """
    func = student_function(func)  # a check never sees the library standing in
    if func is None or func is Ellipsis:
        raise NotWrittenError(f"{what}: not written yet (the blank is still empty).")
    if not callable(func):
        raise CheckFailed(f"{what}: expected a function, got {type(func).__name__}.")
    try:
        out = _run_watched(func, args, kwargs, what)
    except NotImplementedError:
        raise NotWrittenError(
            f"{what}: not written yet (it still raises NotImplementedError)."
        ) from None
    except (ValueError, IndexError, np.linalg.LinAlgError) as exc:
        raise CheckFailed(_shape_message(what, exc, args, kwargs)) from None
    if out is None or out is Ellipsis:
        raise NotWrittenError(f"{what}: not written yet (it returns {out!r}; a `return` missing?).")
    return out


def _shape_message(what: str, exc: Exception, args: tuple, kwargs: dict) -> str:
    """Explain a numpy error raised inside the student's function, with the inputs' shapes."""
    shapes = [
        f"{name} {np.shape(value)}"
        for name, value in [(f"argument {i + 1}", a) for i, a in enumerate(args)]
        + list(kwargs.items())
        if isinstance(value, np.ndarray) and value.ndim
    ]
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if isinstance(exc, np.linalg.LinAlgError):
        hint = "a matrix you invert or solve with is singular or not square — a transposed factor?"
    elif "matmul" in text or "shapes" in text or "broadcast" in text or "dimension" in text:
        hint = (
            "the shapes do not fit — is a matrix transposed (Wᵀ for W, Rᵀ for R) or a vector a row?"
        )
    else:
        hint = "an index or a value does not fit the inputs' shapes"
    given = f" (inputs: {', '.join(shapes)})" if shapes else ""
    return (
        f"{what}: numpy stopped inside your function — {text}. {hint[0].upper()}{hint[1:]}{given}"
    )


def success(message: str) -> None:
    """Print the short success line of a check (``✓ message``)."""
    print(f"✓ {message}")


def check_determined_table(
    got: list[bool],
    truth: list[bool],
    cases: list[tuple[int, ...]],
    rules: list[tuple[str, Callable[..., Any]]],
    *,
    labels: str,
    what: str,
    rank: str,
) -> None:
    """Compare a student's "is it determined?" answers with the rank oracle's, case by case.

    Parameters
    ----------
    got, truth : list of bool
        The student's answer and the oracle's (rank test) for each case.
    cases : list of tuple of int
        The counts each answer was asked for (the arguments of the student's function).
    rules : list of (str, callable)
        Plausible wrong rules: when ``got`` equals a rule's answer for every case, the
        message names that rule's mistake (its text).
    labels : str
        What the counts of a case are, e.g. ``"full, plan, height"``.
    what : str
        What the cases vary, for the message "wrong for some {what}".
    rank : str
        The system and its full rank, e.g. ``"the system has rank 8"``; for the first wrong
        case the message says "... has rank 8 (determined)" or "... has rank below 8 (not
        determined)".

    Raises
    ------
    CheckFailed
        When ``got`` differs from ``truth``.
    """
    if got == truth:
        return
    for text, rule in rules:
        if got == [bool(rule(*c)) for c in cases]:
            raise CheckFailed(f"determined: wrong for some {what} — {text}")
    k = next(i for i in range(len(cases)) if got[i] != truth[i])
    system, full = rank.rsplit(" ", 1)
    state = f"{full} (determined)" if truth[k] else f"below {full} (not determined)"
    raise CheckFailed(f"determined{cases[k]} ({labels}) = {got[k]}: {system} {state} there")


def relative_error(got: ArrayLike, expected: ArrayLike, scale: float | None = None) -> float:
    """Largest absolute difference divided by a scale (default: the largest abs(expected), at least 1e-300).

    Parameters
    ----------
    got, expected : array_like
        Arrays of one shape.
    scale : float, optional
        The reference size; by default ``max(|expected|)``.

    Returns
    -------
    float
        ``max|got - expected| / scale``; ``inf`` if ``got`` is not finite.
    """
    g = np.asarray(got, dtype=float)
    e = np.asarray(expected, dtype=float)
    if not np.all(np.isfinite(g)):
        return math.inf
    ref = float(np.max(np.abs(e))) if scale is None else float(scale)
    return float(np.max(np.abs(g - e), initial=0.0)) / max(ref, 1e-300)


def is_transpose(got: ArrayLike, expected: ArrayLike, rtol: float = 1e-6) -> bool:
    """True if ``got`` equals the transpose of the square matrix ``expected`` (and it is not symmetric)."""
    g = np.asarray(got, dtype=float)
    e = np.asarray(expected, dtype=float)
    if g.ndim < 2 or g.shape != e.shape or g.shape[-1] != g.shape[-2]:
        return False
    eT = np.swapaxes(e, -1, -2)
    return relative_error(g, eT) <= rtol and relative_error(e, eT) > rtol


def is_sign_flip(got: ArrayLike, expected: ArrayLike, rtol: float = 1e-6) -> bool:
    """True if ``got`` equals ``-expected`` (and ``expected`` is not zero)."""
    g = np.asarray(got, dtype=float)
    e = np.asarray(expected, dtype=float)
    return (
        g.shape == e.shape
        and relative_error(g, -e) <= rtol
        and float(np.max(np.abs(e), initial=0.0)) > 0
    )


def _ratio(got: NDArray[np.float64], expected: NDArray[np.float64]) -> float | None:
    """The common factor got/expected if one fits all entries within 1e-6 (else None)."""
    mask = np.abs(expected) > 1e-12 * max(float(np.max(np.abs(expected), initial=0.0)), 1e-300)
    if not np.any(mask):
        return None
    k = float(np.median(got[mask] / expected[mask]))
    if k == 0.0 or relative_error(got, k * expected) > 1e-6:
        return None
    return k


def angle_unit_diagnosis(got: ArrayLike, expected: ArrayLike, unit: str = "gon") -> str | None:
    """Name an angle-unit mistake: ``got`` equals ``expected`` (in ``unit``) read in another unit.

    Parameters
    ----------
    got : array_like
        The student's angles.
    expected : array_like
        The oracle's angles, in ``unit``.
    unit : {"gon", "deg", "rad"}
        The unit the exercise asks for.

    Returns
    -------
    str or None
        e.g. ``"off by a factor 0.9: degrees instead of gon?"``, or None if no unit fits.
    """
    g = np.asarray(got, dtype=float)
    e = np.asarray(expected, dtype=float)
    if g.shape != e.shape:
        return None
    k = _ratio(g, e)
    if k is None:
        return None
    names = {"rad": "radians", "deg": "degrees", "gon": "gon"}
    for other, size in ANGLE_FACTORS.items():
        if other == unit:
            continue
        factor = ANGLE_FACTORS[unit] / size  # the same angle counted in `other` units
        if abs(k / factor - 1.0) < 1e-6:
            return f"off by a factor {factor:.4g}: {names[other]} instead of {names[unit]}?"
    return None


def scale_diagnosis(got: ArrayLike, expected: ArrayLike) -> str | None:
    """Name a common factor between ``got`` and ``expected`` (e.g. a forgotten 1/n or weight)."""
    g = np.asarray(got, dtype=float)
    e = np.asarray(expected, dtype=float)
    if g.shape != e.shape:
        return None
    k = _ratio(g, e)
    if k is None or abs(k - 1.0) < 1e-6:
        return None
    if abs(k + 1.0) < 1e-6:
        return "the sign is wrong throughout"
    return f"off by a common factor {k:.6g}"


def diagnose(
    got: ArrayLike,
    expected: ArrayLike,
    unit: str | None = None,
    wrong: Iterable[tuple[str, ArrayLike]] = (),
    rtol: float = 1e-6,
) -> str:
    """Name the most plausible mistake that turns ``expected`` into ``got``.

    Parameters
    ----------
    got, expected : array_like
        The answer and the oracle.
    unit : str, optional
        If the values are angles in this unit, try the other units.
    wrong : iterable of (str, array_like)
        Lesson-specific wrong answers, as (diagnosis, value): if ``got`` matches a value,
        that diagnosis is returned. They are tried first.
    rtol : float
        Tolerance for a match.

    Returns
    -------
    str
        The diagnosis, or ``""`` if none fits.
    """
    g = np.asarray(got, dtype=float)
    for text, value in wrong:
        v = np.asarray(value, dtype=float)
        if v.shape == g.shape and relative_error(g, v) <= rtol:
            return text
    if is_transpose(g, expected, rtol):
        return "it equals the transpose of the right answer"
    if is_sign_flip(g, expected, rtol):
        return "it equals the right answer with the opposite sign"
    if unit is not None:
        text = angle_unit_diagnosis(g, expected, unit)
        if text:
            return text
    return scale_diagnosis(g, expected) or ""


def compare(
    name: str,
    got: ArrayLike,
    expected: ArrayLike,
    rtol: float = 1e-6,
    unit: str | None = None,
    wrong: Iterable[tuple[str, ArrayLike]] = (),
    scale: float | None = None,
) -> float:
    """Compare an answer with the oracle; raise :class:`CheckFailed` with a diagnosis if it differs.

    Parameters
    ----------
    name : str
        What is compared (used in the message), e.g. ``"R(ω, φ, κ)"``.
    got, expected : array_like
        The answer and the oracle's value.
    rtol : float
        Allowed ``max|got - expected| / scale``.
    unit : str, optional
        The angle unit of ``expected`` if the values are angles (enables the unit diagnosis).
    wrong : iterable of (str, array_like)
        Lesson-specific wrong answers with their diagnosis (see :func:`diagnose`).
    scale : float, optional
        Reference size for the relative error (default: the largest abs(expected)).

    Returns
    -------
    float
        The relative error found (≤ ``rtol``).
    """
    e = np.asarray(expected, dtype=float)
    try:
        g = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise CheckFailed(
            f"{name}: expected numbers of shape {e.shape}, got {type(got).__name__}."
        ) from None
    if g.shape != e.shape:
        hint = " (a transposed vector?)" if sorted(g.shape) == sorted(e.shape) else ""
        raise CheckFailed(f"{name}: expected shape {e.shape}, got {g.shape}{hint}.", tolerance=rtol)
    err = relative_error(g, e, scale)
    if err <= rtol:
        return err
    wrong = list(wrong)
    text = diagnose(g, e, unit=unit, wrong=wrong, rtol=max(rtol, 1e-6))
    with np.printoptions(precision=6, suppress=True):
        detail = f"\n  yours:    {np.array2string(g, prefix='  yours:    ')}\n  expected: {np.array2string(e, prefix='  expected: ')}"
    if g.size > 12:
        detail = ""
    msg = f"{name}: wrong (relative difference {err:.3g}, allowed {rtol:.1g})"
    msg += (f" — {text}" + ("" if text.endswith(("?", ".")) else ".")) if text else "."
    raise CheckFailed(msg + detail, error=err, tolerance=rtol)


def complex_step(
    f: Callable[[NDArray[np.complex128]], ArrayLike], x: ArrayLike
) -> NDArray[np.float64]:
    """Derivatives of ``f`` at ``x`` by the complex step, exact to round-off.

    ``Im f(x + i h e_k) / h`` with h = 1e-30 has no truncation error worth the name (h²) and,
    unlike a finite difference, no cancellation: the derivative comes out to about 1e-16
    relative. ``f`` must be written with operations that accept complex numbers (no ``abs``,
    no ``np.linalg.norm``, no casts to float).

    Parameters
    ----------
    f : callable
        Maps an array of the shape of ``x`` (complex) to an array (complex).
    x : array_like
        The point (real).

    Returns
    -------
    ndarray, shape ``f(x).shape + x.shape``
        ∂f/∂x, in f's units per x's units.
    """
    x = np.asarray(x, dtype=float)
    h = 1e-30
    cols = []
    for k in range(x.size):
        step = np.zeros(x.size, dtype=complex)
        step[k] = 1j * h
        cols.append(np.imag(np.asarray(f(x + step.reshape(x.shape)))) / h)
    out = np.stack(cols, axis=-1)
    return out.reshape(out.shape[:-1] + x.shape)


def exact_derivatives(name: str, got: ArrayLike, exact: ArrayLike, rtol: float = 1e-13) -> float:
    """After a check against finite differences passed: demand round-off agreement.

    A derivation gives partial derivatives that agree with exact ones (complex step, extended
    precision or a closed form) to about 1e-15 of their size. A finite difference — the
    numeric shortcut that skips the derivation — is off by 1e-10 or more whatever its step
    (truncation against cancellation). So an answer that passed the comparison with central
    differences but misses here by more than ``rtol`` is numeric, and is named as such.

    Parameters
    ----------
    name : str
        What is compared (used in the message).
    got, exact : array_like
        The answer and the exact derivatives, one shape.
    rtol : float
        Allowed ``max|got - exact| / max|exact|``.

    Returns
    -------
    float
        The relative error found (≤ ``rtol``).
    """
    err = relative_error(got, exact)
    if err <= rtol:
        return err
    raise CheckFailed(
        f"{name}: right to {err:.0e} of their size, but not to round-off (allowed {rtol:.0e}) — "
        "the signature of a finite difference (numeric derivatives, whatever the step), not of "
        "derived ones, which agree with the exact derivatives to about 1e-15. The exercise is the "
        "derivation: write the partials out.",
        error=err,
        tolerance=rtol,
    )


def rejection(check: Callable[[Any], Any], answer: Any) -> CheckFailed | None:
    """Run ``check(answer)`` silently; return the :class:`CheckFailed` it raised, or None if it passed.

    Used by ``tests/exercises`` and by notebooks that show a wrong answer's message.
    """
    import contextlib
    import io

    with contextlib.redirect_stdout(io.StringIO()):
        try:
            check(answer)
        except CheckFailed as exc:
            return exc
    return None


def show_mistake(check: Callable[[Any], Any], answer: Any) -> None:
    """Print what ``check`` says about a (deliberately) wrong answer, without raising.

    Notebooks use this to show a checker's diagnosis without an error cell in the book.
    """
    exc = rejection(check, answer)
    if exc is None:
        print("(this answer passes the check)")
    else:
        print(str(exc))  # the message begins with "✗"
