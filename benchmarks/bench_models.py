"""Benchmark: block adjustment with independent models on a COED-size block.

Ackermann (1974, Table 2) gives the CPU time per model of PAT-M-43 (3 planimetry/height
iterations, 72 models, 1341 points): 0.85 s on a CDC 6600 … 20 s on an IBM 360/50.
The COED block (Bild 5) had 2193 models and 25 580 model points. This script times
orientviz on a simulated block of exactly 2193 models (43 strips × 52 images, standard
points plus 3 random points per image, perimeter control every 4 bases) and sets the
CPU seconds per model beside Table 2. Peers in the same run:

* the factorisation of the reduced normal system of one Gauss-Newton step: SuperLU with
  a minimum-degree ordering (orientviz's default) against reverse Cuthill-McKee + banded
  Cholesky (the bandwidth minimisation of Ackermann's time, §12);
* on a smaller block (3 × 8 images), SciPy's ``least_squares`` (TRF, sparse Jacobian)
  on the same 7-parameter problem (points and models as unknowns) — the agreement of
  the solutions and the time ratio.

Extensions in the same run (``--extras``; ``--extras-only`` skips the COED block), on
a 6 × 20 block with systematic image errors (model bending) and statoscope/APR data:
the independent-model adjustment without and with model deformation parameters
(shared by the block, per strip), and without and with auxiliary data as joint
observations; the bundle without and with the joint auxiliary data, and the alternation
of :func:`orientviz.bundle.adjust_with_auxiliary` as the peer of the joint one.

Usage::

    python benchmarks/bench_models.py            # best of 3
    python benchmarks/bench_models.py --reps 1 --no-peers
    python benchmarks/bench_models.py --reps 1 --extras-only
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp

from orientviz.simulate import simulate_block
from orientviz.stereo_models import form_models, independent_models

TABLE2 = {
    "CDC 6600": 0.85, "CDC 6400": 3.2, "IBM 360/50": 20.0, "IBM 360/65": 5.1,
    "IBM 360/75": 3.7, "IBM 360/85": 0.94, "UNIVAC 1106": 2.8, "UNIVAC 1108": 1.4,
    "IBM 370/145": 6.2, "IBM 370/155": 3.8, "IBM 370/158": 2.2, "IBM 370/165": 1.1,
}  # fmt: skip


def timed(fn, reps):
    best_w, best_c, out = np.inf, np.inf, None
    for _ in range(reps):
        w, c = time.perf_counter(), time.process_time()
        out = fn()
        best_w = min(best_w, time.perf_counter() - w)
        best_c = min(best_c, time.process_time() - c)
    return out, best_w, best_c


def reduced_system_peer(sim, ms):
    """CPU time of one factorisation of the reduced system: SuperLU (minimum degree, the
    default) vs reverse Cuthill-McKee + banded Cholesky (Ackermann's bandwidth idea)."""
    from orientviz.stereo_models import _normal as mn
    from orientviz.stereo_models import tie_setup
    from orientviz.stereo_models._adjust import _rows3

    su = tie_setup(sim.block, ms)
    n = ms.n_models
    lam, R, T = np.ones(n), ms.start_rotation.copy(), ms.start_translation.copy()
    su.init_points(lam, R, T)
    r, J = _rows3(su, lam, R, T)
    k = r.shape[0]
    args = (np.repeat(su.row_model, 3), J.reshape(3 * k, 7), su.scalar[su.row_point].ravel(),
            np.full(3 * k, 1.0), r.ravel(), n, su.n_scalar)  # fmt: skip
    captured = {}
    orig = mn.factor_spd

    def spy(S, names, context=""):
        captured["S"] = S
        return orig(S, names, context)

    mn.factor_spd = spy
    try:
        t0 = time.perf_counter()
        mn.solve_rows(*args, prior_w=su.prior_w, prior_e=su.prior_e())
        t_ov = time.perf_counter() - t0
    finally:
        mn.factor_spd = orig
    S = captured["S"]
    names = [f"p{i}" for i in range(S.shape[0])]
    t = time.process_time()
    orig(S, names, solver="splu")
    t_lu = time.process_time() - t
    t = time.process_time()
    orig(S, names, solver="banded")
    t_band = time.process_time() - t
    return S.shape[0], t_ov, t_lu, t_band


def least_squares_peer(reps):
    """orientviz vs scipy.optimize.least_squares on a 3 × 8 block (7 p. per model)."""
    from scipy.optimize import least_squares

    from orientviz.rotation import matrix_from_rotvec
    from orientviz.stereo_models import tie_setup
    from orientviz.stereo_models._adjust import _rows3

    sim = simulate_block(3, 8, rng=np.random.default_rng(3), extra=3)
    ms = form_models(sim.block)
    res, w_ov, _ = timed(lambda: independent_models(sim.block, models=ms), reps)
    su = tie_setup(sim.block, ms)
    n = ms.n_models
    R0, T0 = ms.start_rotation.copy(), ms.start_translation.copy()
    su.init_points(np.ones(n), R0, T0)
    X0 = su.X.copy()
    free = su.scalar >= 0
    sxy, sz = res.sigma_model
    wsq = np.array([1 / sxy, 1 / sxy, 1 / sz])

    def fun(p):
        rv, lam, T = p[: 3 * n].reshape(n, 3), p[3 * n : 4 * n], p[4 * n : 7 * n].reshape(n, 3)
        R = R0 @ matrix_from_rotvec(rv)
        su.X[free] = p[7 * n :]
        r, _ = _rows3(su, 1.0 + lam, R, T)
        return (r * wsq).ravel()

    p0 = np.concatenate([np.zeros(3 * n), np.zeros(n), T0.ravel(), X0[free]])
    # sparsity: each row depends on its model's 7 parameters and its point's coordinates
    rows3 = np.arange(3 * su.row_model.size)
    jm = np.repeat(su.row_model, 3)
    cols = [np.stack([3 * jm + a for a in range(3)], 1), (3 * n + jm)[:, None],
            np.stack([4 * n + 3 * jm + a for a in range(3)], 1)]  # fmt: skip
    sc = su.scalar[su.row_point].ravel()
    has = sc >= 0
    rr = np.concatenate([np.repeat(rows3, 7), rows3[has]])
    cc = np.concatenate([np.hstack(cols).ravel(), 7 * n + sc[has]])
    pat = sp.coo_matrix((np.ones(rr.size), (rr, cc)), shape=(rows3.size, p0.size))
    t = time.perf_counter()
    out = least_squares(
        fun, p0, jac_sparsity=pat.tocsr(), method="trf", x_scale="jac", xtol=1e-12, ftol=1e-12
    )
    w_sp = time.perf_counter() - t
    su.X[free] = out.x[7 * n :]
    d = np.abs(su.X[: su.tie_points.size] - res.points[su.tie_points]).max()
    return ms.n_models, w_ov, w_sp, d, out.nfev


def extras(reps) -> None:
    """Self-calibration and joint auxiliary data: times with vs without, same block."""
    from orientviz.bundle import adjust_with_auxiliary, bundle_adjust
    from orientviz.simulate import check_errors, height_control_at_ends, simulate_auxiliary
    from orientviz.simulate import systematic as sy

    sim = simulate_block(
        6, 20, rng=np.random.default_rng(20), control="chains", control_kind="xy+z",
        chain_spacing=2, n_check=40, systematic=sy.model_bending(15.0), sigma_image_mm=0.003,
    )  # fmt: skip
    b = sim.block
    ms = form_models(b)
    print(f"# extras: {b.summary()}; {ms.n_models} models; model bending 15 µm, σ 3 µm")
    print("# case                                   wall_s  iterations  σ0     μxy m  μz m")

    def row(name, fn, xyz_of):
        res, w, _ = timed(fn, reps)
        xy, z = check_errors(sim, xyz_of(res))
        adj = getattr(res, "adjustment", res)
        # steps of one adjustment, or the bundle adjustments of the alternation
        its = getattr(res, "rounds", None) or sum(1 for h in adj.history if h.index > 0)
        print(f"{name:40s} {w:6.2f}  {its:4d}       {adj.sigma0:5.2f}  {xy:.3f}  {z:.3f}")
        return w

    xyz = lambda r: r.points  # noqa: E731
    pts = lambda r: getattr(r, "adjustment", r).points  # noqa: E731
    w0 = row("models, 7 parameters", lambda: independent_models(b, models=ms), xyz)
    w1 = row("models + deformation (block)", lambda: independent_models(
        b, models=ms, deformation="classical", deformation_group="block"), xyz)  # fmt: skip
    w2 = row("models + deformation (strip)", lambda: independent_models(
        b, models=ms, deformation="classical", deformation_group="strip"), xyz)  # fmt: skip
    print(f"# self-calibration / plain: block {w1 / w0:.2f}, strip {w2 / w0:.2f}")
    ends = height_control_at_ends(b)
    rng = np.random.default_rng(1)
    stat = simulate_auxiliary(
        sim, "statoscope", rng=rng, sigma=0.3, offset_sigma=20.0, drift_sigma=2.0
    )
    apr = simulate_auxiliary(sim, "apr", rng=rng, sigma=0.5, offset_sigma=20.0)
    aux = [stat, apr]
    w3 = row("models, heights at the ends", lambda: independent_models(ends, models=ms), xyz)
    w4 = row("models, ends + statoscope + APR (joint)", lambda: independent_models(
        ends, models=ms, auxiliary=aux), xyz)  # fmt: skip
    w5 = row("bundle, heights at the ends", lambda: bundle_adjust(ends, control="weighted"), pts)
    w6 = row("bundle, ends + statoscope + APR (joint)", lambda: bundle_adjust(
        ends, control="weighted", auxiliary=aux), pts)  # fmt: skip
    w7 = row("bundle, ends + stat. + APR (alternation)", lambda: adjust_with_auxiliary(
        ends, aux, tol=0.005), pts)  # fmt: skip
    print(f"# joint auxiliary / plain: models {w4 / w3:.2f}, bundle {w6 / w5:.2f}; "
          f"alternation / joint (bundle) {w7 / w6:.1f}")  # fmt: skip


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--extras", action="store_true", help="also self-calibration, auxiliary data")
    ap.add_argument("--extras-only", action="store_true")
    a = ap.parse_args(argv)
    if a.extras_only:
        extras(a.reps)
        return
    t = time.perf_counter()
    sim = simulate_block(43, 52, rng=np.random.default_rng(2193), extra=3)
    t_sim = time.perf_counter() - t
    b = sim.block
    (ms, w_form, c_form) = timed(lambda: form_models(b), a.reps)
    print(f"# block: {b.summary()}; {ms.n_models} models, {ms.xyz.shape[0]} model points; "
          f"simulated in {t_sim:.1f} s")  # fmt: skip
    print("# step                         wall_s   cpu_s   cpu_s/model  iterations")
    print(
        f"model formation (rel. or.)     {w_form:7.2f} {c_form:7.2f}   {c_form / ms.n_models:.5f}      {ms.iterations}"
    )
    results = {}
    for method in ("rigorous", "pat-m"):
        res, w, c = timed(lambda m=method: independent_models(b, models=ms, method=m), a.reps)
        results[method] = res
        e = res.points - sim.truth.points.xyz
        print(f"adjustment {method:9s}          {w:7.2f} {c:7.2f}   {c / ms.n_models:.5f}      "
              f"{len(res.history)}   (σ0 {res.sigma0:.2f}, RMS error xy {np.sqrt(np.nanmean(e[:, :2] ** 2)):.3f} m, "
              f"z {np.sqrt(np.nanmean(e[:, 2] ** 2)):.3f} m)")  # fmt: skip
    c_rig = None
    print("# Ackermann Table 2, PAT-M-43 CPU s/model (3 iterations, 72 models) and the ratio")
    _, _, c_rig = timed(lambda: independent_models(b, models=ms, method="pat-m", max_iter=3), 1)
    per = c_rig / ms.n_models
    print(f"orientviz pat-m, 3 iterations: {per:.5f} s/model")
    for k, v in TABLE2.items():
        print(f"  {k:12s} {v:5.2f} s/model   orientviz is {v / per:8.0f} × faster")
    if not a.no_peers:
        n, t_ov, t_lu, t_band = reduced_system_peer(sim, ms)
        print(f"# reduced system ({n} unknowns), CPU s per factorisation: SuperLU/MMD {t_lu:.2f}, "
              f"RCM + banded Cholesky {t_band:.2f} (ratio {t_band / t_lu:.1f}); one linear step {t_ov:.2f} s wall")  # fmt: skip
        nm, w_ov, w_sp, d, nfev = least_squares_peer(a.reps)
        print(f"# 3 × 8 block ({nm} models): orientviz rigorous {w_ov:.3f} s, scipy least_squares "
              f"{w_sp:.2f} s ({nfev} evaluations), ratio {w_sp / w_ov:.0f}; max coordinate difference {d * 1000:.3f} mm")  # fmt: skip
    if a.extras:
        extras(a.reps)


if __name__ == "__main__":
    main()
