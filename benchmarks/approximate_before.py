"""orientviz's approximate values as they were before the batched growth (commit 95a8e82).

Kept (module text of src/orientviz/block/_approximate.py at 95a8e82, relative imports
made absolute; ``intersect_rays`` and the datum step ``into_frame``, which the batched
growth did not change, used from orientviz.block) as the baseline of
``bench_approximations.py``: one least-squares resection per image in a Python loop and a
model-frame bundle after every 25 % of growth and after every poor resection. It calls
today's bundle, resection and essential-matrix code. Not used by orientviz.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from orientviz.approximate._values import into_frame
from orientviz.block._tables import CHECK, Block
from orientviz.errors import NotDeterminableError
from orientviz.orientation.intersection import intersect_rays
from orientviz.rotation import matrix_from_opk, opk_from_matrix

F64 = NDArray[np.float64]
#: The oriented part is re-adjusted (model-frame bundle) after every 25 % of growth, at
#: the latest after this many new images.
REFINE_EVERY: int = 100
#: A resection whose σ̂0 exceeds this (image residuals ≫ their a-priori σ) triggers an
#: immediate re-adjustment of the oriented part.
POOR_RESECTION: float = 5.0


def approximate_values(block: Block, *, min_points: int = 6, frame: str = "control") -> Block:
    """:func:`orientviz.approximate.approximate_values` as it was at 95a8e82 (same parameters,
    result and errors; see its docstring): one resection per image, frequent re-adjustments."""
    from orientviz.bundle import bundle_adjust
    from orientviz.orientation.essential import eight_point, select_by_cheirality
    from orientviz.orientation.resection import resection

    obs = block.observations
    use = block.points.role[obs.point] != CHECK
    oi, op, xy = obs.image[use], obs.point[use], obs.xy[use]
    m, p = block.n_images, block.n_points
    cam = block.images.camera
    c = block.cameras.c[cam]
    pp = np.column_stack([block.cameras.x0[cam], block.cameras.y0[cam]])
    xyc = xy - pp[oi]  # image coordinates relative to the principal point
    M = sp.csr_matrix((np.ones(oi.size), (oi, op)), shape=(m, p))
    common = (M @ M.T).toarray() if m <= 3000 else (M @ M.T).tocsr().toarray()
    np.fill_diagonal(common, 0)
    i, k = np.unravel_index(np.argmax(common), common.shape)
    if common[i, k] < 8:
        raise NotDeterminableError("approximate values: no image pair shares 8 points")
    # ---- seed pair: relative orientation in the model frame of image i
    pts_i = {int(q): j for j, q in zip(np.flatnonzero(oi == i), op[oi == i])}
    pairs = [
        (pts_i[int(q)], j) for j, q in zip(np.flatnonzero(oi == k), op[oi == k]) if int(q) in pts_i
    ]
    a_idx, b_idx = np.array(pairs).T
    if c[i] != c[k]:
        raise NotDeterminableError("approximate values: the seed pair needs one principal distance")
    E = eight_point(xyc[a_idx], xyc[b_idx], float(c[i]))
    R2, t, _ = select_by_cheirality(E, xyc[a_idx], xyc[b_idx], float(c[i]))
    Rm = np.full((m, 3, 3), np.nan)
    Xm = np.full((m, 3), np.nan)
    Rm[i], Xm[i] = np.eye(3), np.zeros(3)
    Rm[k], Xm[k] = R2, t / np.linalg.norm(t)
    done = np.zeros(m, bool)
    done[[i, k]] = True
    P = np.full((p, 3), np.nan)

    def intersect(image=None):
        # (re-)intersect the points of ``image`` (all points if None) from oriented rays
        sel = done[oi]
        if image is not None:
            mark = np.zeros(p, bool)
            mark[op[oi == image]] = True
            sel &= mark[op]
        pts, local = np.unique(op[sel], return_inverse=True)
        d = np.einsum("nij,nj->ni", Rm[oi[sel]], np.column_stack([xyc[sel], -c[oi[sel]]]))
        X, cond = intersect_rays(Xm[oi[sel]], d, local, pts.size)
        good = np.isfinite(X).all(axis=1) & (cond > 1e-6)
        P[pts[good]] = X[good]

    intersect()
    anchor = (i, k)
    refined_at = 0

    def refine():
        # bundle adjustment of the oriented part in the model frame: the seed image's
        # orientation and the seed base's x-component are held by strong observations
        nonlocal refined_at
        refined_at = int(done.sum())
        sub = _sub_block(block, done, P, Xm, Rm, oi, op, use, anchor)
        if sub is None:
            return
        res = bundle_adjust(sub.block, precision=False, max_iter=15, tol=1e-2)
        ext = res["exterior"].reshape(-1, 6)
        Xm[sub.images] = ext[:, :3]
        Rm[sub.images] = matrix_from_opk(ext[:, 3], ext[:, 4], ext[:, 5], "opk")
        P[sub.points] = res["points"].reshape(-1, 3)

    refine()
    while not done.all():
        if (
            done.sum() >= min(max(refined_at + 1, 1.25 * refined_at), refined_at + REFINE_EVERY)
            or done.sum() <= 12
        ):
            refine()
        known = np.isfinite(P[op]).all(axis=1)
        score = np.bincount(oi[known], minlength=m).astype(float)
        score[done] = -1
        nxt = int(np.argmax(score))
        if score[nxt] < min_points:
            left = [block.images.ids[j] for j in np.flatnonzero(~done)[:8]]
            raise NotDeterminableError(
                f"approximate values: images {', '.join(left)} share fewer than {min_points} "
                "points with the oriented part of the block",
                parameters=[f"{j}.X0" for j in left],
            )
        sel = (oi == nxt) & known
        # start from the best-connected oriented neighbour (its attitude, its centre);
        # the three-point closed form is the fallback
        nb = int(np.argmax(np.where(done, common[nxt], -1)))
        start = (Xm[nb], np.array(opk_from_matrix(Rm[nb], "opk")))
        res = None
        for st in (start, None):
            try:
                res = resection(xyc[sel], P[op[sel]], float(c[nxt]), start=st, max_iter=15)
            except (NotDeterminableError, np.linalg.LinAlgError, ValueError):
                continue
            if res.converged:
                break
        if res is None:
            raise NotDeterminableError(
                f"approximate values: the resection of image {block.images.ids[nxt]} failed",
                parameters=[f"{block.images.ids[nxt]}.X0"],
            )
        Rm[nxt] = res.R
        Xm[nxt] = res.x[:3]
        done[nxt] = True
        intersect(nxt)
        if res.sigma0 > POOR_RESECTION:  # the chain starts to deteriorate: adjust now
            refine()
    refine()
    out, T = into_frame(block, P, Xm, Rm, done, frame)  # the datum step (the same as then)
    out.meta = dict(
        block.meta, approximate_values={"seed_pair": [int(i), int(k)], "similarity_scale": T.scale}
    )
    return out


class _Sub:
    def __init__(self, block, images, points):
        self.block, self.images, self.points = block, images, points


def _sub_block(block, done, P, Xm, Rm, oi, op, use, anchor):
    """The oriented images and their points with ≥ 2 oriented rays, in the model frame."""
    imgs = np.flatnonzero(done)
    sel = done[oi] & np.isfinite(P[op]).all(axis=1)
    rays = np.bincount(op[sel], minlength=block.n_points)
    pts = np.flatnonzero(rays >= 2)
    sel &= rays[op] >= 2
    if imgs.size < 2 or pts.size < 6:
        return None
    img_new = -np.ones(block.n_images, np.int64)
    img_new[imgs] = np.arange(imgs.size)
    pt_new = -np.ones(block.n_points, np.int64)
    pt_new[pts] = np.arange(pts.size)
    full = np.flatnonzero(use)[sel]
    obs = block.observations
    om, ph, ka = opk_from_matrix(Rm[imgs], "opk")
    sub = Block.from_arrays(
        camera_c=block.cameras.c,
        camera_x0=block.cameras.x0,
        camera_y0=block.cameras.y0,
        image_camera=block.images.camera[imgs],
        X0=Xm[imgs],
        angles=np.column_stack([om, ph, ka]),
        xyz=P[pts],
        obs_image=img_new[obs.image[full]],
        obs_point=pt_new[obs.point[full]],
        obs_xy=obs.xy[full],
        obs_sigma=obs.sigma[full],
    )
    a, b = img_new[anchor[0]], img_new[anchor[1]]
    sub.images.X0_obs[a] = Xm[anchor[0]]
    sub.images.X0_sigma[a] = 1e-6
    sub.images.angles_obs[a] = 0.0
    sub.images.angles_sigma[a] = 1e-9
    sub.images.X0_obs[b, 0] = Xm[anchor[1], 0]
    sub.images.X0_sigma[b, 0] = 1e-6
    return _Sub(sub, imgs, pts)
