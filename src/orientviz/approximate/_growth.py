"""The growth of the approximations: seed pair, then waves of resections and intersections.

Used by :func:`orientviz.approximate.approximate_values`, which adds the datum. Everything
here is in the model frame of the seed pair (left image at the origin with R = I, base
length 1). One wave orients *all* images that see enough intersected points (at least
``min_points`` and at least :data:`WAVE_SHARE` of the best such image's count) in one
stacked resection (``resect_batch`` of ``approximate/_batch.py``), then
intersects every point seen by the new images from all its oriented rays in one call
(:func:`~orientviz.orientation.intersection.intersect_rays`). The oriented part is
re-adjusted by a bundle in the model frame whenever it has grown by the factor :data:`REFINE_GROWTH` (so
O(log n) refines, the last of them on the whole block) and whenever a resection fits
poorly (σ̂0 > :data:`POOR_RESECTION`): the chain's errors are removed before they grow.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..block import CHECK, Block
from ..bundle import bundle_adjust
from ..errors import NotDeterminableError
from ..orientation.essential import eight_point, five_point_route, select_by_cheirality
from ..orientation.intersection import intersect_rays
from ..orientation.resection import resection
from ..rotation import matrix_from_opk, opk_from_matrix
from ._batch import centres_for_attitudes, resect_batch
from ._front import adjust_front

F64 = NDArray[np.float64]
#: The oriented part is re-adjusted (model-frame bundle) when it has grown by this
#: factor since the last re-adjustment (and while it has at most 12 images).
REFINE_GROWTH: float = 2.0
#: Gauss-Newton steps of such a re-adjustment: from the grown chain two steps remove
#: nearly all of its error; the bundle after the approximations does the rest.
REFINE_ITERATIONS: int = 2
#: The last re-adjustment, of the whole block, is left out when the one before already
#: held this share of the images (the few added since came with their local bundle).
FINAL_REFINE: float = 1.1
#: A local bundle whose σ̂0 exceeds this many times that of the last re-adjustment (at
#: least 1; image residuals ≫ their σ: the chain has bent) triggers a re-adjustment of
#: the oriented part after the wave.
POOR_RESECTION: float = 20.0
#: A wave orients the images that see at least this share of the known points of the
#: best-connected waiting image (the best-connected first; all of them in one batch).
WAVE_SHARE: float = 0.5
#: A seed pair shares at least this many points: the five-point relative orientation
#: below 8 (a textbook pair of six von Gruber points), the eight-point one from 8 on.
MIN_SEED_POINTS = 5
#: The seed pair shares at least this share of the largest number of common points of
#: any pair (then the most central such pair is taken).
SEED_SHARE: float = 0.8
#: Seed pairs tried at most (see :meth:`Growth.seed_pair`).
SEED_TRIES: int = 8
#: The local bundle after a wave frees the images of this many latest waves.
FRONT_WAVES: int = 2
#: Gauss-Newton steps of the local bundle.
FRONT_ITERATIONS: int = 1


class Growth:
    """State of the growing model: ``Rm`` (m, 3, 3), ``Xm`` (m, 3), ``P`` (p, 3), ``done``.

    Parameters
    ----------
    block : Block
        Image observations and interior orientation; check points are left out.
    min_points : int
        Fewest intersected points an image needs to be resected.
    """

    def __init__(self, block: Block, min_points: int):
        self.block, self.min_points = block, min_points
        obs = block.observations
        use = block.points.role[obs.point] != CHECK
        self.use = use
        self.oi, self.op = obs.image[use], obs.point[use]
        self.sigma = obs.sigma[use]
        m, p = block.n_images, block.n_points
        cam = block.images.camera
        self.c_img = block.cameras.c[cam]
        pp = np.column_stack([block.cameras.x0[cam], block.cameras.y0[cam]])
        self.xyc = obs.xy[use] - pp[self.oi]  # relative to the principal point
        self.c = self.c_img[self.oi]
        M = sp.csr_matrix((np.ones(self.oi.size), (self.oi, self.op)), shape=(m, p))
        common = (M @ M.T).tocsr()
        common.setdiag(0)
        common.eliminate_zeros()
        self.common = common
        # which observation (+1) is image i's of point q
        self.obs_at = sp.csr_matrix(
            (np.arange(1, self.oi.size + 1), (self.oi, self.op)), shape=(m, p)
        )
        self.Rm = np.full((m, 3, 3), np.nan)
        self.Xm = np.full((m, 3), np.nan)
        self.P = np.full((p, 3), np.nan)
        self.done = np.zeros(m, bool)
        self.refined_at = 0
        self.sigma0 = 1.0  # σ̂0 of the last re-adjustment (at least 1)
        self.refines = 0
        self.waves = 0

    # ---- seed pair -------------------------------------------------------------------
    def seed_pair(self) -> None:
        """Relative orientation of a strong pair near the middle, adjusted.

        The candidates (:meth:`_seed_candidates`) are tried in turn until the bundle of
        the pair fits (σ̂0 ≤ :data:`POOR_RESECTION`): the eight-point solution can be a
        wrong one (e.g. over nearly flat ground); else the best fitting is kept.
        """
        C = self.common.tocoo()
        if C.nnz == 0 or C.data.max() < MIN_SEED_POINTS:
            raise NotDeterminableError(
                f"approximate values: no image pair shares {MIN_SEED_POINTS} points"
            )
        tried = []
        for i, k in self._seed_candidates(C)[:SEED_TRIES]:
            if self.c_img[i] != self.c_img[k] or not self._orient_pair(i, k):
                continue
            self.refine()
            tried.append((self.sigma0, i, k))
            if self.sigma0 <= POOR_RESECTION:
                return
        if not tried:
            raise NotDeterminableError(
                "approximate values: no seed pair with one principal distance and a "
                "relative orientation found"
            )
        _, i, k = min(tried)
        self._orient_pair(i, k)
        self.refine()

    def _orient_pair(self, i: int, k: int) -> bool:
        """Relative orientation of images i, k (essential matrix) as the only oriented ones."""
        self.Rm[:], self.Xm[:], self.P[:], self.done[:] = np.nan, np.nan, np.nan, False
        oi, op = self.oi, self.op
        ri, rk = np.flatnonzero(oi == i), np.flatnonzero(oi == k)
        _, a_pos, b_pos = np.intersect1d(op[ri], op[rk], return_indices=True)
        a_idx, b_idx = ri[a_pos], rk[b_pos]
        c = float(self.c_img[i])
        try:
            if a_idx.size >= 8:
                E = eight_point(self.xyc[a_idx], self.xyc[b_idx], c)
                R2, t, _ = select_by_cheirality(E, self.xyc[a_idx], self.xyc[b_idx], c)
            else:  # a textbook pair of 5-7 points: the five-point solution fitting best
                _, R2, t = five_point_route(self.xyc[a_idx], self.xyc[b_idx], c)
        except (NotDeterminableError, np.linalg.LinAlgError, ValueError):
            return False
        self.Rm[i], self.Xm[i] = np.eye(3), np.zeros(3)
        self.Rm[k], self.Xm[k] = R2, t / np.linalg.norm(t)
        self.done[[i, k]] = True
        self.seed = (i, k)
        self.refined_at, self.sigma0 = 0, 1.0
        self.intersect(np.array([i, k]))
        return True

    def _seed_candidates(self, C: sp.coo_matrix) -> list[tuple[int, int]]:
        """Pairs sharing ≥ :data:`MIN_SEED_POINTS` points: first those with ≥ :data:`SEED_SHARE` of the most
        common points, the most central first, then the others by their common points.

        Central: the smallest eccentricity max(d_a, d_b) in image-graph hops to the two
        ends a, b of a long path (found by two breadth-first searches); seeding there
        halves the way the growth (and its errors) must travel.
        """
        from scipy.sparse.csgraph import shortest_path

        upper = (C.row < C.col) & (C.data >= MIN_SEED_POINTS)
        rows, cols, data = C.row[upper], C.col[upper], C.data[upper]
        start = int(rows[np.argmax(data)])
        d0 = shortest_path(self.common, unweighted=True, indices=start)
        a = int(np.argmax(np.where(np.isfinite(d0), d0, -1)))
        da = shortest_path(self.common, unweighted=True, indices=a)
        b = int(np.argmax(np.where(np.isfinite(da), da, -1)))
        db = shortest_path(self.common, unweighted=True, indices=b)
        ecc = np.maximum(da, db)
        e = np.maximum(ecc[rows], ecc[cols])
        e = np.where(np.isfinite(e), e, np.inf)
        weak = data < SEED_SHARE * data.max()
        order = np.lexsort((cols, rows, -data, np.where(weak, 0, e), weak))
        return [(int(rows[j]), int(cols[j])) for j in order]

    # ---- intersection ----------------------------------------------------------------
    def intersect(self, images: NDArray[np.int64] | None = None) -> None:
        """(Re-)intersect the points of ``images`` (all if None) from all oriented rays."""
        oi, op = self.oi, self.op
        sel = self.done[oi]
        if images is not None:
            new = np.zeros(self.block.n_images, bool)
            new[images] = True
            mark = np.zeros(self.block.n_points, bool)
            mark[op[new[oi]]] = True
            sel &= mark[op]
        pts, local = np.unique(op[sel], return_inverse=True)
        o = oi[sel]
        d = np.einsum("nij,nj->ni", self.Rm[o], np.column_stack([self.xyc[sel], -self.c[sel]]))
        X, cond = intersect_rays(self.Xm[o], d, local, pts.size)
        good = np.isfinite(X).all(axis=1) & (cond > 1e-6)
        self.P[pts[good]] = X[good]

    # ---- refinement ------------------------------------------------------------------
    def refine(self) -> None:
        """Bundle adjustment of the oriented part in the model frame (the seed image's
        orientation and the seed base's x-component held by strong observations)."""
        self.refined_at = int(self.done.sum())
        sub = sub_block(self.block, self.done, self.P, self.Xm, self.Rm, self.use, self.seed)
        if sub is None:
            return
        blk, imgs, pts = sub
        res = bundle_adjust(blk, precision=False, max_iter=REFINE_ITERATIONS, tol=1e-2)
        ext = res["exterior"].reshape(-1, 6)
        self.Xm[imgs] = ext[:, :3]
        self.Rm[imgs] = matrix_from_opk(ext[:, 3], ext[:, 4], ext[:, 5], "opk")
        self.P[pts] = res["points"].reshape(-1, 3)
        self.refines += 1
        if np.isfinite(res.sigma0):
            self.sigma0 = max(float(res.sigma0), 1.0)

    # ---- growth ----------------------------------------------------------------------
    def grow(self) -> None:
        """Seed pair, then waves until every image is oriented, then a last refine."""
        self.seed_pair()
        m = self.block.n_images
        stuck = np.full(m, -1)  # known-point count at which an image's resection failed
        poor = False
        recent = []
        while not self.done.all():
            n_done = int(self.done.sum())
            small = n_done <= 12 and n_done > self.refined_at
            if poor or small or n_done >= REFINE_GROWTH * self.refined_at:
                self.refine()
            known = np.isfinite(self.P[self.op]).all(axis=1)
            score = np.bincount(self.oi[known], minlength=m)
            waiting = ~self.done & (score > stuck)
            best = int(score[waiting].max()) if waiting.any() else 0
            if best >= self.min_points:
                cand = np.flatnonzero(waiting & (score >= max(self.min_points, WAVE_SHARE * best)))
                new, s0 = self._resect(cand, known)
                stuck[cand[~np.isin(cand, new)]] = score[cand[~np.isin(cand, new)]]
                if new.size == 0:
                    continue
            else:  # the batch failed on all that can be reached: one by one, closed form
                cand = np.flatnonzero(~self.done & (score >= self.min_points))
                if cand.size == 0:
                    self._raise_unreached()
                new, s0 = self._resect(cand, known, single=True)
                if new.size == 0:
                    self._raise_failed(cand[0])
            self.done[new] = True
            self.intersect(new)
            self.waves += 1
            recent.append(new)
            if self.done.sum() < REFINE_GROWTH * self.refined_at:  # else the whole follows
                s0 = self.adjust_front(np.concatenate(recent[-FRONT_WAVES:]))
            poor = bool(np.any(s0 > POOR_RESECTION * self.sigma0))
        if self.done.sum() > FINAL_REFINE * self.refined_at:
            self.refine()

    def _resect(self, cand: NDArray[np.int64], known: NDArray[np.bool_], single: bool = False):
        """Orient the images ``cand``; returns those oriented and their σ̂0."""
        local = -np.ones(self.block.n_images, np.int64)
        local[cand] = np.arange(cand.size)
        sel = known & (local[self.oi] >= 0)
        img = local[self.oi[sel]]
        X = self.P[self.op[sel]]
        # start: the attitude of the best-connected oriented neighbour, the centre that
        # fits the rays best with it
        C = self.common[cand][:, np.flatnonzero(self.done)]
        nb = np.flatnonzero(self.done)[np.asarray(C.argmax(axis=1)).ravel()]
        R0 = self.Rm[nb] @ self._turn_to(cand, nb)
        X00, _ = centres_for_attitudes(img, self.xyc[sel], self.c[sel], X, R0, cand.size)
        bad_start = ~np.isfinite(X00).all(axis=1)
        X00[bad_start] = self.Xm[nb[bad_start]]
        R, X0, s0, ok = resect_batch(img, self.xyc[sel], self.c[sel], self.sigma[sel], X, R0, X00)
        # the closed form for images the batch found poorly (a wrong minimum?) and, when
        # the batch could not orient any image that can be reached, for the failed ones
        poor = ok & ~(s0 <= POOR_RESECTION * self.sigma0)
        for j in np.flatnonzero(poor | (~ok if single else False)):
            r1, x1, s1, ok1 = self._resect_one(cand[j], sel & (local[self.oi] == j))
            if ok1 and (not ok[j] or s1 < s0[j]):
                R[j], X0[j], s0[j], ok[j] = r1, x1, s1, True
        self.Rm[cand[ok]], self.Xm[cand[ok]] = R[ok], X0[ok]
        return cand[ok], s0[ok]

    def adjust_front(self, images):
        """Local bundle: ``images`` and all their points, the other oriented images held."""
        oi, op = self.oi, self.op
        new = np.zeros(self.block.n_images, bool)
        new[images] = True
        mark = np.zeros(self.block.n_points, bool)
        mark[op[new[oi]]] = True
        mark &= np.isfinite(self.P).all(axis=1)
        sel = self.done[oi] & mark[op]
        pts, local = np.unique(op[sel], return_inverse=True)
        R, X0, Q, s0 = adjust_front(
            oi[sel],
            local,
            self.xyc[sel],
            self.c[sel],
            self.sigma[sel],
            self.Rm,
            self.Xm,
            images,
            self.P[pts],
            iterations=FRONT_ITERATIONS,
        )
        self.Rm[images], self.Xm[images], self.P[pts] = R[images], X0[images], Q
        return s0

    def _turn_to(self, cand: NDArray[np.int64], nb: NDArray[np.int64]) -> F64:
        """Rotation (3, 3) per candidate about its image normal from its neighbour's image.

        The 2D similarity z_nb ≈ a·z + b of the common points' image coordinates
        (complex numbers z = x + iy) gives the turn arg(a) between the two images (e.g.
        200 gon between neighbouring strips flown in opposite directions); the start
        attitude of the candidate is the neighbour's turned by it.
        """
        local = -np.ones(self.block.n_images, np.int64)
        local[cand] = np.arange(cand.size)
        rays = np.flatnonzero(local[self.oi] >= 0)
        j = local[self.oi[rays]]
        other = np.asarray(self.obs_at[nb[j], self.op[rays]]).ravel() - 1
        both = other >= 0
        j, a, b = j[both], rays[both], other[both]
        za = self.xyc[a, 0] + 1j * self.xyc[a, 1]
        zb = self.xyc[b, 0] + 1j * self.xyc[b, 1]
        k = np.maximum(np.bincount(j, minlength=cand.size), 1)
        ma = (np.bincount(j, za.real, cand.size) + 1j * np.bincount(j, za.imag, cand.size)) / k
        mb = (np.bincount(j, zb.real, cand.size) + 1j * np.bincount(j, zb.imag, cand.size)) / k
        prod = (zb - mb[j]) * np.conj(za - ma[j])
        t = np.angle(
            np.bincount(j, prod.real, cand.size) + 1j * np.bincount(j, prod.imag, cand.size)
        )
        T = np.zeros((cand.size, 3, 3))
        T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = np.cos(t), -np.sin(t), np.sin(t), np.cos(t)
        T[:, 2, 2] = 1.0
        return T

    def _resect_one(self, image: int, sel: NDArray[np.bool_]):
        """Single-image resection from the three-point closed form (the batch's fallback)."""
        try:
            res = resection(
                self.xyc[sel], self.P[self.op[sel]], float(self.c_img[image]),
                sigma=self.sigma[sel], max_iter=15,
            )  # fmt: skip
        except (NotDeterminableError, np.linalg.LinAlgError, ValueError):
            return np.eye(3), np.zeros(3), np.inf, False
        return res.R, res.x[:3], res.sigma0, bool(res.converged)

    def _raise_failed(self, image: int) -> None:
        name = self.block.images.ids[image]
        raise NotDeterminableError(
            f"approximate values: the resection of image {name} failed",
            parameters=[f"{name}.X0"],
        )

    def _raise_unreached(self) -> None:
        left = [self.block.images.ids[j] for j in np.flatnonzero(~self.done)[:8]]
        raise NotDeterminableError(
            f"approximate values: images {', '.join(left)} share fewer than {self.min_points} "
            "points with the oriented part of the block",
            parameters=[f"{j}.X0" for j in left],
        )


def sub_block(block, done, P, Xm, Rm, use, anchor):
    """The oriented images and their points with ≥ 2 oriented rays, in the model frame.

    Returns ``(block, images, points)`` (the sub-block and the original indices of its
    images and points), or None when fewer than 2 images or 6 points are available.
    """
    obs = block.observations
    oi, op = obs.image[use], obs.point[use]
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
    # the datum: the seed image and the base's largest component held by observations
    # some 10³ times stronger than the rays (not more: every solver of the reduced system,
    # also the sparse LU with its pivot test, must still see the rays beside them)
    a, b = img_new[anchor[0]], img_new[anchor[1]]
    sub.images.X0_obs[a] = Xm[anchor[0]]
    sub.images.X0_sigma[a] = 1e-6
    sub.images.angles_obs[a] = 0.0
    sub.images.angles_sigma[a] = 1e-7
    e = int(np.argmax(np.abs(Xm[anchor[1]] - Xm[anchor[0]])))  # the base's largest part
    sub.images.X0_obs[b, e] = Xm[anchor[1], e]
    sub.images.X0_sigma[b, e] = 1e-6
    return sub, imgs, pts
