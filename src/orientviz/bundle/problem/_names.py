"""The names of a bundle's parameters, in the order of ``x``."""

from __future__ import annotations

from collections.abc import Sequence

EXTERIOR_NAMES = ("X0", "Y0", "Z0", "omega", "phi", "kappa")


class ParameterNames(Sequence):
    """The names of a bundle's parameters, a sequence of str formed when first read.

    ``"<image id>.<X0|Y0|Z0|omega|phi|kappa>"`` per image, ``"<point id>.<X|Y|Z>"`` per
    point, then the additional parameters' names: the order of ``x``. A bundle needs
    them only for a message or when a result's names are read. Compares equal to a list of the same
    names; slices are lists.
    """

    def __init__(self, image_ids, point_ids, extra) -> None:
        self._parts = (image_ids, point_ids, extra)
        self._n = 6 * len(image_ids) + 3 * len(point_ids) + len(extra)
        self._items: list[str] | None = None

    def _list(self) -> list[str]:
        if self._items is None:
            image_ids, point_ids, extra = self._parts
            out = [f"{i}.{n}" for i in image_ids for n in EXTERIOR_NAMES]
            out += [f"{i}.{c}" for i in point_ids for c in ("X", "Y", "Z")]
            self._items = out + list(extra)
        return self._items

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, i):
        return self._list()[i]

    def __iter__(self):
        return iter(self._list())

    def __contains__(self, name) -> bool:
        return name in self._list()

    def index(self, name, *args) -> int:
        return self._list().index(name, *args)

    def __eq__(self, other) -> bool:
        if isinstance(other, (ParameterNames, list, tuple)):
            return self._list() == list(other)
        return NotImplemented

    __hash__ = None  # like a list

    def __add__(self, other) -> list[str]:
        return self._list() + list(other)

    def __radd__(self, other) -> list[str]:
        return list(other) + self._list()

    def __repr__(self) -> str:
        return repr(self._list())
