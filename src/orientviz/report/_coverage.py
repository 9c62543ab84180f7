"""Which images' points cover too little of the format: the warning's test without Qhull.

The report's warning names the images whose points' convex hull covers less than a
share of the image format (:func:`orientviz.report._stats.image_coverage`, SciPy's
Qhull). :func:`coverage_below` answers the same question and gives the same printed
values while computing few hulls and, mostly, none with Qhull (so a command need not
import scipy.spatial):

1. an octagon inside each image's hull (the points farthest in eight directions, 45°
   apart) clears the images whose octagon already covers more than the threshold;
2. the points' bounding box, which holds the hull, puts below the threshold the images
   whose box already covers less (their hull is computed only if its value is printed);
3. the others get their hull by Andrew's monotone chain on the points outside the
   octagon (the points inside it are not hull vertices) and its shoelace area;
4. an image whose hull area is within the two areas' rounding (1e-9 relative, more for
   points far from the origin) of the threshold, whose value in percent could print
   otherwise at the warning's digits, or whose points (nearly) lie on a line, is left to
   Qhull.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ._stats import F64, image_coverage

#: Support directions of the inscribed octagon, in counter-clockwise order of their
#: angle (180°, 225°, …, 135°): its vertices follow the hull in that order.
_OCTAGON = np.array([[-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0], [1, 1], [0, 1], [-1, 1]], float)

#: Relative distance from the threshold, and from a rounding boundary of the printed
#: value, below which Qhull decides (both areas agree to ~1e-15 relative for points
#: about the principal point).
MARGIN: float = 1e-9


def _octagons(xy: F64, first: NDArray[np.int64], count: NDArray[np.int64]) -> F64:
    """The octagon's vertices (k, 8, 2) of each of the k runs of points (``first``,
    ``count`` > 0): the first point farthest in each of :data:`_OCTAGON`'s directions."""
    proj = xy @ _OCTAGON.T  # (n, 8): the points' extent in each direction
    vert = np.empty((first.size, 8, 2))
    for d in range(8):
        best = np.maximum.reduceat(proj[:, d], first)
        at = np.flatnonzero(proj[:, d] == np.repeat(best, count))
        vert[:, d] = xy[at[np.searchsorted(at, first)]]  # the first point at its maximum
    return vert


def _shoelace(x: F64, y: F64) -> F64:
    """Signed area of polygons given by their vertices along the last axis."""
    return 0.5 * (x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y).sum(axis=-1)


def _chain(points: list) -> list:
    """One half of Andrew's monotone chain: the points (sorted) that turn left."""
    out: list = []
    for p in points:
        px, py = p
        while len(out) >= 2:
            (ax, ay), (bx, by) = out[-2], out[-1]
            if (bx - ax) * (py - ay) - (by - ay) * (px - ax) > 0:
                break
            out.pop()
        out.append(p)
    return out


def hull_area(xy: F64, octagon: F64) -> float:
    """Area of the convex hull of the points ``xy`` (n, 2), with ``octagon`` (8, 2) their
    inscribed octagon: Andrew's monotone chain on the points not strictly inside it."""
    ox, oy = octagon[:, 0], octagon[:, 1]
    ex, ey = np.roll(ox, -1) - ox, np.roll(oy, -1) - oy  # edges, counter-clockwise
    side = ex[None, :] * (xy[:, 1:2] - oy[None, :]) - ey[None, :] * (xy[:, 0:1] - ox[None, :])
    real = (ex != 0) | (ey != 0)  # an edge between two coinciding vertices says nothing
    inside = np.all((side > 0) | ~real[None, :], axis=1) & real.any()
    cand = np.concatenate([xy[~inside], octagon])
    cand = cand[np.lexsort((cand[:, 1], cand[:, 0]))].tolist()  # by x, then y
    lower, upper = _chain(cand), _chain(cand[::-1])
    hull = np.array(lower[:-1] + upper[:-1])
    if len(hull) < 3:
        return 0.0
    hull -= hull[0]  # about a vertex: no digits lost to coordinates far from the origin
    return float(_shoelace(hull[:, 0], hull[:, 1]))


def _coverage(pts: F64, octagon: F64, fmt_area: float, threshold: float, digits: int):
    """The coverage of one image from its points' hull (:func:`hull_area`), and whether
    Qhull must give it instead (points (nearly) on a line, a value within rounding of
    the threshold or of a change of its printed digits); NaN when it must."""
    a = hull_area(pts, octagon)
    extent = np.ptp(pts, axis=0)
    if not a > MARGIN * float(extent[0] * extent[1]):  # (nearly) on a line
        return np.nan, True
    # Qhull's rounding grows with the squared distance of the points from the origin
    # over the area: the margin does too
    tol = MARGIN + 1e-13 * float(np.max(np.sum(pts * pts, axis=1))) / a
    c = a / fmt_area
    shown = {f"{100 * c * f:.{digits}g}" for f in (1 - tol, 1 + tol)}
    return c, bool(abs(c - threshold) <= tol * threshold or len(shown) > 1)


def coverage_below(
    block: Block,
    threshold: float,
    digits: int = 3,
    *,
    first: int | None = None,
    among: NDArray[np.bool_] | None = None,
) -> tuple[NDArray[np.bool_], F64]:
    """Which images' :func:`~orientviz.report._stats.image_coverage` is below ``threshold``.

    Parameters
    ----------
    block : Block
    threshold : float
        Share of the format area (0…1).
    digits : int
        Significant digits of the coverage in percent as the warning prints it.
    first : int, optional
        Give the coverage of only the first ``first`` images below the threshold (in
        image order) among ``among``: the values a message prints. Default: of every
        image below.
    among : ndarray of bool, shape (m,), optional
        The images ``first`` counts (default: all).

    Returns
    -------
    below : ndarray of bool, shape (m,)
        ``image_coverage(block) < threshold``, exactly.
    coverage : ndarray, shape (m,)
        The coverage where it was computed (every image below, or the ``first`` of
        them), within 1e-9 relative of ``image_coverage`` and printed in percent with
        ``digits`` significant digits the same; NaN for the images the octagon cleared
        and for those below whose value was not asked for.
    """
    obs = block.observations
    m = block.n_images
    fmt_area = np.prod(block.cameras.format_mm[block.images.camera], axis=1)
    img, xy = obs.image, obs.xy
    ok = np.all(np.isfinite(xy), axis=1)
    if not ok.all():
        img, xy = img[ok], xy[ok]
    if np.any(img[1:] < img[:-1]):  # by image (stable: the points' order within an image)
        order = np.argsort(img, kind="stable")
        img, xy = img[order], xy[order]
    starts = np.searchsorted(img, np.arange(m + 1))
    count = np.diff(starts)
    seen = np.flatnonzero(count > 0)
    octagon = np.zeros((m, 8, 2))
    area, box, far = np.zeros(m), np.zeros(m), np.zeros(m)
    if seen.size:
        octagon[seen] = _octagons(xy, starts[seen], count[seen])
        area[seen] = _shoelace(octagon[seen, :, 0], octagon[seen, :, 1])
        # the octagon's vertices are the points of least and largest x and y
        ext = octagon[seen].max(axis=1) - octagon[seen].min(axis=1)
        box[seen] = ext[:, 0] * ext[:, 1]
        far[seen] = np.maximum.reduceat(np.sum(xy * xy, axis=1), starts[seen])
    cov = np.full(m, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        usable = (count >= 3) & (fmt_area > 0)
        cov[~usable] = 0.0  # as image_coverage: no hull of fewer than 3 points
        todo = usable & ~(area / fmt_area > threshold * (1.0 + MARGIN))
        # the box holds the hull: below when the box is, beyond Qhull's rounding of the
        # hull's area (_coverage's margin with the octagon's area, which is smaller)
        tol = MARGIN + 1e-13 * far / area
        boxed = todo & (box / fmt_area < threshold * (1.0 - tol))

    def hulls(images: NDArray[np.bool_]) -> None:  # their coverage into cov, Qhull's where due
        qhull = np.zeros(m, bool)
        for i in np.flatnonzero(images):
            pts = xy[starts[i] : starts[i + 1]]
            cov[i], qhull[i] = _coverage(pts, octagon[i], fmt_area[i], threshold, digits)
        if qhull.any():
            cov[qhull] = image_coverage(block, qhull)[qhull]

    hulls(todo & ~boxed)
    below = boxed | (np.isfinite(cov) & (cov < threshold))
    asked = boxed
    if first is not None:  # the values printed: of the first images below
        listed = np.zeros(m, bool)
        listed[np.flatnonzero(below if among is None else below & among)[:first]] = True
        asked = boxed & listed
    hulls(asked)
    return below, cov
