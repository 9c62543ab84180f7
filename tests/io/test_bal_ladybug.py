"""The shipped real BAL problem (Ladybug 49-7776) against an independent solver.

The independent solver is written here: BAL's projection in plain numpy (angle-axis by
scipy's Rotation, p = −P_xy/P_z, x = f(1 + k1|p|² + k2|p|⁴)p), a central-difference
sparse Jacobian and Levenberg-Marquardt with scipy's sparse direct solver — nothing of
orientviz. Both start from
the file's values with f, k1, k2 held (``--fix-lens``; with them free the 5-camera part is
too weak to determine them: its normal equations are singular at the optimum); the cost
is datum-invariant and compared. The full file's refined optimum against Ceres is in
benchmarks/README.md.
"""

from __future__ import annotations

import bz2
import contextlib
import io
import json

import numpy as np
import pytest
from scipy.sparse import csr_matrix, diags
from scipy.sparse.linalg import spsolve
from scipy.spatial.transform import Rotation

from orientviz.cli import main
from orientviz.io.bal import read_bal, shipped_bal

N_CAMERAS = 5  # the sub-problem: the first cameras of the sequence and their shared points


def _sub_problem():
    """Cameras 0..N−1 of the shipped file, the points seen by ≥ 3 of them, their rays."""
    words = bz2.decompress(shipped_bal().read_bytes()).decode().split()
    nc, npt, nobs = map(int, words[:3])
    obs = np.array(words[3 : 3 + 4 * nobs], float).reshape(nobs, 4)
    rest = np.array(words[3 + 4 * nobs :], float)
    cams, pts = rest[: 9 * nc].reshape(nc, 9), rest[9 * nc :].reshape(npt, 3)
    obs = obs[obs[:, 0] < N_CAMERAS]
    seen = np.bincount(obs[:, 1].astype(int), minlength=npt)
    keep_pt = np.flatnonzero(seen >= 3)
    obs = obs[np.isin(obs[:, 1].astype(int), keep_pt)]
    new = np.full(npt, -1)
    new[keep_pt] = np.arange(keep_pt.size)
    obs[:, 1] = new[obs[:, 1].astype(int)]
    return obs, cams[:N_CAMERAS].copy(), pts[keep_pt].copy()


def _bal_text(obs, cams, pts) -> str:
    head = f"{len(cams)} {len(pts)} {len(obs)}\n"
    rows = "".join(f"{int(c)} {int(p)} {x!r} {y!r}\n" for c, p, x, y in obs.tolist())
    return head + rows + "".join(f"{v!r}\n" for v in np.r_[cams.ravel(), pts.ravel()].tolist())


def _residuals(x, n_cam, ci, pi, xy):
    cams = x[: 9 * n_cam].reshape(n_cam, 9)
    pts = x[9 * n_cam :].reshape(-1, 3)
    P = Rotation.from_rotvec(cams[ci, :3]).apply(pts[pi]) + cams[ci, 3:6]
    p = -P[:, :2] / P[:, 2:3]
    r2 = np.sum(p * p, axis=1)
    d = cams[ci, 6] * (1 + cams[ci, 7] * r2 + cams[ci, 8] * r2 * r2)
    return (d[:, None] * p - xy).ravel()


def _jacobian(x, n_cam, ci, pi, xy, h=1e-6):
    """Sparse Jacobian by central differences, 12 evaluations: every observation depends
    on one camera and one point, so component k of all cameras (points) moves at once."""
    n = len(ci)
    rows = np.repeat(np.arange(2 * n), 12)
    cols, vals = np.empty((2 * n, 12), np.int64), np.empty((2 * n, 12))
    for k in range(12):
        e = np.zeros_like(x)
        if k < 9:
            e[k : 9 * n_cam : 9] = 1.0
            col = 9 * ci + k
        else:
            e[9 * n_cam + k - 9 :: 3] = 1.0
            col = 9 * n_cam + 3 * pi + k - 9
        step = h * np.maximum(1.0, np.abs(x)) * e
        d = _residuals(x + step, n_cam, ci, pi, xy) - _residuals(x - step, n_cam, ci, pi, xy)
        scale = np.repeat(
            2 * np.where(k < 9, step[9 * ci + min(k, 8)], step[9 * n_cam + 3 * pi + max(k - 9, 0)]),
            2,
        )
        cols[:, k] = np.repeat(col, 2)
        vals[:, k] = d / scale
    return csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(2 * n, x.size))


def _independent_optimum(obs, cams, pts, max_iter=100):
    """Levenberg-Marquardt (Marquardt's diagonal scaling, λ × 10 / ÷ 10) with a sparse
    direct solve of the damped normal equations, to a relative cost change of 1e-14."""
    ci, pi, xy = obs[:, 0].astype(int), obs[:, 1].astype(int), obs[:, 2:]
    n_cam = len(cams)
    x = np.r_[cams.ravel(), pts.ravel()]
    free = np.ones(x.size, bool)
    free[[0, 1, 2, 3, 4, 5, 9 + 3]] = False  # the datum: camera 0's pose, t_x of camera 1
    for k in (6, 7, 8):  # f, k1, k2 held at the file's values (import-bal --fix-lens)
        free[k : 9 * n_cam : 9] = False
    r = _residuals(x, n_cam, ci, pi, xy)
    cost, lam = 0.5 * r @ r, 1e-4
    for _ in range(max_iter):
        J = _jacobian(x, n_cam, ci, pi, xy)[:, free]
        N, g = (J.T @ J).tocsc(), J.T @ r
        d = N.diagonal()
        while True:
            dx = np.zeros_like(x)
            dx[free] = spsolve(N + diags(lam * d), -g)
            r_new = _residuals(x + dx, n_cam, ci, pi, xy)
            c_new = 0.5 * r_new @ r_new
            if c_new < cost:
                break
            lam *= 10.0
            if lam > 1e12:
                return cost, x[: 9 * n_cam].reshape(n_cam, 9)
        x, r, done = x + dx, r_new, cost - c_new < 1e-14 * cost
        cost, lam = c_new, max(lam / 10.0, 1e-15)
        if done:
            break
    return cost, x[: 9 * n_cam].reshape(n_cam, 9)


@pytest.fixture(scope="module")
def ladybug_part(tmp_path_factory):
    obs, cams, pts = _sub_problem()
    path = tmp_path_factory.mktemp("lb") / "ladybug8.bal"
    path.write_text(_bal_text(obs, cams, pts))
    return path, obs, cams, pts


def test_the_shipped_file_reads(ladybug_part):
    block = read_bal(shipped_bal())
    assert (block.n_images, block.n_points, block.n_observations) == (49, 7776, 31843)
    assert [m["free"] for m in block.cameras.model[:1]] == [["c", "k1", "k2"]]


def test_orientviz_reaches_the_independent_optimum(ladybug_part, tmp_path):
    path, obs, cams, pts = ladybug_part
    cost, cams_opt = _independent_optimum(obs, cams, pts)
    start = 0.5 * np.sum(_residuals(np.r_[cams.ravel(), pts.ravel()], len(cams),
                                    obs[:, 0].astype(int), obs[:, 1].astype(int), obs[:, 2:]) ** 2)  # fmt: skip
    assert cost < 0.5 * start  # the independent solver did move
    prob = tmp_path / "p.json"
    assert main(["import-bal", str(path), "--fix-lens", "-o", str(prob)]) == 0
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        code = main(["solve", str(prob), "--free", "--json"])
    sol = json.loads(text.getvalue())
    assert code == 0 and sol["converged"]
    ours = 0.5 * sol["sigma0"] ** 2 * sol["redundancy"]  # ½ vᵀPv, σ = 1 px
    assert ours == pytest.approx(cost, rel=1e-6)
    assert sol["parameters"] == []  # f, k1, k2 held
