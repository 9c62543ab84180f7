"""Issue 28 points 1, 2 and 4 on a real SfM set, checked as a user runs it.

    python benchmarks/verify_sfm.py --bal /work/data_sfm/problem-21-11315-pre.txt
    python benchmarks/verify_sfm.py --colmap /work/data_sfm/bart
    python benchmarks/verify_sfm.py --colmap src/orientviz/datasets/axe --json row.json

One row per set, from the command line (``orientviz import-* / solve / export-bal /
export``) and from an independent peer, pycolmap 4 (Ceres), on the same objective:

* BAL (point 1): the file without the observations behind their camera at the start and
  the points then left with < 2 rays (``bench_sfm.front_bal``: pycolmap's reprojection
  cost leaves those out, BAL's does not), ``orientviz import-bal`` (f, k1, k2 free per
  camera), ``orientviz solve --free -o OUT.json``, ``orientviz export-bal OUT.json``.
  Checked: OUT.json's cameras moved from the file's; BAL's own cost (numpy, written
  here, no depth test) of the exported file equals orientviz's ½Σr² = ½σ̂0²·r (σ = 1 px);
  ``import-bal`` of the export and ``export-bal`` again gives the same numbers (round
  trip); the optimum against pycolmap's (one RADIAL camera per BAL camera, principal
  point held, f, k1, k2 refined) run to a tight stop (function tolerance 1e-12,
  gradient and parameter tolerances 0, ≤ 300 iterations), and orientviz's own tight run
  (library, ftol 1e-13, ≤ 300 iterations): the lower of the two is the optimum.
* COLMAP (point 4): ``orientviz import-colmap`` (COLMAP's objective: distorted pixels, f
  and distortion free, σ = 1 px), its message's count of repeated observations against
  the count of (image, point) pairs seen twice in pycolmap's reading; ``solve --free
  -o OUT.json``; ``orientviz export OUT.json --no-adjust --format colmap``: pycolmap
  reads the refined model and its reprojection errors (pixels, ``Camera.img_from_cam``)
  give Σe², which must equal σ̂0²·r (σ̂0 reads as the pixel RMS); pycolmap's bundle
  adjuster on the model as read with the repeated observations deleted (the first kept,
  as orientviz keeps it), f and extra parameters refined, principal point held.
* Both (point 2): ``solve``'s exit code and iterations under its default stopping rule
  (the imported file's), against Ceres's default stopping rule (function tolerance 1e-6,
  gradient 1e-10, parameter 1e-8; ≤ 500 iterations) on the same problem; orientviz's
  iterations are accepted steps, its linear solves (accepted + rejected, counted in the
  library run) are the number to set against Ceres's successful + unsuccessful steps.

Each solver runs in its own process, one BLAS / Ceres thread. ``--json`` appends the row.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
           PYTHONPATH=os.pathsep.join(p for p in (str(HERE), os.environ.get("PYTHONPATH")) if p))

#: Ceres's own default stopping rule (ceres::Solver::Options), and a tight one.
CERES_DEFAULT = dict(function_tolerance=1e-6, gradient_tolerance=1e-10, parameter_tolerance=1e-8,
                     max_num_iterations=500)  # fmt: skip
#: orientviz's tight run (the library, ``BundleOptions`` through the problem's options).
TIGHT = {"ftol": 1e-13, "max_iter": 300}
CERES_TIGHT = dict(function_tolerance=1e-12, gradient_tolerance=0.0, parameter_tolerance=0.0,
                   max_num_iterations=300)  # fmt: skip

PEER = r"""
import json, sys
import numpy as np
import pycolmap
kind, model, tol = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
from _pycolmap_models import (
    adjuster, bal_reconstruction, drop_repeated_observations, full_model_options)
if kind == "bal":
    rec = bal_reconstruction(model)
    removed = 0
else:
    rec = pycolmap.Reconstruction(model)
    removed = drop_repeated_observations(rec)
opts = full_model_options(1)
for k, v in tol.items():
    setattr(opts.ceres.solver_options, k, v)
s = adjuster(rec, opts).solve()
cs = getattr(s, "ceres_summary", s)
behind = 0
for iid in rec.reg_image_ids():
    im = rec.images[iid]
    for p in im.points2D:
        if p.has_point3D():
            behind += int((im.cam_from_world() * rec.points3D[p.point3D_id].xyz)[2] <= 0)
print(json.dumps(dict(cost=cs.final_cost, steps=cs.num_successful_steps + cs.num_unsuccessful_steps,
                      successful=cs.num_successful_steps, removed=removed, behind=behind,
                      termination=cs.BriefReport().split("Termination: ")[-1])))
"""

LIBRARY = r"""
import json, sys
from orientviz.bundle.loop._steps import BundleSteps
from orientviz.io.kinds.block import adjust_block, prepare
from orientviz.io.problem import load_problem
n = [0]
real = BundleSteps.solve
def solve(self, *a, **k):
    n[0] += 1
    return real(self, *a, **k)
BundleSteps.solve = solve
prob = load_problem(sys.argv[1])
prob.options["free"] = True
prob.options.update(json.loads(sys.argv[2]))
block, _ = prepare(prob)
adj, _ = adjust_block(prob, block, precision=False)
print(json.dumps(dict(iterations=adj.iterations, solves=n[0], cost=adj.history[-1].cost / 2,
                      converged=bool(adj.converged))))
"""


def run(cmd: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """A command as a user types it (one BLAS thread), output captured."""
    return subprocess.run(cmd, cwd=cwd, env=ENV, capture_output=True, text=True)


def orientviz(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return run(["orientviz", *args], cwd)


def peer(kind: str, model: Path, tol: dict) -> dict:
    cp = run([sys.executable, "-c", PEER, kind, str(model), json.dumps(tol)], model.parent)
    if cp.returncode:
        raise RuntimeError(cp.stderr[-2000:])
    return json.loads(cp.stdout.strip().splitlines()[-1])


def library(problem: Path, options: dict | None = None) -> dict:
    cp = run([sys.executable, "-c", LIBRARY, str(problem), json.dumps(options or {})],
             problem.parent)  # fmt: skip
    if cp.returncode:
        raise RuntimeError(cp.stderr[-2000:])
    return json.loads(cp.stdout.strip().splitlines()[-1])


def bal_cost(path: Path) -> float:
    """½Σ‖projection − observation‖² (px²) of a BAL file by BAL's own formula: P = R(ω)X +
    t, p = −P_xy / P_z, r² = ‖p‖², projection f·(1 + k1 r² + k2 r⁴)·p (no depth test)."""
    from orientviz.io.bal import read_bal_arrays

    obs, cams, pts = read_bal_arrays(str(path))
    ci, pi = obs[:, 0].astype(int), obs[:, 1].astype(int)
    w, X = cams[ci, :3], pts[pi]
    th = np.linalg.norm(w, axis=1, keepdims=True)
    k = np.divide(w, th, out=np.zeros_like(w), where=th > 0)
    c, s = np.cos(th), np.sin(th)
    P = X * c + np.cross(k, X) * s + k * np.sum(k * X, axis=1, keepdims=True) * (1 - c)
    P += cams[ci, 3:6]
    p = -P[:, :2] / P[:, 2:3]
    r2 = np.sum(p * p, axis=1)
    f, k1, k2 = cams[ci, 6], cams[ci, 7], cams[ci, 8]
    proj = (f * (1 + k1 * r2 + k2 * r2 * r2))[:, None] * p
    return 0.5 * float(np.sum((proj - obs[:, 2:4]) ** 2))


def solve_row(problem: Path, work: Path) -> dict:
    """``orientviz solve --free --json -o`` and the library run with its solve count."""
    out = work / (problem.stem + "_out.json")
    cp = orientviz("solve", problem.name, "--free", "--json", "-o", out.name, cwd=work)
    res = json.loads(cp.stdout) if cp.stdout.strip().startswith("{") else {}
    lib = library(problem)
    tight = library(problem, TIGHT)
    s0, r = res.get("sigma0", np.nan), res.get("redundancy", 0)
    return dict(
        solve_rc=cp.returncode,
        iterations=res.get("iterations"),
        solves=lib["solves"],
        reason=res.get("reason", cp.stderr[-300:]),
        sigma0=s0,
        redundancy=r,
        cost=0.5 * s0 * s0 * r,
        lib_cost=lib["cost"],
        tight_cost=tight["cost"],
        tight_iterations=tight["iterations"],
        out=out,
    )


def cameras_moved(before: Path, after: Path) -> float:
    """Largest relative change of a camera's c between two problem files (their cameras
    table, one column per field)."""
    a = np.array(json.loads(before.read_text())["cameras"]["c"], dtype=float)
    b = np.array(json.loads(after.read_text())["cameras"]["c"], dtype=float)
    return float(np.max(np.abs(b - a) / np.abs(a)))


def verify_bal(src: str, work: Path) -> dict:
    from bench_sfm import front_bal

    from orientviz.io.bal import read_bal_arrays

    front = work / "front.bal"
    removed = front_bal(src, front)
    imp = orientviz("import-bal", front.name, "-o", "bal.json", cwd=work)
    row = dict(set=Path(src).name, removed=removed, import_msg=imp.stdout.strip().splitlines()[0])
    s = solve_row(work / "bal.json", work)
    row.update({k: v for k, v in s.items() if k != "out"})
    row["c_moved"] = cameras_moved(work / "bal.json", s["out"])
    exp = orientviz("export-bal", s["out"].name, "-o", "out.bal", cwd=work)
    row["export_rc"] = exp.returncode
    row["bal_cost_of_export"] = bal_cost(work / "out.bal")
    back = orientviz("import-bal", "out.bal", "-o", "back.json", cwd=work)
    again = orientviz("export-bal", "back.json", "-o", "back.bal", cwd=work)
    a, b = read_bal_arrays(str(work / "out.bal")), read_bal_arrays(str(work / "back.bal"))
    row["round_trip_rc"] = (back.returncode, again.returncode)
    row["round_trip_max_rel"] = max(
        float(np.max(np.abs(x - y) / np.maximum(np.abs(x), 1e-300))) for x, y in zip(a, b)
    )
    row["start_cost"] = bal_cost(front)
    row["ceres_tight"] = peer("bal", front, CERES_TIGHT)
    row["ceres_default"] = peer("bal", front, CERES_DEFAULT)
    return row


def repeated_pairs(directory: str) -> int:
    """(image, point) observations beyond the first, as pycolmap reads the model."""
    import pycolmap

    rec = pycolmap.Reconstruction(directory)
    extra = 0
    for iid in rec.reg_image_ids():
        ids = [p.point3D_id for p in rec.images[iid].points2D if p.has_point3D()]
        extra += len(ids) - len(set(ids))
    return extra


def pixel_sse(directory: Path) -> tuple[float, int]:
    """Σ‖e‖² (px²) of every observation of a COLMAP model (COLMAP's projection)."""
    import pycolmap

    rec = pycolmap.Reconstruction(str(directory))
    sse, n = 0.0, 0
    for iid in rec.reg_image_ids():
        im = rec.images[iid]
        cam = rec.cameras[im.camera_id]
        pts = [p for p in im.points2D if p.has_point3D()]
        if not pts:
            continue
        X = np.array([rec.points3D[p.point3D_id].xyz for p in pts])
        xy = np.array([p.xy for p in pts])
        Pc = np.array([im.cam_from_world() * x for x in X])
        proj = cam.img_from_cam(Pc)
        sse += float(np.sum((proj - xy) ** 2))
        n += len(pts)
    return sse, n


def verify_colmap(src: str, work: Path) -> dict:
    imp = orientviz("import-colmap", str(Path(src).resolve()), "-o", "model.json", cwd=work)
    row = dict(set=Path(src).name, import_rc=imp.returncode, import_msg=imp.stdout.strip())
    row["repeated_pycolmap"] = repeated_pairs(src)
    s = solve_row(work / "model.json", work)
    row.update({k: v for k, v in s.items() if k != "out"})
    row["c_moved"] = cameras_moved(work / "model.json", s["out"])
    exp = orientviz("export", s["out"].name, "-d", "export", "--no-adjust", "--format",
                    "colmap", cwd=work)  # fmt: skip
    row["export_rc"] = exp.returncode
    sse, n = pixel_sse(work / "export" / "colmap")
    row["pixel_sse"], row["pixel_obs"] = sse, n
    row["pixel_rms_over_r"] = float(np.sqrt(sse / s["redundancy"])) if s["redundancy"] else None
    row["ceres_tight"] = peer("colmap", Path(src).resolve(), CERES_TIGHT)
    row["ceres_default"] = peer("colmap", Path(src).resolve(), CERES_DEFAULT)
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--bal", help="BAL problem file (text or .bz2)")
    g.add_argument("--colmap", help="COLMAP sparse model directory")
    ap.add_argument("--dir", default=None, help="working folder (default: a temporary one)")
    ap.add_argument("--json", default=None, help="append the row (JSON lines) to this file")
    ap.add_argument("--tight-steps", type=int, default=300,
                    help="steps of both tight runs at most (default 300)")  # fmt: skip
    a = ap.parse_args(argv)
    CERES_TIGHT["max_num_iterations"] = TIGHT["max_iter"] = a.tight_steps
    with tempfile.TemporaryDirectory(prefix="ov-verify-") as tmp:
        work = Path(a.dir or tmp)
        work.mkdir(parents=True, exist_ok=True)
        row = verify_bal(a.bal, work) if a.bal else verify_colmap(a.colmap, work)
    tight = row["ceres_tight"]["cost"]
    row["cost_rel_to_ceres_tight"] = (row["cost"] - tight) / tight
    best = min(tight, row["tight_cost"])
    row["cost_rel_to_optimum"] = (row["cost"] - best) / best
    row["ceres_tight_rel_to_optimum"] = (tight - best) / best
    row["iter_ratio"] = row["solves"] / row["ceres_default"]["steps"]
    print(json.dumps(row, indent=1, default=str))
    if a.json:
        with open(a.json, "a") as f:
            f.write(json.dumps(row, default=str) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
