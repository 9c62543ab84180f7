"""Automatic data cleaning of image blocks: the bundle as a solver for :mod:`adjust.gross`.

Ackermann (1974, §13) reports that a block had to be adjusted 3 to 6 times (or more)
until manual data cleaning had removed all gross errors, and asks for automatic
cleaning. :func:`clean_block` does it in one run: it gives the bundle
(:func:`orientviz.bundle.bundle_adjust`) to the generic methods of
:mod:`orientviz.adjust.gross` — data snooping, robust reweighting (Danish, Huber) or the
rerun model of manual practice — and eliminates whole image rays (both coordinates of an
observation) at a time.

Observations of the solver are the 2n image coordinates of the block (x, y of each
observation, interleaved, mm); a ray is eliminated by leaving it out of the block and
down-weighted by dividing its σ by √w. A tie point left with fewer than two rays is
left out too (it carries no redundancy). Each adjustment starts from the previous
solution (warm start), so that the repeated adjustments of data snooping take one or
two Gauss-Newton steps each.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

from ..adjust.gross import Cleaning
from ..adjust.gross2d import statistic_2d
from ..adjust.result import Adjustment
from ..adjust.robust import rerun_cleaning, robust_adjust
from ..adjust.snooping import data_snooping
from ..block import CHECK, CONTROL, Block
from ..camera import project
from ..errors import InputError
from ..rotation import matrix_from_opk
from ._result import RaySubset
from .loop._adjust import bundle_adjust
from .model._kernel import collinearity_block
from .reduced import inv3

F64 = NDArray[np.float64]

__all__ = ["bundle_solver", "clean_block", "cleaned_block", "ray_labels"]

METHODS = ("snooping", "danish", "huber", "reruns")
#: Default margin (χ² units) below which two rejected rays of one point are not separable.
SEPARATION: float = 2.0
#: Fast data snooping: after a round that eliminated fewer rays than this fraction of
#: the largest round, the next adjustment is exact (see ``data_snooping``).
EXACT_WHEN_FEW: float = 0.01
#: Fast data snooping on blocks of at least this many images: first adjustment exact,
#: screening sharpened with its redundancy blocks, next round exact when few went (see
#: ``clean_block``). Smaller blocks keep the plain point-local screening: their exact
#: rounds cost little, and in weak blocks (Gruber points only) the sharper screening
#: raised the false alarms of the w-test and the worst check-point ratio (bench_gross).
SHARP_SCREENING_MIN_IMAGES: int = 500


def ray_labels(block: Block) -> list[str]:
    """``"image/point"`` id of every observation (ray)."""
    o = block.observations
    return [f"{block.images.ids[i]}/{block.points.ids[p]}" for i, p in zip(o.image, o.point)]


def _subset(
    block: Block, keep: NDArray[np.bool_], sigma: F64
) -> tuple[Block, NDArray[np.bool_], NDArray[np.int64]]:
    """The block with only the kept rays and the points they still determine.

    Tie and check points left with fewer than two rays lose their last ray and leave the
    block, control points with no ray leave it. Returns the sub-block, the kept-ray mask
    and the indices (into ``block.points``) of the points kept.
    """
    o = block.observations
    keep = keep.copy()
    rays = np.bincount(o.point[keep], minlength=block.n_points)
    lonely = (rays < 2) & (block.points.role != CONTROL)
    keep &= ~lonely[o.point]
    rays = np.bincount(o.point[keep], minlength=block.n_points)
    pts = np.flatnonzero(rays > 0)
    sub = block.take(points=pts, observations=np.flatnonzero(keep))
    sub.observations.sigma = sigma[keep]
    return sub, keep, pts


def _local_redundancy(sub, adj, idx, v, sigma, rn, wn, rxy, rays) -> None:
    """Redundancy blocks and normalised residuals of rays in their point's intersection.

    For each point, ``P½Q_vvP½ = I − J̃(J̃ᵀJ̃)⁻¹J̃ᵀ`` of its forward intersection with
    the adjusted orientations held fixed (J̃: weighted Jacobian of the image coordinates
    by the point's X, Y, Z; fixed control points: R = I). For adjusted points this is an
    upper bound of the exact redundancy numbers (fixing the orientations adds
    redundancy), i.e. abs(w) is not overestimated. Arrays are filled in place (rows of
    the full block; ``idx`` maps sub-block rays to them); ``rays`` selects sub-block rays.
    """
    o = sub.observations
    sel = np.flatnonzero(rays)
    if sel.size == 0:
        return
    _, Jp = _ray_jacobians(sub, adj, sel)
    Jw = Jp / sigma[idx[sel]][:, :, None]
    Jw[sub.points.role[o.point[sel]] == CONTROL] = 0.0
    col = o.point[sel]
    JtJ = (Jw.transpose(0, 2, 1) @ Jw).reshape(-1, 9)
    N = np.stack([np.bincount(col, JtJ[:, k], sub.n_points) for k in range(9)], 1)
    N = N.reshape(-1, 3, 3)
    # condition bound of a symmetric positive semi-definite 3×3 matrix without an SVD:
    # λmax ≤ tr, λmin ≥ det / (λmax λmid) ≥ 4 det / tr², so cond ≤ tr³ / (4 det)
    tr = np.einsum("nii->n", N)
    a, b, c, d, e, f = (N[:, i, j] for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))
    det = a * (d * f - e * e) - b * (b * f - c * e) + c * (b * e - c * d)
    ok = (det > 0) & (tr**3 < 4e12 * det)
    Ninv = np.zeros_like(N)
    Ninv[ok] = inv3(N[ok])
    R = np.eye(2) - Jw @ Ninv[col] @ Jw.transpose(0, 2, 1)  # (k, 2, 2)
    rows = idx[sel]
    rn[rows] = np.clip(np.stack([R[:, 0, 0], R[:, 1, 1]], 1), 0.0, 1.0)
    rxy[rows] = R[:, 0, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        wn[rows] = np.where(rn[rows] > 1e-10, v[rows] / (sigma[rows] * np.sqrt(rn[rows])), np.nan)


def _use_earlier_exact(exact, w, rows, v, sigma, rn, wn, rxy) -> None:
    """Screening statistics from the redundancy blocks of the last exact adjustment.

    Leaving observations out can only enlarge the cofactors of the unknowns, so the
    redundancy block ``R = I − P½ A Q Aᵀ P½`` of every remaining ray can only shrink
    (in the Loewner order): blocks of an earlier exact adjustment whose rays included
    the present ones (same weights for the ray, no weight larger elsewhere) are upper
    bounds of the present exact blocks, just as the point-local ones are. Each ray takes
    the one of the two bounds that gives the larger 2-D statistic (or the lower rank),
    so the screening test is never above the exact one (up to the change of the
    linearisation point) but finds most of what the exact test finds: the local bound
    misses errors where the orientations are weak. Arrays are updated in place (rows of
    the full block; ``rows``: the tested rays of the present adjustment).
    """
    if exact is None or rows.size == 0:
        return
    ex_rows, ex_rn, ex_rxy, ex_w = exact
    if np.any(w > ex_w):
        return
    pos = np.full(w.shape[0], -1)
    pos[ex_rows] = np.arange(ex_rows.size)
    rows = rows[(pos[rows] >= 0) & np.all(w[rows] == ex_w[rows], axis=1)]
    if rows.size == 0:
        return
    z = v[rows] / sigma[rows]
    r_old, c_old = ex_rn[pos[rows]], ex_rxy[pos[rows]]
    T_loc, d_loc = statistic_2d(z, rn[rows], rxy[rows])
    T_old, d_old = statistic_2d(z, r_old, c_old)
    take = (d_old < d_loc) | ((d_old == d_loc) & (T_old > T_loc))
    rows, r_old = rows[take], r_old[take]
    rn[rows] = r_old
    rxy[rows] = c_old[take]
    with np.errstate(divide="ignore", invalid="ignore"):
        wn[rows] = np.where(r_old > 1e-10, v[rows] / (sigma[rows] * np.sqrt(r_old)), np.nan)


def _check_ray_tests(sub, adj, idx, v, sigma, rn, wn, rxy, rays, pairs) -> None:
    """Test quantities of the rays of check points, with the orientations' uncertainty.

    The bundle intersects a check point afterwards from its own rays with the adjusted
    orientations, which carry errors of their own: the rays' residuals have the
    covariance ``C = diag(σ²) + J_e Q_ee J_eᵀ`` (Q_ee: cofactors of the orientations
    of the images involved *with their correlations*, a-priori σ0 = 1; a common error
    of all of them only moves the point). In that model (intersection weighted with
    C⁻¹, one linear step from the bundle's point) the 2-D test of ray a uses
    ``g = (C⁻¹v)_a`` and ``M = (C⁻¹Q_vvC⁻¹)_aa``, ``T = gᵀM⁻¹g``; they are stored scaled
    by the ray's σ (z = σ·g, R = σMσ), so that with C = diag(σ²) they are the usual
    residuals and redundancy blocks. ``pairs`` (:class:`ExteriorPairs`: sorted keys i·m + k, blocks (6, 6))
    of Q_ee for image pairs i ≤ k; pairs not listed count as uncorrelated.
    """
    o = sub.observations
    sel = np.flatnonzero(rays)
    if sel.size == 0:
        return
    keys, blocks = pairs.keys, pairs.blocks
    m = sub.n_images
    Je, Jp = _ray_jacobians(sub, adj, sel)
    for p in np.unique(o.point[sel]):
        k = np.flatnonzero(o.point[sel] == p)
        if k.size < 2:
            continue
        img = o.image[sel[k]]
        rows = idx[sel[k]]
        s = sigma[rows].reshape(-1)
        lo, hi = np.minimum.outer(img, img), np.maximum.outer(img, img)
        pos = np.clip(np.searchsorted(keys, lo * m + hi), 0, keys.size - 1)
        known = keys[pos] == lo * m + hi
        if not known.all():
            # some image pairs share no adjusted point (their Q_ee block is not computed):
            # keep the correlations only inside groups where all are known (a principal
            # block-diagonal part of a covariance matrix is a covariance matrix again),
            # i.e. neglect those between groups — the test becomes conservative
            _, grp = connected_components(known, directed=False)
            same = grp[:, None] == grp[None, :]
            if not known[same].all():
                same = np.eye(k.size, dtype=bool)
            known &= same
        Q = np.where(known[:, :, None, None], blocks[pos], 0.0)
        Q = np.where((img[:, None] > img[None, :])[:, :, None, None], Q.swapaxes(2, 3), Q)
        E = Je[k]  # (k, 2, 6)
        C = np.einsum("aij,abjl,bml->aibm", E, Q, E).reshape(2 * k.size, 2 * k.size)
        C += np.diag(s**2)
        J = Jp[k].reshape(-1, 3)
        Ci = np.linalg.inv(C)
        N = J.T @ Ci @ J
        if np.linalg.cond(N) > 1e12:
            continue
        Ninv = np.linalg.inv(N)
        vv = v[rows].reshape(-1)
        vv = vv - J @ (Ninv @ (J.T @ Ci @ vv))
        g = Ci @ vv
        M = Ci @ (C - J @ Ninv @ J.T) @ Ci
        for a, row in enumerate(rows):
            sa = s[2 * a : 2 * a + 2]
            Ma = M[2 * a : 2 * a + 2, 2 * a : 2 * a + 2] * np.outer(sa, sa)
            za = g[2 * a : 2 * a + 2] * sa
            rn[row] = np.clip(np.diag(Ma), 0.0, 1.0)
            rxy[row] = Ma[0, 1]
            with np.errstate(divide="ignore", invalid="ignore"):
                wn[row] = np.where(rn[row] > 1e-10, za / np.sqrt(rn[row]), np.nan)


def bundle_solver(
    block: Block,
    *,
    warm_start: bool = True,
    check_rays: bool = True,
    redundancy: str = "exact",
    sharpen: bool = False,
    **bundle_options,
):
    """A solver ``solve(weights (2n,)) -> Adjustment`` over the image coordinates of a block.

    The returned Adjustment has ``residuals``, ``sigma_obs`` (a-priori σ),
    ``redundancy_numbers`` and ``normalized_residuals`` for the 2n image coordinates of
    ``block`` (x, y per observation; left-out rays: residual predicted from the adjusted
    orientation, redundancy number 0, normalised residual NaN); everything else is the
    bundle's result (``points``: all block points; ``subset``: the rays adjusted and the
    sub-block's own bundle).

    Parameters
    ----------
    block : Block
        Approximate values and observations.
    warm_start : bool
        Start each adjustment from the previous solution.
    check_rays : bool
        Also report redundancy numbers and normalised residuals for the rays of check
        points, from their forward intersection with the adjusted orientations (the way
        the bundle computes check coordinates), so that cleaning tests them too.
    redundancy : {"exact", "local"}
        Default for ``solve(weights, redundancy=None)``: ``"exact"`` redundancy blocks
        from the bundle's cofactors (:mod:`orientviz.bundle.precision._precision`), or ``"local"``:
        each point's intersection with the orientations held fixed (no precision
        computation; an upper bound of r, i.e. abs(w) is not overestimated).
    sharpen : bool
        In ``"local"`` rounds take, per ray, the sharper of the point-local redundancy
        block and the one of the last exact round (both are upper bounds of the
        present exact block; see :func:`_use_earlier_exact`).
    **bundle_options
        Passed to :func:`bundle_adjust` (``control``, ``additional``, …).
    """
    n = block.n_observations
    state = {"block": block.copy(), "warm": False}
    sig0 = block.observations.sigma.reshape(-1).copy()
    default = redundancy

    def solve(weights: F64, redundancy: str | None = None) -> Adjustment:
        mode = default if redundancy is None else redundancy
        if mode not in ("exact", "local"):
            raise InputError(f"unknown redundancy {mode!r}; expected 'exact' or 'local'")
        w = np.broadcast_to(np.asarray(weights, float), (2 * n,)).reshape(n, 2)
        # a weight below 1e-6 (σ × 1000) counts as eliminated: keeps the normals regular
        w = np.where(w < 1e-6, 0.0, w)
        keep = np.all(w > 0, axis=1)
        with np.errstate(divide="ignore"):
            sigma = np.where(w > 0, block.observations.sigma / np.sqrt(np.where(w > 0, w, 1)), 1.0)
        sub, kept, pts = _subset(state["block"], keep, sigma)
        screening = mode == "local" and state["warm"]
        opts = {**bundle_options, "max_iter": 1} if screening else bundle_options
        adj = bundle_adjust(sub, precision=mode == "exact", **opts)
        if screening and not adj.converged and len(adj.history) == 2:
            # a screening round: one Gauss-Newton step from the previous solution (a few
            # rays less) is enough to test; the exact round converges fully
            adj = replace(adj, converged=True, reason="one step from the previous solution")
        ns = sub.n_observations
        xyz = state["block"].points.xyz.copy()
        xyz[pts] = adj.points
        if warm_start and adj.converged:
            state["warm"] = True
            b = state["block"]
            b.images.X0[:] = adj.exterior[:, :3]
            b.images.angles[:] = adj.exterior[:, 3:]
            b.points.xyz[pts] = adj.points
        idx = np.flatnonzero(kept)
        v = np.full((n, 2), np.nan)
        v[idx] = adj.residuals[: 2 * ns].reshape(ns, 2)
        gone = np.flatnonzero(~kept)
        if gone.size:
            o = block.observations
            ext = adj.exterior
            cam = block.images.camera[o.image[gone]]
            R = matrix_from_opk(*ext[o.image[gone], 3:].T, block.sequence)
            f = project(
                xyz[o.point[gone]],
                ext[o.image[gone], :3],
                R,
                block.cameras.c[cam],
                block.cameras.x0[cam],
                block.cameras.y0[cam],
            )
            v[gone] = f - o.xy[gone]
        rn = np.zeros((n, 2))
        wn = np.full((n, 2), np.nan)
        rxy = np.zeros(n)
        chk = sub.points.role[sub.observations.point] == CHECK
        if mode == "local":
            _local_redundancy(sub, adj, idx, v, sigma, rn, wn, rxy, ~chk)
            if sharpen:
                _use_earlier_exact(state.get("exact"), w, idx[~chk], v, sigma, rn, wn, rxy)
        elif adj.redundancy_numbers is not None:
            rn[idx] = np.nan_to_num(adj.redundancy_numbers[: 2 * ns].reshape(ns, 2))
            wn[idx] = adj.normalized_residuals[: 2 * ns].reshape(ns, 2)
            rxy[idx] = np.nan_to_num(
                adj.redundancy_xy if adj.redundancy_xy is not None else np.zeros(ns)
            )
            state["pairs"] = adj.exterior_pairs
            rays = idx[~chk]
            state["exact"] = (rays, rn[rays].copy(), rxy[rays].copy(), w.copy())
        if check_rays and state.get("pairs") is not None:
            # check rays: tested once the orientations' precision is known (exact round)
            _check_ray_tests(sub, adj, idx, v, sigma, rn, wn, rxy, chk, state["pairs"])
        # normalised with the a-priori σ of the observation, not the down-weighted one
        wn[idx] *= sigma[idx] / block.observations.sigma[idx]
        return replace(
            adj,
            residuals=v.reshape(-1),
            sigma_obs=sig0.copy(),
            redundancy_numbers=rn.reshape(-1),
            normalized_residuals=wn.reshape(-1),
            redundancy_xy=rxy,
            points=xyz,
            subset=RaySubset(kept, pts, mode, adj),
        )

    return solve


def clean_block(
    block: Block,
    method: str = "snooping",
    *,
    alpha0: float = 0.001,
    max_fraction: float = 0.1,
    robust_c: float | None = None,
    threshold: float = 3.0,
    one_at_a_time: bool = False,
    image_cluster: bool = True,
    fast: bool = True,
    test: str = "2d",
    separation: float = SEPARATION,
    check_rays: bool = True,
    **bundle_options,
) -> Cleaning:
    """Clean a block of gross errors automatically, in one run, with a log.

    Parameters
    ----------
    block : Block
        Approximate values and (possibly corrupted) observations.
    method : {"snooping", "danish", "huber", "reruns"}
        Baarda's data snooping; robust reweighting (Danish method or Huber) followed by a
        final adjustment without the rejected rays; or the model of manual practice
        (:func:`~orientviz.adjust.robust.rerun_cleaning`).
    alpha0 : float
        Significance level of the w-test (0.1 %: k = 3.29).
    max_fraction : float
        Give up (:class:`~orientviz.adjust.gross.CleaningBreakdown`, with the log) when
        more than this fraction of the rays would have to be eliminated.
    robust_c : float, optional
        Tuning constant of the robust weight function.
    threshold : float
        Rejection threshold of the rerun model, in σ̂0.
    one_at_a_time : bool
        Data snooping strictly one ray per adjustment (Baarda). Default False: per
        adjustment every rejected ray that is the worst ray of its point and of its image
        (blunders in different points and images do not mask each other; far fewer
        adjustments).
    image_cluster : bool
        With several rays per adjustment, at most one per image (default True; without
        it a large blunder drags good rays of its image over the threshold: the false
        alarms tripled in the benchmark).
    fast : bool
        Screening rounds with the point-local redundancy numbers (orientations held
        fixed: abs(w) never overestimated, no precision computation, one Gauss-Newton
        step each) and an exact round before stopping (default True). False: every round
        exact. On blocks of ``SHARP_SCREENING_MIN_IMAGES`` (500) images or more the first
        round is exact too, the screening takes per ray the sharper of the local and the
        last exact redundancy block, and after a round that eliminated fewer than
        ``EXACT_WHEN_FEW`` (1 %) of the largest round's rays the next one is exact.
    test : {"2d", "w"}
        2-D test per image point (default) or the w-test per coordinate.
    separation : float
        Rejected rays of the same point whose 2-D statistic is within this margin of the
        worst one are eliminated with it: the data cannot tell which of them is wrong
        (default 2, i.e. a likelihood ratio below e; 0: off).
    check_rays : bool
        Test the rays of check points too, in their intersection with the adjusted
        orientations and the orientations' covariance (default True).
    **bundle_options
        Passed to :func:`bundle_adjust`.

    Returns
    -------
    Cleaning
        ``eliminated`` and the log refer to observation (ray) indices of ``block``.
    """
    if method not in METHODS:
        raise InputError(
            f"unknown cleaning method {method!r}; expected one of {', '.join(METHODS)}"
        )
    n = block.n_observations
    groups = np.repeat(np.arange(n), 2)
    labels = ray_labels(block)
    local = fast and method == "snooping"
    sharp = local and block.n_images >= SHARP_SCREENING_MIN_IMAGES
    solve = bundle_solver(
        block,
        check_rays=check_rays,
        redundancy="local" if local else "exact",
        sharpen=sharp,
        **bundle_options,
    )
    if method == "snooping":
        o = block.observations
        clusters = None if one_at_a_time else [o.point, o.image] if image_cluster else [o.point]
        return data_snooping(
            solve, 2 * n, alpha0=alpha0, groups=groups, labels=labels,
            max_fraction=max_fraction, clusters=clusters, test=test,
            separate=o.point, separation=separation,
            solve_exact=(lambda w: solve(w, "exact")) if fast else None, exact_first=sharp,
            exact_when_few=EXACT_WHEN_FEW if sharp else 0.0,
        )  # fmt: skip
    if method == "reruns":
        return rerun_cleaning(solve, 2 * n, threshold=threshold, groups=groups, labels=labels)
    return robust_adjust(
        solve, 2 * n, method=method, c=robust_c, alpha0=alpha0, groups=groups, labels=labels,
        max_fraction=max_fraction,
    )  # fmt: skip


def cleaned_block(block: Block, cleaning: Cleaning) -> Block:
    """The block without the rays a cleaning eliminated."""
    keep = np.ones(block.n_observations, bool)
    keep[cleaning.eliminated] = False
    return _subset(block, keep, block.observations.sigma)[0]


def _ray_jacobians(sub: Block, adj: Adjustment, sel: NDArray[np.int64]) -> tuple:
    """Collinearity derivatives (by orientation, by point) of rays ``sel`` at the adjusted state."""
    o = sub.observations
    ext = adj.exterior
    cam = sub.images.camera
    c, x0, y0 = (getattr(sub.cameras, k)[cam] for k in ("c", "x0", "y0"))
    _, Je, Jp = collinearity_block(
        ext[:, :3], ext[:, 3:], c, x0, y0, o.image[sel], adj.points[o.point[sel]],
        sub.sequence,
    )  # fmt: skip
    return Je, Jp
