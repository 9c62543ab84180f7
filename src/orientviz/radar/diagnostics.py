"""Weak geometry of radar pairs and adjustments, said in words and numbers.

Geier (1973): a homologous pair gives a poor condition when the azimuth planes ε1 and
ε2 are (nearly) parallel, or when their line of intersection touches a range sphere.
:func:`pair_geometry` measures both per point; :func:`weakest_direction` names the
parameter combination an adjustment determines worst (the eigenvector of the smallest
eigenvalue of the scaled normal matrix), which is what turns into a
:class:`~orientviz.errors.NotDeterminableError` once it vanishes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment
from .pair import circle_sphere_candidates
from .ppi import RadarImage, check_image_points, plane_normal, sphere_radius

F64 = NDArray[np.float64]

#: Below this angle (rad) between ε1 and ε2 a point counts as weak (≈ 0.6 gon).
PARALLEL_LIMIT: float = 0.01
#: Below this abs(cos) between the ε-line and a station ray the line counts as tangent.
TANGENT_LIMIT: float = 0.02


@dataclass
class PairGeometry:
    """Per-point geometry of a homologous pair (arrays of shape (n,)).

    Attributes
    ----------
    plane_angle : ndarray
        Angle between the planes ε1 and ε2 in rad (0 = parallel: no condition).
    tangency1, tangency2 : ndarray
        abs(cos) of the angle between the line ε1 ∩ ε2 and the ray from station 1 (2) to
        the point; 0 means the line touches that range sphere.
    circle_misses : ndarray of bool
        Image 1's projection circle does not reach image 2's range sphere (the closed-form
        intersection is imaginary).
    weak : ndarray of bool
        Any of the above beyond :data:`PARALLEL_LIMIT` / :data:`TANGENT_LIMIT`.
    """

    plane_angle: F64
    tangency1: F64
    tangency2: F64
    circle_misses: NDArray[np.bool_]
    weak: NDArray[np.bool_]

    def summary(self) -> str:
        """One line: how many points are weak and why."""
        n = len(self.weak)
        par = int((self.plane_angle < PARALLEL_LIMIT).sum())
        tan = int(((self.tangency1 < TANGENT_LIMIT) | (self.tangency2 < TANGENT_LIMIT)).sum())
        return (
            f"{int(self.weak.sum())} of {n} pairs weak: {par} with nearly parallel planes "
            f"(< {PARALLEL_LIMIT} rad), {tan} with the plane line nearly tangent to a sphere, "
            f"{int(self.circle_misses.sum())} circles missing the other sphere"
        )


def pair_geometry(
    xy1: ArrayLike, image1: RadarImage, xy2: ArrayLike, image2: RadarImage, points: ArrayLike
) -> PairGeometry:
    """Measure the strength of each homologous pair's condition.

    Parameters
    ----------
    xy1, xy2 : array_like, shape (n, 2)
        Image coordinates in m.
    image1, image2 : RadarImage
        Orientations (true or approximate).
    points : array_like, shape (n, 3)
        The object points (e.g. from :func:`~orientviz.radar.pair.intersect`), m.
    """
    L1, L2 = check_image_points(xy1), check_image_points(xy2)
    P = np.asarray(points, float)
    n1, n2 = plane_normal(L1, image1), plane_normal(L2, image2)
    line = np.cross(n1, n2)
    s = np.linalg.norm(line, axis=1)
    angle = np.arcsin(np.clip(s, 0.0, 1.0))
    dirn = line / np.where(s > 0, s, 1.0)[:, None]

    def tang(X0):
        ray = P - np.asarray(X0, float)
        ray = ray / np.linalg.norm(ray, axis=1)[:, None]
        return np.abs(np.einsum("ij,ij->i", dirn, ray))

    t1, t2 = tang(image1.X0), tang(image2.X0)
    lo, _ = circle_sphere_candidates(L1, image1, sphere_radius(L2, image2), image2.X0)
    miss = ~np.all(np.isfinite(lo), axis=1)
    weak = (angle < PARALLEL_LIMIT) | (t1 < TANGENT_LIMIT) | (t2 < TANGENT_LIMIT) | miss
    return PairGeometry(angle, t1, t2, miss, weak)


def weakest_direction(
    result: Adjustment, k: int = 4, block: str | None = None
) -> tuple[float, list[tuple[str, float]]]:
    """The worst-determined parameter combination of an adjustment.

    Parameters
    ----------
    result : Adjustment
        With a dense cofactor matrix.
    k : int
        How many parameters to name.
    block : str, optional
        Restrict to one parameter block (e.g. ``"image2"`` of a relative orientation).

    Returns
    -------
    condition : float
        Condition number of the correlation matrix (1 = independent; ≥ 1e12 counts as
        singular in the engine).
    involved : list of (name, share)
        The parameters with the largest share (0-1) of that direction, largest first.
    """
    C = result.correlations()
    names = list(result.names)
    if block is not None:
        sl = result.groups[block]
        C, names = C[sl, sl], names[sl]
    w, V = np.linalg.eigh(C)
    cond = float(w[-1] / max(w[0], 1e-300))
    share = V[:, 0] ** 2
    order = np.argsort(-share)[:k]
    return cond, [(names[i], float(share[i])) for i in order]
