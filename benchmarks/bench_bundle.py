"""Bundle block adjustment: orientviz against its peers on the same blocks, in one run.

    python benchmarks/bench_bundle.py                       # small + medium, all peers
    python benchmarks/bench_bundle.py --sizes large --peers pycolmap,gtsam
    python benchmarks/bench_bundle.py --reduced             # solver/ordering table of S

The blocks and the peers come from the shared bench (/work/shared/bench, see its
README): ``make_block.py`` generates the data into $ORIENTVIZ_BENCH_DATA (default
/tmp/orientviz-bench), ``run_peers.py`` runs each peer in its own process. Nothing of the
bench is copied here: its scripts are run, and its ``Problem.metrics`` (the formula every
peer is judged by: σ0, image RMS, ground RMS) is imported from that path at run time.

orientviz runs in its own worker process too (fresh interpreter → honest peak RSS):
``wall`` = building the Block from the in-memory arrays + ``bundle_adjust(precision=
False)``, best of N and median; ``+prec`` repeats it with precision (per-image and
per-point cofactor blocks, redundancy numbers). ``d_ref_mm`` is the RMS distance of the
tie points to the bench's tightly converged reference optimum.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "src"))  # this checkout's orientviz, not an installed one
BENCH = Path(os.environ.get("ORIENTVIZ_BENCH_DIR", "/work/shared/bench"))


def _bench_module(name: str):
    sys.path.insert(0, str(BENCH))
    import importlib

    return importlib.import_module(name)


def ensure_data(size: str) -> Path:
    from bench_blocks import data_dir, npz_path

    path = npz_path(size)
    if not path.exists():
        subprocess.run(
            [
                sys.executable,
                str(BENCH / "make_block.py"),
                "--size",
                size,
                "--out",
                str(data_dir()),
            ],
            check=True,
        )
    return path


# --------------------------------------------------------------------------- orientviz worker
def worker(npz: str, reps: int, precision: bool, solver: str, control: str = "fixed") -> dict:
    from bench_blocks import load_bench_block, user_arrays

    from orientviz.block import Block
    from orientviz.bundle import bundle_adjust
    from orientviz.rotation import matrix_from_opk, rotvec_from_matrix

    rp = _bench_module("run_peers")
    P = rp.Problem(npz, control=control)
    block, _ = load_bench_block(npz, control=control)
    arrays = user_arrays(block)  # the in-memory arrays a user would hold
    walls, cpus = [], []
    for _ in range(reps):
        t0, c0 = time.perf_counter(), time.process_time()
        b = Block.from_arrays(**arrays)
        res = bundle_adjust(b, control=control, precision=precision, solver=solver)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    m = block.n_images
    ext = res["exterior"].reshape(m, 6)
    R = matrix_from_opk(ext[:, 3], ext[:, 4], ext[:, 5], "opk")
    Rb = np.swapaxes(R, 1, 2)
    aa = rotvec_from_matrix(Rb)
    t = -np.einsum("nij,nj->ni", Rb, ext[:, :3])
    X = res["points"].reshape(-1, 3)
    out = P.metrics(aa, t, X)
    ref = Path(rp.reference_path(P))
    if ref.exists():
        z = np.load(ref)
        tie = ~P.is_ctrl
        d = X[tie] - z["X"][tie]
        out["d_ref_mm"] = 1000.0 * float(np.sqrt(np.mean(np.sum(d**2, axis=1))))
    out.update(
        solver="orientviz" + ("+prec" if precision else ""),
        wall_s=min(walls),
        wall_med_s=statistics.median(walls),
        cpu_s=min(cpus),
        iters=res.iterations,
        reps=reps,
        sigma0_orientviz=res.sigma0,
        converged=res.converged,
        reduced=res.reduced_info,
        peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    )
    return out


def run_orientviz(
    npz: Path, reps: int, precision: bool, threads: int, solver: str, control: str = "fixed"
) -> dict:
    env = dict(os.environ)
    for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[k] = str(threads)
    cmd = [sys.executable, __file__, "--worker", str(npz), "--reps", str(reps), "--solver", solver]
    cmd += ["--control", control]
    if precision:
        cmd.append("--precision")
    cp = subprocess.run(cmd, capture_output=True, text=True, env=env)
    lines = [ln for ln in cp.stdout.splitlines() if ln.startswith("@@RESULT ")]
    if not lines:
        return {"solver": "orientviz", "status": "failed", "error": cp.stderr[-1500:]}
    return json.loads(lines[-1][9:])


def run_peers(npz: Path, peers: str, threads: int, control: str = "fixed") -> list[dict]:
    cmd = [
        sys.executable,
        str(BENCH / "run_peers.py"),
        str(npz),
        "--solvers",
        peers,
        "--threads",
        str(threads),
        "--json",
        "/tmp/orientviz_bench_peers.json",
        "--control",
        control,
    ]
    cp = subprocess.run(cmd, capture_output=True, text=True)
    try:
        return json.load(open("/tmp/orientviz_bench_peers.json"))["results"]
    except (OSError, ValueError, KeyError):
        print(cp.stdout, cp.stderr, file=sys.stderr)
        return []


def fmt(v, nd=3):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{nd}g}" if abs(v) < 1e-2 else f"{v:.{nd}f}"
    return str(v)


def table(size: str, rows: list[dict]) -> str:
    base = next((r for r in rows if r.get("solver") == "pycolmap" and r.get("wall_s")), None)
    base = base or next((r for r in rows if r.get("solver") == "gtsam" and r.get("wall_s")), None)
    peer = base["solver"] if base else "pycolmap"
    head = (
        f"{'solver':18s} {'wall_s':>8s} {'med_s':>8s} {'iters':>5s} {'sigma0':>8s} "
        f"{'d_ref_mm':>9s} {'ground_m':>8s} {'peak_MB':>8s} {'/' + peer:>9s}"
    )
    lines = [f"## {size}", head, "-" * len(head)]
    for r in rows:
        ratio = r["wall_s"] / base["wall_s"] if base and r.get("wall_s") else None
        lines.append(
            f"{r.get('solver', '?'):18s} {fmt(r.get('wall_s')):>8s} {fmt(r.get('wall_med_s')):>8s} "
            f"{fmt(r.get('iters')):>5s} {fmt(r.get('sigma0'), 5):>8s} {fmt(r.get('d_ref_mm')):>9s} "
            f"{fmt(r.get('rms_ground_m'), 4):>8s} {fmt(r.get('peak_mb'), 4):>8s} "
            f"{fmt(ratio, 3):>9s}  {r.get('status', 'ok' if r.get('converged') else '')}"
        )
    return "\n".join(lines)


# --------------------------------------------------------------------------- reduced system
def reduced_comparison(size: str, reps: int, dense: bool) -> str:
    """Time factor + solve of the same reduced system S with each solver/ordering."""
    from bench_blocks import load_bench_block

    from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
    from orientviz.bundle.reduced import ReducedStructure, factor_reduced

    block, _ = load_bench_block(ensure_data(size))
    prob = BundleProblem(block, point_setup(block, "fixed"))
    st = BundleState(block.images.X0, block.images.angles, block.points.xyz, np.zeros(0))
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    base = prob.reduced
    variants = [
        ("banded, across-strip order", dict(solver="banded", orderings=list(base.orderings))),
        ("banded, RCM only", dict(solver="banded", orderings=[])),
        ("sparse, nested dissection", dict(solver="sparse", positions=block.images.X0)),
    ]
    if dense:
        variants.append(("dense Cholesky", dict(solver="dense")))
    ref = None
    lines = [
        f"## reduced system, {size}: {6 * block.n_images} unknowns, "
        f"{base.n_blocks} non-zero 6x6 blocks (upper); CPU seconds, best of {reps}",
        f"{'solver':28s} {'setup_s':>8s} {'factor_s':>9s} {'solve_s':>8s} {'median_f+s':>10s} "
        f"{'GFlop':>6s} {'bandwidth':>10s} {'max|dx-ref|':>12s}",
    ]
    for name, kw in variants:
        t0 = time.process_time()
        S = ReducedStructure(base.obs_cam, base.obs_pt, base.n_cam, base.n_pt, **kw)
        setup = time.process_time() - t0
        fac_t, sol_t, both = [], [], []
        for _ in range(reps):
            t0 = time.process_time()
            fac = factor_reduced(S, ne.blocks)
            t1 = time.process_time()
            x = fac.solve(ne.rhs)
            t2 = time.process_time()
            fac_t.append(t1 - t0)
            sol_t.append(t2 - t1)
            both.append(t2 - t0)
        ref = x if ref is None else ref
        bw = S.info.get("bandwidth_images", "-")
        if "flops" in S.info:
            gflop = S.info["flops"] / 1e9
        elif "kd" in S.info:  # LAPACK's band Cholesky: n·(kd + 1)² − 2(kd + 1)³/3
            b = S.info["kd"] + 1.0
            gflop = (S.n_reduced * b * b - 2.0 * b**3 / 3.0) / 1e9
        else:
            gflop = S.n_reduced**3 / 3e9
        lines.append(
            f"{name:28s} {setup:8.3f} {min(fac_t):9.4f} {min(sol_t):8.4f} "
            f"{statistics.median(both):10.4f} {gflop:6.2f} {bw!s:>10s} "
            f"{float(np.max(np.abs(x - ref)) / np.max(np.abs(ref))):12.2e}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--sizes", default="small,medium")
    ap.add_argument("--peers", default="pycolmap,gtsam,pyceres,scipy_jac")
    ap.add_argument("--threads", type=int, default=2, help="threads for the peers")
    ap.add_argument("--ov-threads", type=int, default=1, help="BLAS threads for orientviz")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--solver", default="auto", help="orientviz's reduced-system solver")
    ap.add_argument("--control", default="fixed", choices=["fixed", "weighted"])
    ap.add_argument("--reduced", action="store_true", help="compare solvers of S instead")
    ap.add_argument("--dense", action="store_true", help="include dense Cholesky in --reduced")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--precision", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        print(
            "@@RESULT "
            + json.dumps(worker(a.worker, a.reps, a.precision, a.solver, a.control), default=float)
        )
        return 0
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')}  load average {os.getloadavg()}")
    for size in a.sizes.split(","):
        if a.reduced:
            print(reduced_comparison(size, a.reps, a.dense or size != "large"), flush=True)
            continue
        npz = ensure_data(size)
        rows = run_peers(npz, a.peers, a.threads, a.control) if a.peers else []
        rows.append(run_orientviz(npz, a.reps, False, a.ov_threads, a.solver, a.control))
        rows.append(
            run_orientviz(npz, max(1, a.reps // 2), True, a.ov_threads, a.solver, a.control)
        )
        print(table(size, rows), flush=True)
        print(f"# orientviz reduced system: {rows[-2].get('reduced')}", flush=True)
        print(
            f"# orientviz CPU time (best): {rows[-2].get('cpu_s')} s; +prec {rows[-1].get('cpu_s')} s;"
            f" load average now {os.getloadavg()}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
