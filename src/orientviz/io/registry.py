"""The registry of problem kinds: how a kind is read, written and solved.

A *kind* (``"block"``, ``"similarity"``, …) is one module ``orientviz/io/kinds/<kind>.py``
that calls :func:`register_kind` at import time, plus a schema
``orientviz/io/schema/<kind>.json``. :func:`get_kind` imports the module on first use, so
adding a kind needs no edit anywhere else. See book/api/contracts.md, "Problem files".
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from . import kinds

if TYPE_CHECKING:  # pragma: no cover
    from .problem import Problem, Units
    from .solution import Solution


@dataclass(frozen=True)
class Kind:
    """How one kind of problem file is handled.

    Attributes
    ----------
    name : str
        The ``kind`` string in the file.
    schema : str
        File name of its JSON Schema in ``orientviz/io/schema`` (Draft 2020-12).
    load : callable
        ``load(doc, units, source) -> data``: the schema-validated document → the
        kind's data object in internal units (m, mm, rad). Raises :class:`InputError`
        naming the place for what a schema cannot check (ids, counts, geometry).
    dump : callable
        ``dump(data, units, columnar) -> dict``: the kind's data → the body of the
        document (everything except ``format``, ``kind``, ``units``, ``sequence``,
        ``name``, ``description``, ``options``) in the file's units.
    solve : callable or None
        ``solve(problem, method) -> Solution``; None if the kind cannot be solved (yet).
    description : str
        One line for ``list_kinds()``.
    methods : tuple of str
        Values of ``--method`` the kind accepts (the first is the default).
    """

    name: str
    schema: str
    load: Callable[[dict[str, Any], Units, str], Any]
    dump: Callable[[Any, Units, bool], dict[str, Any]]
    solve: Callable[[Problem, str | None], Solution] | None = None
    description: str = ""
    methods: tuple[str, ...] = field(default=())


_KINDS: dict[str, Kind] = {}


def register_kind(kind: Kind) -> Kind:
    """Register (or replace) a kind; call this at the bottom of ``io/kinds/<kind>.py``."""
    _KINDS[kind.name] = kind
    return kind


def available_kinds() -> list[str]:
    """Names of all kinds shipped in ``orientviz.io.kinds`` (imports nothing heavy)."""
    names = {m.name for m in pkgutil.iter_modules(kinds.__path__) if not m.name.startswith("_")}
    return sorted(names | set(_KINDS))


def get_kind(name: str, source: str | None = None) -> Kind:
    """The :class:`Kind` called ``name``, importing ``orientviz.io.kinds.<name>`` if needed.

    Raises
    ------
    InputError
        ``"unknown kind 'x' (known: block, intersection, …)"``.
    """
    if name not in _KINDS and isinstance(name, str) and name.isidentifier():
        if name in available_kinds():
            importlib.import_module(f"orientviz.io.kinds.{name}")
    if name not in _KINDS:
        known = ", ".join(available_kinds())
        raise InputError(f"unknown kind {name!r} (known: {known})", source, "kind")
    return _KINDS[name]
