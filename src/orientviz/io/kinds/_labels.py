"""The labels of a block adjustment's observations, each formed when it is read.

A block of 10⁵ image points has 2·10⁵ labels ``image/point/x``; a report reads a few
of them (the flagged and the largest residuals), so :class:`ObservationLabels` keeps the
ids and forms a label on access. The labels of the other observations (control
coordinates, observed orientations, additional parameters, auxiliary rows) are few and
are kept as strings.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import overload

import numpy as np
from numpy.typing import NDArray


class ObservationLabels(Sequence):
    """A read-only sequence of labels: ``image/point/x`` (``/y``) for the image
    observations (the first ``2 · len(image)`` places), the given strings elsewhere,
    ``observation no. k`` (1-based) where a place has no label.

    Parameters
    ----------
    image_ids, point_ids : sequence of str
        Ids of the block's images and points.
    image, point : ndarray of int, shape (n_obs,)
        Image and point of each image observation.
    rest : list of str or None, shape (n,)
        The label of each place; None: the image observation's label there.
    """

    def __init__(
        self,
        image_ids: Sequence[str],
        point_ids: Sequence[str],
        image: NDArray[np.int64],
        point: NDArray[np.int64],
        rest: list[str | None],
    ) -> None:
        self._im, self._pt = list(image_ids), list(point_ids)
        self._image, self._point = np.array(image), np.array(point)
        self._rest = rest

    def __len__(self) -> int:
        return len(self._rest)

    def _label(self, j: int) -> str:
        lab = self._rest[j]
        if lab is None:
            o = j // 2
            return f"{self._im[self._image[o]]}/{self._pt[self._point[o]]}/{'xy'[j % 2]}"
        return lab or f"observation no. {j + 1}"

    @overload
    def __getitem__(self, j: int) -> str: ...

    @overload
    def __getitem__(self, j: slice) -> list[str]: ...

    def __getitem__(self, j):
        if isinstance(j, slice):
            return [self._label(k) for k in range(*j.indices(len(self._rest)))]
        n = len(self._rest)
        k = int(j)
        if k < 0:
            k += n
        if not 0 <= k < n:
            raise IndexError("observation label index out of range")
        return self._label(k)

    def __iter__(self) -> Iterator[str]:
        return (self._label(k) for k in range(len(self._rest)))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (ObservationLabels, list, tuple)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"ObservationLabels({len(self)} labels)"
