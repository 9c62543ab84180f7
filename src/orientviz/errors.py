"""The exceptions orientviz raises on purpose.

* :class:`InputError` — the input is wrong (a file, a shape, an id). The command line
  prints its one-line message and exits with code 2.
* :class:`AdjustmentError` — the input is well formed but the adjustment cannot be
  done: a datum defect, parameters that are not determinable, a breakdown. Exit code 3.

Both derive from :class:`OrientvizError`; :class:`InputError` is also a ``ValueError``
so that ``check_*`` validators can be caught either way.
"""

from __future__ import annotations


class OrientvizError(Exception):
    """Base class of orientviz's deliberate errors."""

    exit_code = 1


class InputError(OrientvizError, ValueError):
    """Bad input: names the source, the place and what is wrong.

    Parameters
    ----------
    message : str
        What is wrong, e.g. ``"expected 3 coordinates, got 2"``.
    source : str, optional
        The file (or other source) the input came from.
    where : str, optional
        The place inside it, e.g. ``"observations[12].x"`` or ``"line 7"``.
    """

    exit_code = 2

    def __init__(self, message: str, source: str | None = None, where: str | None = None):
        self.message = message
        self.source = source
        self.where = where
        super().__init__(self.one_line())

    def one_line(self) -> str:
        """``"file: place: message"``, omitting what is unknown.

        Always one printable line: line breaks become spaces, characters that cannot be
        encoded (lone surrogates) are shown as escapes, and user text longer than 300
        characters is shortened.
        """
        parts = [printable(p, 300) for p in (self.source, self.where) if p]
        return ": ".join(parts + [printable(self.message, 1000)])


def printable(text: object, limit: int = 300) -> str:
    """``text`` as one printable line of at most ``limit`` characters (for messages)."""
    flat = " ".join(str(text).split())
    flat = flat.encode("utf-8", "backslashreplace").decode("utf-8")
    return flat if len(flat) <= limit else flat[: limit - 3] + "..."


class AdjustmentError(OrientvizError):
    """The adjustment could not be carried out (exit code 3)."""

    exit_code = 3


class NotDeterminableError(AdjustmentError):
    """Some parameters are not determinable from the observations.

    Parameters
    ----------
    message : str
        Explanation for the user.
    parameters : list of str
        Names of the parameters involved in the rank defect.
    defect : int
        Number of missing ranks (e.g. 7 for a free 3D network).
    """

    def __init__(self, message: str, parameters: list[str] | None = None, defect: int = 0):
        self.parameters = list(parameters or [])
        self.defect = int(defect)
        super().__init__(message)


class DatumDefectError(NotDeterminableError):
    """The datum is not defined: translation, rotation or scale are free."""


#: Parameter suffixes of an image's exterior orientation and of a point.
_IMAGE_PARTS = {"X0": "X0", "Y0": "Y0", "Z0": "Z0", "omega": "ω", "phi": "φ", "kappa": "κ"}
_POINT_PARTS = ("X", "Y", "Z")


def parameter_words(names: list[str], max_owners: int = 8) -> str:
    """Internal parameter names in the user's words, grouped by image, point or strip.

    ``["img24.Z0", "img24.omega", "p7.X", "strip3.height.tilt across the strip"]`` →
    ``"image img24 (Z0, ω), point p7 (X), strip 3 (tilt across the strip)"``: the ids
    are the user's own; the suffixes name what of it is meant. Names of another form
    are kept as they are.

    Parameters
    ----------
    names : list of str
        Parameter names ``"<image id>.<X0|…|kappa>"``, ``"<point id>.<X|Y|Z>"``,
        ``"strip<strip number>.<part>.<term in words>"`` or other.
    max_owners : int
        At most this many images/points/strips are listed, then "and N more".

    Returns
    -------
    str
    """
    groups: dict[tuple[str, str], list[str]] = {}
    for name in names:
        owner, dot, part = str(name).rpartition(".")
        if dot and part in _IMAGE_PARTS:
            groups.setdefault(("image", owner), []).append(_IMAGE_PARTS[part])
        elif dot and part in _POINT_PARTS:
            groups.setdefault(("point", owner), []).append(part)
        elif owner.startswith("strip") and "." in owner:
            strip = owner.partition(".")[0]
            groups.setdefault(("strip", strip[len("strip") :]), []).append(part)
        else:
            groups.setdefault(("", str(name)), [])
    words = []
    for (kind, owner), parts in list(groups.items())[:max_owners]:
        head = f"{kind} {owner}" if kind else owner
        words.append(f"{head} ({', '.join(dict.fromkeys(parts))})" if parts else head)
    if len(groups) > max_owners:
        words.append(f"and {len(groups) - max_owners} more")
    return ", ".join(words)
