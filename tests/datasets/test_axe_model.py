"""The shipped real COLMAP model ``axe`` against an independent solver written here.

The independent solver reads the three text files itself and minimises COLMAP's own
objective — ½ Σ |reprojection error|² in pixels with COLMAP's RADIAL camera
(x_cam = R(q)·X + t, p = x_cam[:2]/x_cam[2], u = f·(1 + k1|p|² + k2|p|⁴)·p + (cx, cy)),
f, k1, k2 free and the principal point held as COLMAP's bundle adjustment does — by
Levenberg-Marquardt: central-difference Jacobian, points eliminated (Schur complement),
scipy's Rotation for the angle-axis poses, nothing of orientviz. The datum (image 0's
pose, one centre coordinate of image 1) does not change the cost, so the two minima are
compared by their cost. Both start from the same perturbed copy of the model; COLMAP's
own optimum (the file's values) is the third cost.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

import orientviz as ov
from orientviz.datasets.sfm import AXE_PIXEL_MM, axe_manifest, axe_model, read_axe
from orientviz.io.problem import problem_from_block


def _read_text_model(folder):
    """(f, cx, cy, k1, k2), per image (quaternion wxyz, t), points {id: xyz}, observations
    (image index, point index, u, v) — a point seen twice in one image keeps its first
    keypoint, as orientviz's import does (its message counts them)."""
    cam = (folder / "cameras.txt").read_text().split("\n")
    cam = [c for c in cam if c and not c.startswith("#")][0].split()
    assert cam[1] == "RADIAL"
    f, cx, cy, k1, k2 = map(float, cam[4:9])
    pts = {}
    for line in (folder / "points3D.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            w = line.split()
            pts[int(w[0])] = [float(v) for v in w[1:4]]
    pid = {p: k for k, p in enumerate(sorted(pts))}
    lines = [s for s in (folder / "images.txt").read_text().splitlines() if not s.startswith("#")]
    poses, obs = [], []
    for i in range(0, len(lines) - 1, 2):
        head = lines[i].split()
        if not head:
            continue
        poses.append([float(v) for v in head[1:8]])
        seen = set()
        w = lines[i + 1].split()
        for u, v, p in zip(w[0::3], w[1::3], w[2::3]):
            p = int(p)
            if p >= 0 and p not in seen:
                seen.add(p)
                obs.append((len(poses) - 1, pid[p], float(u), float(v)))
    X = np.array([pts[p] for p in sorted(pts)])
    return np.array([f, cx, cy, k1, k2]), np.array(poses), X, np.array(obs)


class Problem:
    """COLMAP's objective over x = [rotvec, t per image | f, k1, k2 | X per point]."""

    def __init__(self, cam, poses, X, obs):
        self.cx, self.cy = cam[1], cam[2]
        self.m, self.p = len(poses), len(X)
        self.ci, self.pi = obs[:, 0].astype(int), obs[:, 1].astype(int)
        self.uv = obs[:, 2:]
        q = poses[:, :4]
        rv = Rotation.from_quat(np.c_[q[:, 1:], q[:, :1]]).as_rotvec()
        self.x0 = np.r_[np.c_[rv, poses[:, 4:7]].ravel(), cam[[0, 3, 4]], X.ravel()]
        self.na = 6 * self.m + 3

    def residuals(self, x):
        e = x[: 6 * self.m].reshape(self.m, 6)
        f, k1, k2 = x[6 * self.m : self.na]
        X = x[self.na :].reshape(self.p, 3)
        R = Rotation.from_rotvec(e[:, :3]).as_matrix()  # per image, then per ray
        P = np.einsum("nij,nj->ni", R[self.ci], X[self.pi]) + e[self.ci, 3:]
        p = P[:, :2] / P[:, 2:3]
        r2 = np.sum(p * p, axis=1)
        d = f * (1.0 + k1 * r2 + k2 * r2 * r2)
        return (d[:, None] * p + [self.cx, self.cy] - self.uv).ravel()

    def jacobian(self, x, h=1e-6):
        """Per ray (n, 2, k) derivatives by central differences in 12 sweeps: every ray
        depends on one image and one point, so component k of all images (points) moves
        at once; f, k1, k2 one by one. Returns (image (n,2,6), camera (n,2,3), point (n,2,3))."""
        n = len(self.ci)
        out = np.empty((n, 2, 12))
        for k in range(12):
            e = np.zeros_like(x)
            if k < 6:
                e[k : 6 * self.m : 6] = 1.0
                col = 6 * self.ci + k
            elif k < 9:
                e[6 * self.m + k - 6] = 1.0
                col = np.full(n, 6 * self.m + k - 6)
            else:
                e[self.na + k - 9 :: 3] = 1.0
                col = self.na + 3 * self.pi + k - 9
            step = h * np.maximum(1.0, np.abs(x)) * e
            d = (self.residuals(x + step) - self.residuals(x - step)).reshape(n, 2)
            out[:, :, k] = d / (2.0 * step[col])[:, None]
        return out[:, :, :6], out[:, :, 6:9], out[:, :, 9:]

    def solve(self, x, fixed, max_iter=60):
        """Levenberg-Marquardt (Marquardt's scaling) on the normal equations with the points
        eliminated (Schur complement); ``fixed`` indices of x (in the images' part) are
        held; stops when a step lowers the cost by < 1e-11 relative."""
        n, m, p, na = len(self.ci), self.m, self.p, self.na
        keep = np.setdiff1d(np.arange(na), fixed)
        r = self.residuals(x)
        cost, lam = 0.5 * r @ r, 1e-4
        rows = np.arange(2 * n).reshape(n, 2)
        for _ in range(max_iter):
            Je, Jc, Jp = self.jacobian(x)
            ecol = 6 * self.ci[:, None] + np.arange(6)
            A = sp.csr_matrix(
                (np.c_[Je.reshape(2 * n, 6), Jc.reshape(2 * n, 3)].ravel(),
                 (np.repeat(rows.ravel(), 9),
                  np.c_[np.repeat(ecol, 2, axis=0), np.tile(6 * m + np.arange(3), (2 * n, 1))].ravel())),
                shape=(2 * n, na))[:, keep]  # fmt: skip
            B = sp.csr_matrix(
                (Jp.reshape(2 * n, 3).ravel(),
                 (np.repeat(rows.ravel(), 3), np.repeat(3 * self.pi[:, None] + np.arange(3), 2, axis=0).ravel())),
                shape=(2 * n, 3 * p))  # fmt: skip
            U, W = (A.T @ A).toarray(), (A.T @ B).tocsr()
            V = np.zeros((p, 3, 3))
            np.add.at(V, self.pi, np.einsum("nki,nkj->nij", Jp, Jp))
            ga, gb = A.T @ r, B.T @ r
            while True:
                Ud = U + lam * np.diag(np.diag(U))
                inv = np.linalg.inv(V * (1.0 + lam * np.eye(3)))  # the 3×3 blocks of V⁻¹
                Vi = sp.csr_matrix((inv.ravel(), np.repeat(3 * np.arange(p), 9) % (3 * p)
                                    + np.tile(np.arange(3), 3 * p), np.arange(0, 9 * p + 1, 3)),
                                   shape=(3 * p, 3 * p))  # fmt: skip
                WVi = W @ Vi
                da = np.linalg.solve(Ud - (WVi @ W.T).toarray(), -(ga - WVi @ gb))
                db = -(Vi @ (gb + W.T @ da))
                dx = np.zeros_like(x)
                dx[keep] = da
                dx[na:] = db
                r_new = self.residuals(x + dx)
                c_new = 0.5 * r_new @ r_new
                if c_new < cost:
                    break
                lam *= 10.0
                if lam > 1e10:
                    return cost, x
            done = cost - c_new < 1e-11 * cost
            x, r, cost, lam = x + dx, r_new, c_new, max(lam / 10.0, 1e-12)
            if done:
                break
        return cost, x


def _perturbed_copy(src, dst, rng):
    """The model with every image centre moved by ~0.2 % of the object's size, every
    attitude by ~0.2 mrad and every point by ~0.1 %: a start ~10² times COLMAP's cost."""
    dst.mkdir()
    (dst / "cameras.txt").write_text((src / "cameras.txt").read_text())
    out, pts = [], (src / "points3D.txt").read_text().splitlines()
    X = np.array([[float(v) for v in s.split()[1:4]] for s in pts if s and s[0] != "#"])
    size = float(np.ptp(X, axis=0).max())
    for line in pts:
        if line and not line.startswith("#"):
            w = line.split()
            xyz = np.array(w[1:4], float) + rng.normal(0, 0.001 * size, 3)
            line = " ".join([w[0], *map(repr, xyz.tolist()), *w[4:]])
        out.append(line)
    (dst / "points3D.txt").write_text("\n".join(out) + "\n")
    lines, out, head = (src / "images.txt").read_text().splitlines(), [], True
    for line in lines:
        if line.startswith("#") or not line.strip():
            out.append(line)
            continue
        if head:
            w = line.split()
            q = np.array(w[1:5], float)
            R = Rotation.from_quat(np.r_[q[1:], q[:1]]) * Rotation.from_rotvec(
                rng.normal(0, 1e-3, 3)
            )
            qn = R.as_quat()
            t = np.array(w[5:8], float) + rng.normal(0, 0.002 * size, 3)
            line = " ".join([w[0], *map(repr, np.r_[qn[3], qn[:3], t].tolist()), *w[8:]])
        out.append(line)
        head = not head
    (dst / "images.txt").write_text("\n".join(out) + "\n")


@pytest.fixture(scope="module")
def start(tmp_path_factory):
    d = tmp_path_factory.mktemp("axe") / "perturbed"
    _perturbed_copy(axe_model(), d, np.random.default_rng(28))
    return d


def test_the_shipped_files_are_the_manifests(start):
    man = axe_manifest()
    for name, digest in man["sha256"].items():
        assert hashlib.sha256((axe_model() / name).read_bytes()).hexdigest() == digest, name
    block = read_axe()
    assert (block.n_images, block.n_points) == (man["images"], man["points"])
    assert block.cameras.model[0]["free"] == ["c", "k1", "k2"]
    assert "Attribution 4.0" in (axe_model() / "LICENSE.md").read_text().splitlines()[0]


def test_orientviz_reaches_the_independent_optimum_from_a_perturbed_start(start):
    cam, poses, X, obs = _read_text_model(start)
    prob = Problem(cam, poses, X, obs)
    # the datum: image 0's pose and the largest translation component of image 1
    fixed = np.r_[np.arange(6), 9 + np.abs(prob.x0[9:12]).argmax()]
    start_cost = 0.5 * np.sum(prob.residuals(prob.x0) ** 2)
    cost, x = prob.solve(prob.x0.copy(), fixed)
    assert cost < 0.05 * start_cost  # the independent solver did move

    colmap = Problem(*_read_text_model(axe_model()))
    colmap_cost = 0.5 * np.sum(colmap.residuals(colmap.x0) ** 2)  # COLMAP's own optimum

    from orientviz.io.colmap import read_colmap

    block = read_colmap(start, pixel_size_mm=AXE_PIXEL_MM, sigma_px=1.0)
    sol = ov.solve_problem(problem_from_block(block, options={"free": True}))
    adj = sol.adjustment
    assert adj.converged
    ours = 0.5 * adj.sigma0**2 * adj.redundancy  # ½ vᵀPv, σ = 1 px
    assert ours == pytest.approx(cost, rel=1e-6)
    assert ours <= colmap_cost * (1 + 1e-6)
    # the camera: f, k1, k2 as the independent solver found them
    f, k1, k2 = x[6 * prob.m : prob.na]
    c, _ = adj.camera.get("c")
    assert c / AXE_PIXEL_MM == pytest.approx(f, rel=1e-6)
    assert adj.camera.get("k1")[0] == pytest.approx(k1, rel=1e-4, abs=1e-9)
