"""How the viewer adjusts a block and reads an :class:`Adjustment` back into a Block.

The viewer does not hold a solver of its own. It calls
:func:`orientviz.bundle.bundle_adjust` (book/api/contracts.md, "Bundle") when that module
is installed. Until it is, and for blocks it cannot take, :func:`small_bundle` is a
plain dense bundle on the shared engine (:func:`orientviz.adjust.gauss_newton`) for the
tiny demo blocks (a few images): enough to step through iterations in the viewer.

Parameter layout (the bundle contract): block ``"exterior"`` (m, 6) with X0, Y0, Z0 in
m and ω, φ, κ in rad per image (the block's rotation sequence), block ``"points"``
(p, 3) with X, Y, Z in m.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..adjust import Adjustment, gauss_newton
from ..block import Block
from ..bundle import bundle_adjust
from ..camera import collinearity_jacobian
from ..errors import InputError

#: ``adjuster(block, max_iter) -> Adjustment``; adjusters that can skip the precision
#: also take ``precision=False`` (the viewer's quick re-solve after an action).
Adjuster = Callable[..., Adjustment]

#: :func:`small_bundle` refuses blocks with more unknowns than this (dense precision).
SMALL_LIMIT = 3000


def apply_parameters(block: Block, result: Adjustment, x: np.ndarray | None = None) -> Block:
    """Copy of ``block`` with exterior orientations and points taken from ``x``.

    Parameters
    ----------
    block : Block
        The block the adjustment was computed for.
    result : Adjustment
        Supplies the parameter layout (``blocks["exterior"]``, ``blocks["points"]``).
    x : ndarray, optional
        A parameter vector in that layout (default ``result.x``), e.g. a history record.
    """
    x = result.x if x is None else np.asarray(x, dtype=float)
    out = block.copy()
    m, p = block.n_images, block.n_points
    if "exterior" in result.groups:
        ext = x[result.groups["exterior"]].reshape(m, 6)
        out.images.X0 = ext[:, :3].copy()
        out.images.angles = ext[:, 3:].copy()
    if "points" in result.groups:
        out.points.xyz = x[result.groups["points"]].reshape(p, 3).copy()
    return out


def small_bundle(block: Block, max_iter: int = 20, precision: bool = True) -> Adjustment:
    """A dense collinearity bundle for small blocks (fallback for the viewer's demos).

    Control coordinates with σ = 0 are held fixed, σ > 0 enter as weighted
    pseudo-observations; tie and check points are free. Interior orientation is fixed.

    Parameters
    ----------
    block : Block
        Start values and observations (mm, m, rad).
    max_iter : int
        Maximum number of Gauss-Newton steps (1 = a single step).
    precision : bool
        Accepted for the adjuster protocol; the dense precision is always computed.

    Returns
    -------
    Adjustment
        Blocks ``"exterior"`` and ``"points"``; residuals ordered x, y per observation
        (2n), then the control pseudo-observations.
    """
    m, p, n = block.n_images, block.n_points, block.n_observations
    u = 6 * m + 3 * p
    if u > SMALL_LIMIT:
        raise InputError(f"small_bundle: {u} unknowns is too many for the viewer's fallback")
    obs, pts, cam = block.observations, block.points, block.cameras
    ci = block.images.camera[obs.image]
    given = (pts.role == 1)[:, None] & np.isfinite(pts.xyz_known) & np.isfinite(pts.sigma)
    fixed_pt = given & (pts.sigma == 0)
    weighted = np.argwhere(given & (pts.sigma > 0))
    fixed = np.zeros(u, bool)
    fixed[6 * m :] = fixed_pt.reshape(-1)
    x0 = np.concatenate(
        [np.hstack([block.images.X0, block.images.angles]).ravel(), pts.xyz.ravel()]
    )
    x0[6 * m :][fixed_pt.reshape(-1)] = pts.xyz_known[fixed_pt]
    l = np.concatenate([obs.xy.ravel(), pts.xyz_known[weighted[:, 0], weighted[:, 1]]])
    sig = np.concatenate([obs.sigma.ravel(), pts.sigma[weighted[:, 0], weighted[:, 1]]])
    rows = np.arange(2 * n).reshape(n, 2)

    def equations(x: np.ndarray):
        ext = x[: 6 * m].reshape(m, 6)
        xyz = x[6 * m :].reshape(p, 3)
        e = ext[obs.image]
        xy, Je, Jp, _ = collinearity_jacobian(
            xyz[obs.point], e[:, :3], e[:, 3:], cam.c[ci], cam.x0[ci], cam.y0[ci], block.sequence
        )
        r_e = np.repeat(rows, 6, axis=1)
        c_e = (6 * obs.image[:, None] + np.arange(6))[:, None, :].repeat(2, axis=1)
        r_p = np.repeat(rows, 3, axis=1)
        c_p = (6 * m + 3 * obs.point[:, None] + np.arange(3))[:, None, :].repeat(2, axis=1)
        k = weighted.shape[0]
        r_w = 2 * n + np.arange(k)
        c_w = 6 * m + 3 * weighted[:, 0] + weighted[:, 1]
        J = sp.csr_matrix(
            (
                np.concatenate([Je.ravel(), Jp.ravel(), np.ones(k)]),
                (
                    np.concatenate([r_e.ravel(), r_p.ravel(), r_w]),
                    np.concatenate([c_e.ravel(), c_p.ravel(), c_w]),
                ),
            ),
            shape=(2 * n + k, u),
        )
        f = np.concatenate([xy.ravel(), xyz[weighted[:, 0], weighted[:, 1]]])
        return f, J

    names = [
        f"{i}.{q}" for i in block.images.ids for q in ("X0", "Y0", "Z0", "omega", "phi", "kappa")
    ]
    names += [f"{i}.{q}" for i in pts.ids for q in ("X", "Y", "Z")]
    labels = [
        f"{block.images.ids[i]}/{pts.ids[j]}/{a}"
        for i, j in zip(obs.image, obs.point)
        for a in "xy"
    ]
    labels += [f"{pts.ids[i]}/{'XYZ'[j]}" for i, j in weighted]
    return gauss_newton(
        equations,
        x0,
        l,
        sig,
        names=names,
        groups={"exterior": slice(0, 6 * m), "points": slice(6 * m, u)},
        obs_labels=labels,
        fixed=fixed,
        max_iter=max_iter,
        context="viewer bundle",
    )


def default_adjuster() -> Adjuster:
    """The bundle to use: :func:`orientviz.bundle.bundle_adjust`."""

    def adjust(block: Block, max_iter: int, precision: bool = True) -> Adjustment:
        return bundle_adjust(block, max_iter=max_iter, history_x=True, precision=precision)

    return adjust


def image_normalized_residuals(result: Adjustment | None, n: int) -> np.ndarray | None:
    """Normalised residuals (n, 2) of the n image observations, or None if not available.

    Assumes the contract's order: the first 2n residuals are x, y of observation 0, 1, ….
    """
    if result is None or result.normalized_residuals is None:
        return None
    w = np.asarray(result.normalized_residuals)
    if w.shape[0] < 2 * n:
        return None
    return w[: 2 * n].reshape(n, 2)
