"""Gross-error detection on simulated blocks: detection, false alarms, check points, time.

Run:  python benchmarks/bench_gross.py [--seeds 1 2 …] [--strips 4] [--images 10]
                                        [--tie grid|gruber] [--large 30 70] [--reps 1]
                                        [--no-large | --large-only]

Part 1 — quality (pooled over seeds): blocks from
:func:`orientviz.simulate.simulate_block` (σ = 5 µm, 60 %/20 % overlap, XYZ
perimeter control, 30 check points) with 1 % of the rays corrupted by 4-50 σ
(20-250 µm, random direction). ``--tie grid`` (default) has the Gruber points plus a
30 mm grid of tie points — the uniform spread of automatic tie points, where about 60 %
of the tie points lie in only two images; ``--tie gruber`` keeps only the Gruber points
(classical point selection, every tie point in ≥ 3 images; 10 check points, seeds
1..``--gruber-seeds``: these blocks have only ~340 rays, 3 errors each). Methods: orientviz's data
snooping as it was (per-coordinate w-test, exact every round, check rays untested), with
the w-test, with the 2-D test of image points without and with the separability rule
(the default of ``clean_block``: all with check rays tested and fast screening), the Danish
method, and SciPy ``least_squares`` (robust ``soft_l1`` loss on the same bundle; rays
with abs(v) > 3.29 σ̂ after the fit count as detected; no check-ray test).

* detection of the errors ≥ 6 σ (target ≥ 95 %): the ray is excluded from the final
  adjustment (eliminated, or dropped with a 2-ray point whose other ray went);
* testable: the bias gives the 2-D test a non-centrality λ = ∇ᵀP½RP½∇ ≥ λ0 = δ0² = 17.1
  (found with ≥ 80 % power) with the exact redundancy blocks R of the error-free block;
* each miss is classified: ``untestable-2ray`` (2-ray point, error along the base),
  ``untestable`` (other), ``wrong-ray`` (another ray of its point was eliminated and the
  error stayed), ``below-k`` (tested, not rejected);
* false alarms: good rays excluded, in % of the good rays (target ≤ 1 %); also on the
  error-free block (expected: about the test level α, 0.1-0.28 % per ray, doubled for
  2-ray points, whose second ray leaves with the first);
* check-point RMS (X, Y, Z) over that of the adjustment of the error-free block
  (target ≤ 1.10), pooled RMS over all seeds.

Part 2 — the 2 100-image block (30 × 70, ``--large``): the same quality figures for the
default method, and time — plain bundle with and without precision, data snooping
(whole run) — in one process, median of ``--reps``; target snooping ≤ 5× the plain bundle.
"""

from __future__ import annotations

import argparse
import os
import time

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # one BLAS thread: CPU time = work, on a shared machine

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

from orientviz.adjust.gross import critical_value, noncentrality  # noqa: E402
from orientviz.adjust.gross2d import noncentrality_2d  # noqa: E402
from orientviz.block import CHECK, CONTROL  # noqa: E402  (after the sys.path insert)
from orientviz.bundle import bundle_adjust, bundle_solver, clean_block  # noqa: E402
from orientviz.camera import project  # noqa: E402
from orientviz.errors import AdjustmentError  # noqa: E402
from orientviz.rotation import matrix_from_opk  # noqa: E402
from orientviz.simulate import simulate_block  # noqa: E402

SIGMA_MM = 0.005
METHODS = {
    "before: w-test, exact, no check rays": dict(
        method="snooping", test="w", fast=False, check_rays=False, separation=0.0
    ),
    "snooping w-test": dict(method="snooping", test="w", separation=0.0),
    "snooping 2-D, no separ.": dict(method="snooping", separation=0.0),
    "snooping 2-D (default)": dict(method="snooping"),
    "danish": dict(method="danish"),
}
MISS = ("untestable-2ray", "untestable", "wrong-ray", "below-k")


def make(seed: int, strips: int, images: int, tie: str):
    # Gruber points only: ~8 tie points per image, so fewer of them become check points
    kw = dict(rng=seed, n_check=30 if tie == "grid" else 10, control="perimeter")
    kw["extra"] = "grid" if tie == "grid" else None
    clean = simulate_block(strips, images, **kw)
    n = clean.block.n_observations
    g = {"count": max(1, round(0.01 * n)), "size_mm": (4 * SIGMA_MM, 50 * SIGMA_MM)}
    return clean, simulate_block(strips, images, gross=g, **kw)


def scipy_robust(block):
    """Bundle with SciPy least_squares, soft_l1 loss; control fixed (not estimated)."""
    o = block.observations
    m = block.n_images
    ctrl = (block.points.role == CONTROL) & np.all(np.isfinite(block.points.xyz_known), axis=1)
    free_pts = np.flatnonzero(~ctrl)
    col = -np.ones(block.n_points, int)
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
    rows = np.arange(2 * n).reshape(n, 2)
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
    flagged = np.any(np.abs(r) > critical_value(0.001) * max(s0, 1.0), axis=1)
    _, xyz = unpack(res.x)
    chk = block.points.role == CHECK
    return flagged, xyz[chk] - block.points.xyz_known[chk]


def truth_info(clean, dirty):
    """Per corrupted ray: size in σ, λ of the 2-D test, rays of its point, check ray?"""
    b = dirty.block
    ref_solve = bundle_solver(clean.block)
    ref = ref_solve(np.ones(2 * b.n_observations))
    n = b.n_observations
    idx = dirty.info["gross"]["index"]
    err = dirty.info["gross"]["error_mm"]
    r = ref.redundancy_numbers.reshape(n, 2)[idx]
    lam = noncentrality_2d(err, b.observations.sigma[idx], r, ref.redundancy_xy[idx])
    rays = b.rays_per_point()[b.observations.point[idx]]
    return dict(
        idx=idx, size=np.hypot(*err.T) / SIGMA_MM, lam=lam, rays=rays,
        check=b.points.role[b.observations.point[idx]] == CHECK,
        ref_rms=ref.check_rms, n=n,
    )  # fmt: skip


def classify(info, excluded, eliminated, block):
    """Counts of detected / missed-by-class for the errors ≥ 6 σ."""
    out = dict.fromkeys(("n", "det", "testable", "det_testable", *MISS), 0)
    lam0 = noncentrality() ** 2
    elim = np.zeros(info["n"], bool)
    elim[eliminated] = True
    pt = block.observations.point
    for j, s, lam, rays in zip(info["idx"], info["size"], info["lam"], info["rays"]):
        if s < 6:
            continue
        out["n"] += 1
        testable = lam >= lam0
        out["testable"] += testable
        if excluded[j]:
            out["det"] += 1
            out["det_testable"] += testable
        elif not testable:
            out["untestable-2ray" if rays == 2 else "untestable"] += 1
        elif elim[(pt == pt[j]) & (np.arange(info["n"]) != j)].any():
            out["wrong-ray"] += 1
        else:
            out["below-k"] += 1
    return out


def run_method(name, block, info):
    t = time.perf_counter()
    if name == "scipy soft_l1":
        excluded, d = scipy_robust(block)
        chk2 = np.nanmean(d**2, axis=0)
        nadj, elim, broke = 1, np.flatnonzero(excluded), 0
    else:
        try:
            c = clean_block(block, **METHODS[name])
        except (AdjustmentError, np.linalg.LinAlgError):
            # gave up (CleaningBreakdown), or the weights made the block singular or
            # disconnected: nothing cleaned, the plain bundle stands
            c = None
        if c is None:
            excluded = np.zeros(info["n"], bool)
            chk2 = bundle_adjust(block).check_rms ** 2
            nadj, elim, broke = 0, np.zeros(0, int), 1
        else:
            excluded = ~c.adjustment.subset.kept_rays
            chk2 = c.adjustment.check_rms**2
            nadj, elim, broke = c.adjustments, c.eliminated, 0
    dt = time.perf_counter() - t
    good = np.ones(info["n"], bool)
    good[info["idx"]] = False
    row = classify(info, excluded, elim, block)
    row.update(fa=int((excluded & good).sum()), good=int(good.sum()), chk2=chk2,
               ref2=info["ref_rms"] ** 2, adj=nadj, time=dt, broke=broke)  # fmt: skip
    return row


def error_free_rate(clean, name):
    """False alarms on the error-free block: rays excluded and tests that rejected."""
    try:
        c = clean_block(clean.block, **METHODS[name])
    except AdjustmentError:  # counted apart (weak blocks: an image left undeterminable)
        return 0, 0, 0, 1
    excluded = int((~c.adjustment.subset.kept_rays).sum())
    rejected = sum(1 for e in c.log if e.action == "eliminated")
    return excluded, rejected, clean.block.n_observations, 0


def print_table(title, rows, clean_rates):
    print(f"\n{title}")
    head = (f"| method | ≥6σ | detected | testable | det. of testable | {' | '.join(MISS)} | "
            "false alarms | error-free: excl. / rejections | chk/ref X, Y, Z | adj. | time s |")  # fmt: skip
    print(head)
    print("|" + " --- |" * (head.count("|") - 1))
    for name, rs in rows.items():
        a = {k: sum(r[k] for r in rs) for k in ("n", "det", "testable", "det_testable", "fa", "good",
                                                  "adj", "broke", *MISS)}  # fmt: skip
        ratio = np.sqrt(sum(r["chk2"] for r in rs) / sum(r["ref2"] for r in rs))
        worst = np.max([np.sqrt(r["chk2"] / r["ref2"]) for r in rs], axis=0)
        t = sum(r["time"] for r in rs)
        cr = clean_rates.get(name)
        crs = f"{cr[0] / cr[2]:.2%} / {cr[1] / cr[2]:.2%}" if cr else "–"
        if cr and cr[3]:
            crs += f" ({cr[3]} block(s) failed)"
        print(f"| {name} | {a['n']} | {a['det']} ({a['det'] / a['n']:.1%}) | {a['testable']} "
              f"({a['testable'] / a['n']:.1%}) | {a['det_testable'] / max(a['testable'], 1):.1%} | "
              + " | ".join(str(a[k]) for k in MISS)
              + f" | {a['fa']} ({a['fa'] / a['good']:.2%}) | {crs} | "
              f"{ratio[0]:.3f}, {ratio[1]:.3f}, {ratio[2]:.3f} (worst {worst.max():.2f}) | "
              f"{a['adj']} | {t:.1f} |" + (f" gave up on {a['broke']} block(s)" if a["broke"] else ""))  # fmt: skip


def quality(seeds, strips, images, tie):
    rows: dict[str, list] = {}
    clean_rates: dict[str, list] = {}
    geom = []
    skipped = []
    for seed in seeds:
        clean, dirty = make(seed, strips, images, tie)
        try:
            info = truth_info(clean, dirty)
        except (AdjustmentError, np.linalg.LinAlgError):
            skipped.append(seed)  # the error-free bundle itself fails (weak geometry)
            continue
        b = dirty.block
        geom.append(((b.rays_per_point()[b.observations.point] == 2).mean(), info["check"].sum()))
        for name in (*METHODS, "scipy soft_l1"):
            rows.setdefault(name, []).append(run_method(name, b, info))
        for name in ("snooping w-test", "snooping 2-D, no separ.", "snooping 2-D (default)"):
            e = error_free_rate(clean, name)
            acc = clean_rates.setdefault(name, [0, 0, 0, 0])
            for k in range(4):
                acc[k] += e[k]
    g = np.array(geom, float)
    print_table(
        f"Part 1: {strips} strips × {images} images, tie points {tie!r}, seeds {seeds}; "
        f"rays in 2-ray points {g[:, 0].mean():.1%}, errors on check-point rays "
        f"{int(g[:, 1].sum())}"
        + (
            f"; seeds {skipped} skipped: the error-free bundle fails (not determinable)"
            if skipped
            else ""
        ),
        rows,
        clean_rates,
    )


def large(strips, images, reps):
    clean, dirty = make(1, strips, images, "grid")
    b = dirty.block

    def med(f):
        ts, cs, out = [], [], None
        for _ in range(reps):
            t, cpu = time.perf_counter(), time.process_time()
            out = f()
            ts.append(time.perf_counter() - t)
            cs.append(time.process_time() - cpu)
        return (float(np.median(ts)), float(np.median(cs))), out

    t_plain, _ = med(lambda: bundle_adjust(b, precision=False))
    t_prec, _ = med(lambda: bundle_adjust(b))
    t_snoop, c = med(lambda: clean_block(b, "snooping"))
    info = truth_info(clean, dirty)
    good = np.ones(info["n"], bool)
    good[info["idx"]] = False
    excluded = ~c.adjustment.subset.kept_rays
    row = classify(info, excluded, c.eliminated, b)
    ratio = c.adjustment.check_rms / info["ref_rms"]
    print(f"\nPart 2: {strips} × {images} = {b.n_images} images, {b.n_observations} rays, "
          f"{info['idx'].size} errors, median of {reps}, load {os.getloadavg()[0]:.1f}")  # fmt: skip
    print(f"  quality (snooping 2-D, default): ≥6σ {row['n']}, detected {row['det'] / row['n']:.1%}, "
          f"testable {row['testable'] / row['n']:.1%}, detected of testable "
          f"{row['det_testable'] / max(row['testable'], 1):.1%}, misses "
          + ", ".join(f"{k} {row[k]}" for k in MISS)
          + f"; false alarms {(excluded & good).sum() / good.sum():.2%}; chk/ref "
          f"{ratio[0]:.3f}, {ratio[1]:.3f}, {ratio[2]:.3f}; {c.adjustments} adjustments")  # fmt: skip
    print("| run | wall s | CPU s | CPU ratio to plain | to plain + precision |")
    print("| --- | --- | --- | --- | --- |")
    for name, t in (("plain bundle (precision=False)", t_plain),
                    ("plain bundle + precision", t_prec),
                    ("data snooping, whole run (target ≤ 5×)", t_snoop)):  # fmt: skip
        print(f"| {name} | {t[0]:.2f} | {t[1]:.2f} | {t[1] / t_plain[1]:.2f} | "
              f"{t[1] / t_prec[1]:.2f} |")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5, 6, 7, 8])
    ap.add_argument("--strips", type=int, default=4)
    ap.add_argument("--images", type=int, default=10)
    ap.add_argument("--tie", choices=("grid", "gruber", "both"), default="both")
    ap.add_argument("--gruber-seeds", type=int, default=24, help="seeds 1..N for --tie gruber")
    ap.add_argument("--large", type=int, nargs=2, default=[30, 70], metavar=("STRIPS", "IMAGES"))
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--no-large", action="store_true")
    ap.add_argument("--large-only", action="store_true", help="only part 2 (time, large block)")
    a = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.1f}")
    for tie in () if a.large_only else ("grid", "gruber") if a.tie == "both" else (a.tie,):
        seeds = a.seeds if tie == "grid" else list(range(1, a.gruber_seeds + 1))
        quality(seeds, a.strips, a.images, tie)
    if not a.no_large:
        large(*a.large, a.reps)


if __name__ == "__main__":
    main()
