"""Unordered close-range networks: orientviz's bundle against pycolmap's, in one run.

    python benchmarks/bench_unordered.py                    # 30 and 150 images, both track kinds
    python benchmarks/bench_unordered.py --large            # adds 600 images
    python benchmarks/bench_unordered.py --sizes 150 --poor-only
    python benchmarks/bench_unordered.py --sizes 30 --peers pyceres --no-poor
    python benchmarks/bench_unordered.py --sizes 150 --peers "" --no-poor --lens undistort,fixed

The networks come from ``pycolmap.synthesize_dataset`` (one PINHOLE camera, 1024 × 768 px,
f = 1280 px; 0.7 px Gaussian noise on the image points, ``synthesize_noise``):
``random`` tracks (each point seen by ``--track-length`` random images) and
``visibility`` tracks (each point seen by every image, ``track_length = -1``). Each is
written as a COLMAP text model to a temporary folder (nothing is kept) and read by both
solvers from there: orientviz through ``orientviz.io.colmap.read_colmap`` (the reader
behind ``orientviz import-colmap``, σ = 0.7 px), pycolmap through
``pycolmap.Reconstruction``. 12 control points (random, tracks of ≥ 3 images) are held
fixed in both, the intrinsics are constant, the datum comes from the control.

Every solve runs in its own fresh worker process (honest peak RSS, ``ru_maxrss``):
``wall`` = orientviz ``bundle_adjust(precision=False)`` on the imported Block (the
import itself is not timed), or pycolmap's adjuster set-up + ``solve()`` with
SPARSE_SCHUR, function tolerance 1e-10 (as in the shared peer bench), 1 thread each.
``cpu`` = the CPU time (``time.process_time``) of the same span (orientviz and pycolmap;
on a loaded machine the CPU ratio is the steadier one, on an idle one both agree).
Best of ``--reps``; peak MB = the worker's VmHWM (interpreter and libraries included).
The same optimum is checked on the results: σ0 of both (pycolmap's from its final
cost, 2·cost / σ² / redundancy), and the largest difference of projection centres and
of tie points between the two solutions, in units of the scene (about 5 units across).

Extra peers (``--peers``, default ``pycolmap,gtsam``): GTSAM (Levenberg-Marquardt, METIS
ordering, control held by priors of 1e-5 units) and pyceres (Ceres with SPARSE_SCHUR and
the projection as Python cost functions: slow by construction, small networks only), both
through the shared peer bench's solvers (``/work/shared/bench/run_peers.py``, given the
network in its BAL camera convention); wall = their set-up + solve.

``--poor`` (on by default for 150 images): orientations perturbed by 20° (random axes)
and 1 unit (random directions), points re-intersected from the perturbed orientations
(linear ray intersection), control kept; both solvers start there (max 100 iterations
for pycolmap, orientviz's default ``max_iter``), and the table says whether each
reaches the optimum of the good start.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))  # this checkout's orientviz, not an installed one

SIGMA_PX = 0.7
N_CONTROL = 12
F_PX, W_PX, H_PX = 1280.0, 1024, 768


# --------------------------------------------------------------------------- generator
def generate(
    directory: Path, n_images: int, tracks: str, rng: np.random.Generator, track_length: int = 8
) -> list[int]:
    """Write a synthetic unordered network as a COLMAP text model; return the control ids.

    Parameters
    ----------
    directory : Path
        Output folder (``cameras.txt``, ``images.txt``, ``points3D.txt``).
    n_images : int
        Number of images (one PINHOLE camera).
    tracks : {"random", "visibility"}
        ``random``: every point in ``track_length`` random images, 40 points per image;
        ``visibility``: every point in every image, 1000 points.
    rng : numpy.random.Generator
        Seeds pycolmap's generator and draws the control points.
    track_length : int
        Images per point for random tracks.

    Returns
    -------
    list of int
        POINT3D_IDs of the 12 control points (tracks of at least 3 images).
    """
    import pycolmap

    pycolmap.set_random_seed(int(rng.integers(0, 2**31 - 1)))
    random = tracks == "random"
    opt = pycolmap.SyntheticDatasetOptions(
        num_rigs=1,
        num_cameras_per_rig=1,
        num_frames_per_rig=n_images,
        num_points3D=40 * n_images if random else 1000,
        track_length=min(track_length, n_images) if random else -1,
        camera_model_id=pycolmap.CameraModelId.PINHOLE,
        camera_params=[F_PX, F_PX, W_PX / 2, H_PX / 2],
        camera_width=W_PX,
        camera_height=H_PX,
        num_points2D_without_point3D=0,
    )
    rec = pycolmap.synthesize_dataset(opt)
    pycolmap.synthesize_noise(pycolmap.SyntheticNoiseOptions(point2D_stddev=SIGMA_PX), rec)
    directory.mkdir(parents=True, exist_ok=True)
    rec.write_text(str(directory))
    ids = np.array(sorted(p for p, pt in rec.points3D.items() if pt.track.length() >= 3))
    return sorted(int(i) for i in rng.choice(ids, N_CONTROL, replace=False))


def read_block(directory: Path, control: list[int], lens: str = "undistort"):
    """The COLMAP model as an orientviz Block (σ = 0.7 px) with the control points fixed.

    Intrinsics constant, as in pycolmap's run: a PINHOLE camera has nothing to
    undistort, so ``lens="undistort"`` gives the plain collinearity model with the camera
    held; ``lens="fixed"`` keeps COLMAP's pixels with the camera as a held lens model
    without distortion (the same model: ``bundle_adjust`` solves it as the plain one).
    """
    from orientviz.block import CONTROL
    from orientviz.io.colmap import read_colmap

    block = read_colmap(directory, sigma_px=SIGMA_PX, lens=lens)
    index = {pid: k for k, pid in enumerate(block.points.ids)}
    sel = np.array([index[str(c)] for c in control])
    block.points.role[sel] = CONTROL
    block.points.xyz_known[sel] = block.points.xyz[sel]
    return block


def perturb(block, rng: np.random.Generator, angle_deg: float = 20.0, shift: float = 1.0):
    """Rotate every image by ``angle_deg`` about a random axis, shift it by ``shift``, and
    re-intersect the tie points from the perturbed orientations (in place)."""
    from orientviz.block import CONTROL
    from orientviz.orientation.intersection import intersect_rays
    from orientviz.rotation import matrix_from_opk, matrix_from_rotvec, opk_from_matrix

    im, seq = block.images, block.sequence
    m = im.X0.shape[0]
    axis = rng.normal(size=(m, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    dirs = rng.normal(size=(m, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    R = matrix_from_opk(im.angles[:, 0], im.angles[:, 1], im.angles[:, 2], seq)
    R = matrix_from_rotvec(axis * np.radians(angle_deg)) @ R
    im.X0[:] = im.X0 + shift * dirs
    im.angles[:] = np.column_stack(opk_from_matrix(R, seq)).reshape(-1, 3)
    ob = block.observations
    c = block.cameras.c[im.camera[ob.image]]
    ray = np.column_stack([ob.xy, -c])
    d = np.einsum("nij,nj->ni", R[ob.image], ray)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    xyz, _ = intersect_rays(im.X0[ob.image], d, ob.point, block.points.xyz.shape[0])
    tie = block.points.role != CONTROL
    block.points.xyz[tie] = xyz[tie]


# --------------------------------------------------------------------------- workers
def _peak_mb() -> float:
    """Peak resident memory of this process in MB (VmHWM: ``ru_maxrss`` would carry the
    parent's resident size at the fork across ``exec``)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def worker_orientviz(directory: Path, control: list[int], reps: int, lens: str) -> dict:
    from orientviz.bundle import bundle_adjust

    walls, cpus = [], []
    for _ in range(reps):
        block = read_block(directory, control, lens)
        t0, c0 = time.perf_counter(), time.process_time()
        res = bundle_adjust(block, precision=False)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    centres = res["exterior"].reshape(-1, 6)[:, :3]
    return dict(
        wall_s=min(walls),
        cpu_s=min(cpus),
        iters=res.iterations,
        converged=bool(res.converged),
        sigma0=float(res.sigma0),
        peak_mb=_peak_mb(),
        centres={n: centres[k].tolist() for k, n in enumerate(block.images.ids)},
        points={p: v.tolist() for p, v in zip(block.points.ids, res["points"].reshape(-1, 3))},
    )


def worker_pycolmap(directory: Path, control: list[int], reps: int, max_iters: int) -> dict:
    import pycolmap

    walls, cpus = [], []
    for _ in range(reps):
        rec = pycolmap.Reconstruction(str(directory))
        t0, c0 = time.perf_counter(), time.process_time()
        opts = pycolmap.BundleAdjustmentOptions()
        opts.refine_focal_length = False
        opts.refine_principal_point = False
        opts.refine_extra_params = False
        opts.print_summary = False
        opts.ceres.auto_select_solver_type = False
        so = opts.ceres.solver_options
        so.num_threads = 1
        so.linear_solver_type = type(so.linear_solver_type).SPARSE_SCHUR
        so.max_num_iterations = max_iters
        so.function_tolerance = 1e-10
        so.gradient_tolerance = 1e-10
        so.parameter_tolerance = 1e-8
        config = pycolmap.BundleAdjustmentConfig()
        for i in rec.images:
            config.add_image(i)
        for c in rec.cameras:
            config.set_constant_cam_intrinsics(c)
        for p in control:
            config.add_constant_point(p)
        config.fix_gauge(pycolmap.BundleAdjustmentGauge.UNSPECIFIED)  # datum from control
        summary = pycolmap.create_default_bundle_adjuster(opts, config, rec).solve()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    cs = summary.ceres_summary
    n_obs = sum(len(p.track.elements) for p in rec.points3D.values())
    redundancy = 2 * n_obs - 6 * rec.num_images() - 3 * (rec.num_points3D() - len(control))
    return dict(
        wall_s=min(walls),
        cpu_s=min(cpus),
        iters=cs.num_successful_steps + cs.num_unsuccessful_steps,
        converged=str(summary.termination_type).endswith("CONVERGENCE"),
        sigma0=float(np.sqrt(2.0 * cs.final_cost / SIGMA_PX**2 / redundancy)),
        peak_mb=_peak_mb(),
        n_obs=n_obs,
        centres={im.name: im.projection_center().tolist() for im in rec.images.values()},
        points={str(p): pt.xyz.tolist() for p, pt in rec.points3D.items()},
    )


BENCH = Path(os.environ.get("ORIENTVIZ_BENCH_DIR", "/work/shared/bench"))


def _colmap_problem(directory: Path, control: list[int]):
    """The COLMAP model as the shared peer bench's problem (its BAL camera convention), so
    that its GTSAM and pyceres solvers run unchanged; also the model for the results."""
    import types

    import pycolmap

    sys.path.insert(0, str(BENCH))
    import make_block as mb

    rec = pycolmap.Reconstruction(str(directory))
    cam = next(iter(rec.cameras.values()))
    f, cx, cy = cam.params[0], cam.params[2], cam.params[3]
    image_ids = sorted(rec.images)
    point_ids = sorted(rec.points3D)
    col = {pid: k for k, pid in enumerate(point_ids)}
    oc, op, uv = [], [], []
    for i, iid in enumerate(image_ids):
        for p2 in rec.images[iid].points2D:
            if p2.has_point3D():
                oc.append(i)
                op.append(col[p2.point3D_id])
                uv.append((p2.xy[0] - cx, -(p2.xy[1] - cy)))  # BAL: origin centre, y up
    F = np.diag([1.0, -1.0, -1.0])
    R = np.array([rec.images[i].cam_from_world().rotation.matrix() for i in image_ids])
    t = np.array([rec.images[i].cam_from_world().translation for i in image_ids])
    X = np.array([rec.points3D[p].xyz for p in point_ids])
    ctrl = np.array([col[c] for c in control])
    is_ctrl = np.zeros(len(point_ids), bool)
    is_ctrl[ctrl] = True
    P = types.SimpleNamespace(
        f=float(f), sigma_px=SIGMA_PX, obs_cam=np.array(oc), obs_pt=np.array(op),
        obs=np.array(uv), cam_aa0=mb.R_to_aa(F @ R), cam_t0=(F @ t[:, :, None])[:, :, 0],
        pt0=X, is_ctrl=is_ctrl, ctrl_idx=ctrl, ctrl_xyz=X[ctrl], ctrl_sigma=1e-5,
        control="fixed", n_cam=len(image_ids), n_pt=len(point_ids), n_obs=len(oc),
        pt_is_var=~is_ctrl, pt_fixed=X.copy(),
    )  # fmt: skip
    names = [rec.images[i].name for i in image_ids]
    return P, mb, names, [str(p) for p in point_ids]


def worker_peer(solver: str, directory: Path, control: list[int], reps: int) -> dict:
    """GTSAM or pyceres through the shared bench's solvers (1 thread; wall = set-up + solve)."""
    sys.path.insert(0, str(BENCH))
    import run_peers as rp

    P, mb, names, pids = _colmap_problem(directory, control)
    solve = {"gtsam": rp.solve_gtsam, "pyceres": rp.solve_pyceres}[solver]
    walls = []
    for _ in range(reps):
        aa, t, X, iters, solve_s, info = solve(P, 1)
        walls.append(solve_s + info.get("setup_s", 0.0))
    Rb = mb.aa_to_R(aa)
    C = -np.einsum("nji,nj->ni", Rb, t)
    proj = mb.bal_project(aa[P.obs_cam], t[P.obs_cam], np.full(P.n_obs, P.f), X[P.obs_pt])
    chi2 = float(np.sum(((proj - P.obs) / SIGMA_PX) ** 2))
    redundancy = 2 * P.n_obs - 6 * P.n_cam - 3 * int(P.pt_is_var.sum())
    return dict(
        wall_s=min(walls),
        iters=int(iters),
        converged=True,
        sigma0=float(np.sqrt(chi2 / redundancy)),
        peak_mb=_peak_mb(),
        centres={n: C[k].tolist() for k, n in enumerate(names)},
        points={p: X[k].tolist() for k, p in enumerate(pids)},
    )


def run_worker(solver: str, directory: Path, control: list[int], reps: int, max_iters: int):
    env = dict(os.environ)
    for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[k] = "1"
    cmd = [
        sys.executable,
        __file__,
        "--worker",
        solver,
        str(directory),
        ",".join(map(str, control)),
    ]
    cmd += ["--reps", str(reps), "--max-iters", str(max_iters)]
    cp = subprocess.run(cmd, capture_output=True, text=True, env=env)
    lines = [ln for ln in cp.stdout.splitlines() if ln.startswith("@@RESULT ")]
    if not lines:
        return dict(status="failed", error=cp.stderr[-1500:])
    return json.loads(lines[-1][9:])


def difference(a: dict, b: dict, what: str) -> float:
    """Largest coordinate difference of the common items of two solutions."""
    keys = sorted(set(a[what]) & set(b[what]))
    return float(np.max(np.abs(np.array([a[what][k] for k in keys]) - [b[what][k] for k in keys])))


# --------------------------------------------------------------------------- main
def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="30,150")
    ap.add_argument("--large", action="store_true", help="add the 600-image networks")
    ap.add_argument("--tracks", default="random,visibility")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--seed", type=int, default=15)
    ap.add_argument("--no-poor", action="store_true", help="skip the poor-start run")
    ap.add_argument("--poor-only", action="store_true")
    ap.add_argument("--worker", nargs=3, metavar=("SOLVER", "DIR", "CONTROL"))
    ap.add_argument("--max-iters", type=int, default=100)
    ap.add_argument(
        "--peers",
        default="pycolmap,gtsam",
        help="peers besides orientviz (pycolmap always; gtsam, pyceres through the shared "
        "bench's solvers; pyceres's costs are Python callbacks: small networks only)",
    )
    ap.add_argument(
        "--lens",
        default="undistort",
        help="comma-separated read_colmap lens modes for orientviz's rows: undistort (the "
        "plain model), fixed (COLMAP's pixels, a held lens model without distortion)",
    )
    a = ap.parse_args()
    if a.worker:
        solver, d, ctrl = a.worker
        control = [int(c) for c in ctrl.split(",")]
        if solver.startswith("orientviz"):  # "orientviz" or "orientviz:LENS"
            out = worker_orientviz(Path(d), control, a.reps, (solver + ":undistort").split(":")[1])
        elif solver in ("gtsam", "pyceres"):
            out = worker_peer(solver, Path(d), control, a.reps)
        else:
            out = worker_pycolmap(Path(d), control, a.reps, a.max_iters)
        print("@@RESULT " + json.dumps(out))
        return
    sizes = [int(s) for s in a.sizes.split(",")] + ([600] if a.large else [])
    print(
        f"# load average {os.getloadavg()[0]:.1f} (shared 2-core machine), "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    )
    head = (
        "| network | images | obs | solver | wall_s | cpu_s | iters | σ0 | peak MB "
        "| wall / pycolmap | cpu / pycolmap | max ΔX0 | max Δpoint |"
    )
    rows = [head, "|" + " --- |" * 13]
    rng = np.random.default_rng(a.seed)
    with tempfile.TemporaryDirectory(prefix="ov-unordered-") as tmp:
        for tracks in a.tracks.split(","):
            for n in sizes:
                d = Path(tmp) / f"{tracks}_{n}"
                control = generate(d, n, tracks, rng)
                poor = n == 150 and not a.no_poor
                if a.poor_only and not poor:
                    continue
                peers = ["pycolmap"] + [p for p in a.peers.split(",") if p and p != "pycolmap"]
                ours = [
                    "orientviz" if m == "undistort" else f"orientviz:{m}" for m in a.lens.split(",")
                ]
                res = {s: run_worker(s, d, control, a.reps, a.max_iters) for s in peers + ours}
                n_obs = res["pycolmap"].get("n_obs")
                for s, r in res.items():
                    if "wall_s" not in r:
                        rows.append(f"| {tracks} | {n} | | {s} | failed: {r['error'][-200:]!r} |")
                        continue
                    ok = all("wall_s" in v for v in res.values())
                    ratio = r["wall_s"] / res["pycolmap"]["wall_s"] if ok else float("nan")
                    cpu = r.get("cpu_s", float("nan"))
                    cpu_ratio = cpu / res["pycolmap"]["cpu_s"] if ok else float("nan")
                    dx = difference(r, res["pycolmap"], "centres") if ok else float("nan")
                    dp = difference(r, res["pycolmap"], "points") if ok else float("nan")
                    rows.append(
                        f"| {tracks} | {n} | {n_obs or '-'} | {s} | {r['wall_s']:.3f} | {cpu:.3f} "
                        f"| {r['iters']} | {r['sigma0']:.6f} | {r['peak_mb']:.0f} | {ratio:.2f} "
                        f"| {cpu_ratio:.2f} | {dx:.1e} | {dp:.1e} |"
                    )
                print("\n".join(rows[-len(res) :]), flush=True)
                if poor:
                    poor_run(d, control, rng, res, tmp, tracks, n)
    print()
    print("\n".join(rows))


def poor_run(d: Path, control, rng, good: dict, tmp: str, tracks: str, n: int) -> None:
    """Both solvers from a start 20° / 1 unit off; compare with the good start's optimum."""
    from orientviz.io.colmap import write_colmap

    block = read_block(d, control)
    perturb(block, rng)
    dp = Path(tmp) / f"{tracks}_{n}_poor"
    write_colmap(block, dp)
    print(f"\nPoor start ({tracks}, {n} images: 20°, 1 unit, points re-intersected):")
    print("| solver | converged | iters | σ0 | max ΔX0 to good-start optimum | wall_s |")
    print("| --- | --- | --- | --- | --- | --- |")
    for s in ("pycolmap", "orientviz"):
        r = run_worker(s, dp, control, 1, 100)
        if "wall_s" not in r:
            print(f"| {s} | failed | {r['error'][-200:]!r} |")
            continue
        ref = good[s] if "centres" in good.get(s, {}) else good["pycolmap"]
        dx = difference(r, ref, "centres")
        print(
            f"| {s} | {r['converged']} | {r['iters']} | {r['sigma0']:.6f} | {dx:.1e} | "
            f"{r['wall_s']:.2f} |",
            flush=True,
        )
    print()


if __name__ == "__main__":
    main()
