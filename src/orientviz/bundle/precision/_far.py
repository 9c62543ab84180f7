"""Points near infinity in the precision: placed where their depth is defined.

A point whose rays meet at less than :data:`HELD_PARALLAX` (rad) has no determined depth:
its normal block V has an eigenvalue along the mean ray that is zero to rounding, and the
reduced system S = U − Σ W V⁻¹ Wᵀ formed with it is not positive definite in floating
point (its Cholesky fails, or its cofactors carry the noise of V⁻¹). For the precision
such a point is moved along its mean ray to the distance at which its rays meet at
:data:`PLACED_PARALLAX` (its rays' directions, and so what they tell about the images'
rotations, are kept; its depth becomes weakly determined instead of undetermined), and
the rays' Jacobians are taken there. The images', the cameras' and the other points'
cofactors and every ray's redundancy number are then finite; what the placed depth adds
to them is of the order of the images' base over that distance. The point's own
cofactors and its rays' point gains are reported as NaN (its depth is not determined).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Rays of a point meeting at less than this angle (rad): the point is near infinity for
#: the precision (the loop's own limit, ``bundle.loop.FAR_PARALLAX``).
HELD_PARALLAX: float = 1e-5


def row_norms(v: F64) -> F64:
    """Euclidean norms of the rows of ``v`` (n, 3): the additions of
    ``np.linalg.norm(v, axis=1)`` in its order, without its generic reduction."""
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1] + v[:, 2] * v[:, 2])


def rays_about_their_mean(point: I64, d: F64, n_points: int) -> tuple[F64, F64, F64]:
    """Unit rays ``d`` (n, 3) of points ``point`` (n,) about each point's mean ray.

    Returns each point's mean direction (n_points, 3: its rays summed in their order, as
    ``np.add.at`` adds them, and normalised), that mean at each ray (n, 3), and each ray's
    cross product d × mean (n, 3), whose norm is the sine of the ray's angle to the mean
    (accurate for tiny angles, where the arccos of a dot product is not).
    """
    mean = np.stack([np.bincount(point, d[:, c], n_points) for c in range(3)], axis=1)
    mean /= row_norms(mean)[:, None]
    m = mean[point]
    cross = np.empty_like(d)
    cross[:, 0] = d[:, 1] * m[:, 2] - d[:, 2] * m[:, 1]
    cross[:, 1] = d[:, 2] * m[:, 0] - d[:, 0] * m[:, 2]
    cross[:, 2] = d[:, 0] * m[:, 1] - d[:, 1] * m[:, 0]
    return mean, m, cross


def far_columns(prob, st) -> tuple[I64, F64]:
    """Columns of the point unknowns whose rays meet at less than :data:`HELD_PARALLAX`
    (the largest angle between a ray and the point's mean ray direction), not weighted
    by a coordinate observation, with at least two rays; and their mean ray directions
    (unit vectors, (far, 3))."""
    vo = prob.obs.var_rays
    col = prob.obs.column[vo]
    p_var = prob.points.n
    if not col.size:
        return np.zeros(0, np.int64), np.zeros((0, 3))
    d = st.xyz[prob.points.unknown[col]] - st.X0[prob.obs.image[vo]]
    d /= row_norms(d)[:, None]
    mean, _, cross = rays_about_their_mean(col, d, p_var)
    sin = row_norms(cross)
    par = np.zeros(p_var)
    np.maximum.at(par, col, sin)
    rays = np.bincount(col, minlength=p_var)
    free = ~np.any(prob.points.prior_w > 0, axis=1)
    cols = np.flatnonzero((par < np.sin(HELD_PARALLAX)) & (rays >= 2) & free)
    return cols, mean[cols]


#: The angle (rad) at which a point's rays meet where the precision places a point near
#: infinity (its V then has a condition number of about 1/PLACED_PARALLAX²).
PLACED_PARALLAX: float = 1e-4


def placed_state(prob, st):
    """``(st, cols)``: ``st`` with the points near infinity placed along their mean rays
    at the distance where their rays meet at :data:`PLACED_PARALLAX` (a new state; ``st``
    itself when there are none), and those points' columns."""
    cols, d = far_columns(prob, st)
    if not cols.size:
        return st, cols
    vo = prob.obs.var_rays
    col = prob.obs.column[vo]
    img = prob.obs.image[vo]
    pos = -np.ones(prob.points.n, np.int64)
    pos[cols] = np.arange(cols.size)
    sel = pos[col] >= 0
    k = pos[col[sel]]
    X0 = st.X0[img[sel]]
    centre = np.zeros((cols.size, 3))
    np.add.at(centre, k, X0)
    centre /= np.bincount(k, minlength=cols.size)[:, None]
    spread = np.zeros(cols.size)
    np.maximum.at(spread, k, np.linalg.norm(X0 - centre[k], axis=1))
    keep = spread > 0  # rays from one centre: nothing to place by
    xyz = st.xyz.copy()
    pts = prob.points.unknown[cols[keep]]
    xyz[pts] = centre[keep] + (spread[keep] / PLACED_PARALLAX)[:, None] * d[keep]
    return replace(st, xyz=xyz), cols


def mark_far(res, prob, cols: I64) -> None:
    """The far points' cofactors and their rays' point gains in ``res``: NaN (their depth
    is not determined)."""
    if not cols.size:
        return
    res.cofactor_groups["points"][prob.points.unknown[cols]] = np.nan
    vo = prob.obs.var_rays
    rays = np.arange(prob.obs.image.size)[vo][np.isin(prob.obs.column[vo], cols)]
    res.ray_gains.points[prob.obs.index[rays]] = np.nan
