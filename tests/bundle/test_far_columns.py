"""The points near infinity of the precision (orientviz.bundle.precision._far.far_columns)
against the formula written plainly: the largest angle between a point's rays and its mean
ray direction, from np.linalg.norm, np.add.at and np.cross — the same columns and the same
directions to the last bit."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from orientviz.bundle.precision._far import HELD_PARALLAX, far_columns


def _problem(rng):
    """Twelve images on a 2 m base looking at 40 points: ten of them 1e7–1e9 m away
    (parallax far below HELD_PARALLAX), one of those weighted, one seen by one image;
    the rays of point unknowns in a shuffled order, a ray of a fixed point among them."""
    m, p = 12, 40
    X0 = rng.uniform(-1.0, 1.0, (m, 3))
    xyz = rng.uniform(-50.0, 50.0, (p, 3)) + [0.0, 0.0, 100.0]
    xyz[:10] = rng.standard_normal((10, 3)) * 10.0 ** rng.uniform(7, 9, (10, 1))
    img, col = [], []
    for j in range(p):
        k = 1 if j == 3 else int(rng.integers(2, 7))
        img += rng.choice(m, k, replace=False).tolist()
        col += [j] * k
    order = rng.permutation(len(img) + 1)
    image = np.r_[img, 0][order]
    column = np.r_[col, -1][order]
    prior_w = np.zeros((p, 3))
    prior_w[5] = 1.0
    obs = SimpleNamespace(image=image, column=column, var_rays=np.flatnonzero(column >= 0))
    points = SimpleNamespace(n=p, unknown=np.arange(p), prior_w=prior_w)
    return SimpleNamespace(obs=obs, points=points), SimpleNamespace(X0=X0, xyz=xyz)


def _plain(prob, st):
    vo = prob.obs.var_rays
    col = prob.obs.column[vo]
    d = st.xyz[prob.points.unknown[col]] - st.X0[prob.obs.image[vo]]
    d /= np.linalg.norm(d, axis=1)[:, None]
    mean = np.zeros((prob.points.n, 3))
    np.add.at(mean, col, d)
    mean /= np.linalg.norm(mean, axis=1)[:, None]
    sin = np.linalg.norm(np.cross(d, mean[col]), axis=1)
    par = np.zeros(prob.points.n)
    np.maximum.at(par, col, sin)
    rays = np.bincount(col, minlength=prob.points.n)
    free = ~np.any(prob.points.prior_w > 0, axis=1)
    cols = np.flatnonzero((par < np.sin(HELD_PARALLAX)) & (rays >= 2) & free)
    return cols, mean[cols]


def test_far_columns_equal_the_plain_formula():
    for seed in range(5):
        prob, st = _problem(np.random.default_rng(seed))
        cols, dirs = far_columns(prob, st)
        want_cols, want_dirs = _plain(prob, st)
        assert cols.tolist() == want_cols.tolist()
        assert dirs.tobytes() == want_dirs.tobytes()
        # the far points found: the distant ones but the weighted and the one-ray point
        assert set(cols.tolist()) == set(range(10)) - {3, 5}
