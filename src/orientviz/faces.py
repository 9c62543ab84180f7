"""Package faces whose names are loaded on first use (PEP 562's module ``__getattr__``).

A package's ``__init__.py`` lists which module holds each public name; the module is
imported only when the name is first asked for, so importing the package stays cheap
(``import orientviz`` loads no NumPy; ``orientviz import-bal`` never loads the solver).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_names(
    package: str, where: dict[str, str], namespace: dict[str, Any]
) -> Callable[[str], Any]:
    """The ``__getattr__`` of a package whose names load on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    where : dict
        Public name → the module holding it, relative to the package (``".loop"``).
    namespace : dict
        The package's ``globals()``: a name once loaded is kept there, so later look-ups
        no longer reach ``__getattr__``.

    Returns
    -------
    callable
        ``__getattr__(name)``: the name's value, or ``AttributeError`` for a name not in
        ``where``.
    """

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value

    return __getattr__
