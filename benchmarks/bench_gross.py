"""Gross-error detection and self-calibration on simulated blocks: quality and time.

Run:  python benchmarks/bench_gross.py [--seeds 1 2] [--strips 4] [--images 10]

Part 1 — quality (per seed, then pooled): blocks from
:func:`orientviz.block.simulate.simulate_block` (σ = 5 µm) with 1 % of the rays
corrupted by 4-50 σ (20-250 µm, random direction). Cleaned by orientviz's data snooping
(one ray per point and image per adjustment), strict one-at-a-time snooping, the Danish
method, and — the peer a user would pick — SciPy ``least_squares`` with the robust
``soft_l1`` loss on the same bundle (rays with |v| > 3.29 σ̂ after the robust fit count
as detected). Reported:

* detection rate of the blunders ≥ 6 σ (target ≥ 95 %): a blunder counts as detected
  when its ray is excluded from the final adjustment (eliminated, or dropped with a
  2-ray point whose other ray was eliminated); also among the *testable* ones — those
  whose bias would produce |w| > δ0 = 4.13 (β0 = 80 %) in a coordinate, given the
  redundancy numbers: a blunder along a direction without redundancy (e.g. x of a
  2-ray point along the base) cannot be found by any method;
* false alarms: good rays excluded, in % of the good rays (target ≤ 1 %);
* check-point RMS (X, Y, Z) over that of the adjustment of the *error-free* block
  (target: within 10 %, i.e. ratio ≤ 1.10).

Part 2 — time, median of 3, same block, ratios against the plain bundle in the same
run: self-calibrating bundle (Ebner 12) — target ≤ 1.5×; data snooping — target ≤ 5×.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
from scipy.optimize import least_squares

from orientviz.adjust.gross import critical_value
from orientviz.block.additional import Ebner12
from orientviz.block.bundle import bundle_adjust
from orientviz.block.cleaning import clean_block
from orientviz.block.simulate import simulate_block
from orientviz.camera import project
from orientviz.model import CONTROL
from orientviz.rotation import matrix_from_opk

SIGMA_MM = 0.005


def make(seed: int, strips: int, images: int, gross: bool = True):
    kw = dict(rng=seed, n_check=30, control="perimeter", control_spacing=4)
    clean = simulate_block(strips, images, **kw)
    n = clean.block.n_observations
    g = {"count": max(1, round(0.01 * n)), "size_mm": (4 * SIGMA_MM, 50 * SIGMA_MM)}
    return clean, simulate_block(strips, images, gross=g, **kw) if gross else None


def scipy_robust(block):
    """Bundle with SciPy least_squares, soft_l1 loss; control fixed (not estimated)."""
    o = block.observations
    m, p = block.n_images, block.n_points
    ctrl = (block.points.role == CONTROL) & np.all(np.isfinite(block.points.xyz_known), axis=1)
    free_pts = np.flatnonzero(~ctrl)
    col = -np.ones(p, int)
    col[free_pts] = np.arange(free_pts.size)
    xyz_fixed = block.points.xyz.copy()
    xyz_fixed[ctrl] = block.points.xyz_known[ctrl]
    c = block.cameras.c[block.images.camera[o.image]]
    x0 = np.concatenate([np.hstack([block.images.X0, block.images.angles]).ravel(),
                         xyz_fixed[free_pts].ravel()])  # fmt: skip

    def unpack(x):
        eo = x[: 6 * m].reshape(m, 6)
        xyz = xyz_fixed.copy()
        xyz[free_pts] = x[6 * m :].reshape(-1, 3)
        return eo, xyz

    def fun(x):
        eo, xyz = unpack(x)
        R = matrix_from_opk(eo[:, 3], eo[:, 4], eo[:, 5])
        f = project(xyz[o.point], eo[o.image, :3], R[o.image], c)
        return ((f - o.xy) / SIGMA_MM).ravel()

    n = o.image.shape[0]
    rows = np.repeat(np.arange(2 * n), 1).reshape(n, 2)
    S = sp.lil_matrix((2 * n, x0.size), dtype=int)
    for a in range(2):
        for k in range(6):
            S[rows[:, a], 6 * o.image + k] = 1
        free = col[o.point] >= 0
        for k in range(3):
            S[rows[free, a], 6 * m + 3 * col[o.point[free]] + k] = 1
    res = least_squares(fun, x0, jac_sparsity=S.tocsr(), loss="soft_l1", f_scale=3.0,
                        x_scale="jac", method="trf", max_nfev=300)  # fmt: skip
    r = res.fun.reshape(n, 2)
    good = np.all(np.abs(r) < 3 * 3.0, axis=1)
    s0 = np.sqrt(np.median(r[good] ** 2) / 0.4549)  # MAD-type scale of the inliers
    flagged = np.flatnonzero(np.any(np.abs(r) > critical_value(0.001) * max(s0, 1.0), axis=1))
    eo, xyz = unpack(res.x)
    chk = block.points.role == 2
    return flagged, xyz[chk] - block.points.xyz_known[chk]


def quality(seeds, strips, images):
    rows = []
    pooled: dict[str, list] = {}
    for seed in seeds:
        clean, dirty = make(seed, strips, images)
        ref_adj = bundle_adjust(clean.block)
        ref = ref_adj.extra["check_rms"]
        idx = dirty.info["gross"]["index"]
        err = dirty.info["gross"]["error_mm"]
        size = np.hypot(*err.T) / SIGMA_MM
        big = set(idx[size >= 6].tolist())
        # testable: the bias would give |w| > δ0 = 4.13 in some coordinate (Baarda's
        # β0 = 80 % power), with the redundancy numbers of the error-free block
        r = np.nan_to_num(ref_adj.redundancy_numbers[: 2 * clean.block.n_observations])
        r = r.reshape(-1, 2)[idx]
        testable = set(
            idx[(size >= 6) & (np.max(np.abs(err) * np.sqrt(r), 1) / SIGMA_MM > 4.13)].tolist()
        )
        n = dirty.block.n_observations
        bad_all = set(idx.tolist())
        for name, kw in (
            ("snooping", dict(method="snooping")),
            ("snooping 1-at-a-time", dict(method="snooping", one_at_a_time=True)),
            ("danish", dict(method="danish")),
        ):
            t = time.perf_counter()
            c = clean_block(dirty.block, **kw)
            dt = time.perf_counter() - t
            excl = set(np.flatnonzero(~c.adjustment.extra["kept_rays"]).tolist())
            chk = c.adjustment.extra["check_rms"]
            rows.append((seed, name, len(big), len(big & excl), len(excl - bad_all), n - len(bad_all),
                         chk / ref, c.adjustments, dt, len(testable), len(testable & excl)))  # fmt: skip
        t = time.perf_counter()
        flagged, d = scipy_robust(dirty.block)
        dt = time.perf_counter() - t
        excl = set(flagged.tolist())
        chk = np.sqrt(np.nanmean(d**2, axis=0))
        rows.append((seed, "scipy soft_l1", len(big), len(big & excl), len(excl - bad_all),
                     n - len(bad_all), chk / ref, 1, dt, len(testable), len(testable & excl)))  # fmt: skip
    print(f"\nPart 1: 1 % blunders of 4-50 σ, {strips} strips × {images} images, seeds {seeds}")
    print(f"{'seed':>4} {'method':<22} {'≥6σ':>4} {'found':>6} {'rate':>6} {'testbl':>6} "
          f"{'found':>6} {'false':>6} {'false %':>8} {'chk/ref X':>9} {'Y':>6} {'Z':>6} "
          f"{'adj.':>5} {'time s':>7}")  # fmt: skip
    for seed, name, nb, nf, fa, ngood, ratio, nadj, dt, nt, ntf in rows:
        print(f"{seed:>4} {name:<22} {nb:>4} {nf:>6} {nf / max(nb, 1):6.1%} {nt:>6} {ntf:>6} "
              f"{fa:>6} {fa / ngood:8.2%} {ratio[0]:9.2f} {ratio[1]:6.2f} {ratio[2]:6.2f} "
              f"{nadj:>5} {dt:7.2f}")  # fmt: skip
        pooled.setdefault(name, []).append((nb, nf, fa, ngood, nt, ntf))
    print("pooled:")
    for name, v in pooled.items():
        a = np.array(v, float).sum(axis=0)
        print(f"     {name:<22} detection ≥6σ {a[1] / a[0]:6.1%} (target ≥ 95 %; of the testable "
              f"ones {a[5] / max(a[4], 1):6.1%}), false alarms {a[2] / a[3]:.2%} (target ≤ 1 %)")  # fmt: skip


def timing(seed, strips, images, reps=3):
    clean, dirty = make(seed, strips, images)
    b = dirty.block

    def med(f):
        ts = []
        for _ in range(reps):
            t = time.perf_counter()
            f()
            ts.append(time.perf_counter() - t)
        return float(np.median(ts))

    t_plain = med(lambda: bundle_adjust(clean.block))
    t_sc = med(lambda: bundle_adjust(clean.block, additional=Ebner12(), ap_sigma=10.0))
    t_snoop = med(lambda: clean_block(b, "snooping"))
    t_plain_dirty = med(lambda: bundle_adjust(b))
    print(f"\nPart 2: time, {strips} × {images} images, {b.n_observations} rays, median of {reps}")
    print(f"  plain bundle (error-free)     {t_plain:7.3f} s  1.00×")
    print(f"  self-calibrating (Ebner 12)   {t_sc:7.3f} s  {t_sc / t_plain:4.2f}×  (target ≤ 1.5×)")
    print(f"  plain bundle (with blunders)  {t_plain_dirty:7.3f} s  1.00×")
    print(
        f"  data snooping (whole run)     {t_snoop:7.3f} s  {t_snoop / t_plain_dirty:4.2f}×  (target ≤ 5×)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--strips", type=int, default=4)
    ap.add_argument("--images", type=int, default=10)
    a = ap.parse_args()
    quality(a.seeds, a.strips, a.images)
    timing(a.seeds[0], a.strips, a.images)


if __name__ == "__main__":
    main()
