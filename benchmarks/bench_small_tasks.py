"""Timing of the single-image and absolute-orientation tasks beside peers, in one run.

    python benchmarks/bench_small_tasks.py [--repeat 30]

Prints best-of-N wall times in ms and the ratio orientviz / peer (< 1: orientviz faster),
plus the largest difference between the two solutions, to show that both solved the same
problem. Peers: a bare numpy SVD (Umeyama-style) and scipy's ``Rotation.align_vectors``
for the closed-form similarity; ``scipy.optimize.least_squares`` with the same analytic
Jacobian for the least-squares similarity; OpenCV's ``solvePnP`` (iterative LM, and SQPnP)
for the resection; OpenCV's ``triangulatePoints`` (linear DLT, 2 views) for intersection.
orientviz's least-squares functions also compute the full precision (cofactor matrix,
redundancy numbers, normalised residuals), which the peers do not.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from orientviz.camera import project
from orientviz.orientation.absolute import (
    SimilarityTransform,
    similarity_closed_form,
    similarity_model,
    similarity_transform,
)
from orientviz.orientation.intersection import intersect_points
from orientviz.orientation.resection import resection
from orientviz.rotation import matrix_from_opk


def best_ms(fn, repeat: int) -> float:
    fn()  # warm-up
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best * 1000.0


def umeyama_numpy(x, X):
    xc, Xc = x.mean(0), X.mean(0)
    U, D, Vt = np.linalg.svd((X - Xc).T @ (x - xc))
    S = np.array([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    R = (U * S) @ Vt
    m = (D * S).sum() / np.sum((x - xc) ** 2)
    return m, R, Xc - m * R @ xc


def align_vectors_scipy(x, X):
    xc, Xc = x.mean(0), X.mean(0)
    rot, _ = Rotation.align_vectors(X - Xc, x - xc)
    R = rot.as_matrix()
    m = np.sum((X - Xc) * ((x - xc) @ R.T)) / np.sum((x - xc) ** 2)
    return m, R, Xc - m * R @ xc


def similarity_scipy_ls(x, X, p0):
    def fun(p):
        return (similarity_model(p, x)[0] - X).ravel()

    def jac(p):
        return similarity_model(p, x)[1].reshape(-1, 7)

    return least_squares(fun, p0, jac=jac, method="lm", xtol=1e-12).x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=30)
    args = ap.parse_args()
    rng = np.random.default_rng(42)
    rows = []

    # ---- similarity, 1000 points
    x = rng.uniform(-100, 100, (1000, 3))
    truth = SimilarityTransform.from_params([5000, 3000, 400, 0.02, -0.03, 2.5, 10.0])
    X = truth.apply(x) + rng.normal(0, 0.02, x.shape)
    cf = similarity_closed_form(x, X)
    m1, R1, _ = umeyama_numpy(x, X)
    m2, R2, _ = align_vectors_scipy(x, X)
    t_ov = best_ms(lambda: similarity_closed_form(x, X), args.repeat)
    rows.append(("similarity closed form, 1000 pts", "numpy SVD", t_ov,
                 best_ms(lambda: umeyama_numpy(x, X), args.repeat), np.abs(cf.R - R1).max()))  # fmt: skip
    rows.append(("similarity closed form, 1000 pts", "scipy align_vectors", t_ov,
                 best_ms(lambda: align_vectors_scipy(x, X), args.repeat), np.abs(cf.R - R2).max()))  # fmt: skip
    ls = similarity_transform(x, X, sigma_target=0.02)
    p_sc = similarity_scipy_ls(x, X, cf.params())
    rows.append((
        "similarity LS + precision, 1000 pts", "scipy least_squares",
        best_ms(lambda: similarity_transform(x, X, sigma_target=0.02), args.repeat),
        best_ms(lambda: similarity_scipy_ls(x, X, cf.params()), args.repeat),
        np.abs(ls.x - p_sc).max(),
    ))  # fmt: skip

    # ---- resection, 50 points
    import cv2

    c = 152.7
    P = np.column_stack(
        [rng.uniform(-500, 500, 50), rng.uniform(-500, 500, 50), rng.uniform(0, 80, 50)]
    )
    X0, ang = np.array([30.0, -20.0, 1500.0]), np.array([0.02, -0.03, 1.2])
    xy = project(P, X0, matrix_from_opk(*ang), c) + rng.normal(0, 0.005, (50, 2))
    K = np.array([[c, 0, 0], [0, c, 0], [0, 0, 1.0]])
    uv = np.column_stack([xy[:, 0], -xy[:, 1]])  # OpenCV: y down, camera looking along +z
    res = resection(xy, P, c)
    flip = np.diag([1.0, -1.0, -1.0])

    def pnp(flag):
        ok, rvec, tvec = cv2.solvePnP(P, uv, K, None, flags=flag)
        Rc = cv2.Rodrigues(rvec)[0]
        return -Rc.T @ tvec.ravel(), Rc.T @ flip

    for flag, name in (
        (cv2.SOLVEPNP_ITERATIVE, "OpenCV solvePnP (LM)"),
        (cv2.SOLVEPNP_SQPNP, "OpenCV solvePnP (SQPnP)"),
    ):
        X0_cv, _ = pnp(flag)
        rows.append((
            "resection + precision, 50 pts", name,
            best_ms(lambda: resection(xy, P, c), args.repeat),
            best_ms(lambda f=flag: pnp(f), args.repeat),
            np.abs(res.x[:3] - X0_cv).max(),
        ))  # fmt: skip

    # ---- intersection, 10 000 points, 2 views
    n = 10_000
    Q = np.column_stack(
        [rng.uniform(-400, 400, n), rng.uniform(-400, 400, n), rng.uniform(0, 80, n)]
    )
    X0s = np.array([[-300.0, 0, 1500], [300.0, 0, 1500]])
    Rs = np.stack([np.eye(3), np.eye(3)])
    img, pt = np.repeat([0, 1], n), np.tile(np.arange(n), 2)
    xy2 = project(Q[pt], X0s[img], Rs[img], c) + rng.normal(0, 0.005, (2 * n, 2))
    cam_P = [
        K @ np.hstack([flip @ Rs[i].T, (-(flip @ Rs[i].T) @ X0s[i])[:, None]]) for i in range(2)
    ]
    a = np.vstack([xy2[:n, 0], -xy2[:n, 1]])
    b = np.vstack([xy2[n:, 0], -xy2[n:, 1]])

    def tri():
        h = cv2.triangulatePoints(cam_P[0], cam_P[1], a, b)
        return (h[:3] / h[3]).T

    lin = intersect_points(xy2, img, pt, X0s, Rs, c, rigorous=False)
    rows.append((
        "intersection linear, 10 000 pts", "OpenCV triangulatePoints",
        best_ms(lambda: intersect_points(xy2, img, pt, X0s, Rs, c, rigorous=False), args.repeat),
        best_ms(tri, args.repeat), np.abs(lin.xyz - tri()).max(),
    ))  # fmt: skip
    rig = intersect_points(xy2, img, pt, X0s, Rs, c)
    rows.append((
        "intersection rigorous + cov, 10 000", "OpenCV triangulatePoints",
        best_ms(lambda: intersect_points(xy2, img, pt, X0s, Rs, c), args.repeat),
        best_ms(tri, args.repeat), np.abs(rig.xyz - tri()).max(),
    ))  # fmt: skip

    import os

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"best of {args.repeat} runs, ms (ratio = orientviz / peer); "
          f"{os.cpu_count()} CPUs, 1-min load average {load:.1f}")  # fmt: skip
    head = (
        f"{'task':38s} {'peer':26s} {'orientviz':>10s} {'peer':>9s} {'ratio':>7s} {'max |Δ|':>10s}"
    )
    print(head)
    print("-" * len(head))
    for task, peer, t1, t2, diff in rows:
        print(f"{task:38s} {peer:26s} {t1:10.3f} {t2:9.3f} {t1 / t2:7.2f} {diff:10.2e}")
    print("max |Δ|: rotation elements (closed form), parameters (LS), X0 in m (resection), "
          "coordinates in m (intersection)")  # fmt: skip


if __name__ == "__main__":
    main()
