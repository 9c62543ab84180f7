"""COLMAP import at scale: a generated ~1 GB images.txt, the streaming reader vs the old one.

``python benchmarks/bench_colmap_import.py [--size-mb 1000] [--keypoints 12000]
[--matched 0.10] [--readers new,binary,before] [--reps N] [--dir DIR]``

Writes a COLMAP text model (cameras.txt, images.txt with ``--keypoints`` keypoints per
image of which the fraction ``--matched`` observe a 3D point, points3D.txt) of about
``--size-mb`` MB of images.txt into ``--dir`` (a temporary folder by default; reused if
it holds a model of that size), and the same model in COLMAP's binary layout. Then
every reader runs in its own fresh process (honest peak RSS): ``new`` =
``orientviz.io.colmap.read_colmap`` on the text files, ``binary`` = the same on the
binary files, ``before`` = the reader of commit 775b17c (``colmap_reader_before.py``).
Reported: wall and CPU time of the read (s; on the shared 2-core machine the CPU time is
the steadier number), peak RSS of the process above its RSS after the
imports (MB), the size of the kept data (the Block's observation and point arrays, MB)
and the peak over the kept data, and the CPU ratios to ``binary`` and ``before`` measured
in the same run (``--reps N``: the readers run N times, alternating; the best CPU time of
each is shown).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

WORKER = r"""
import json, resource, sys, time
sys.path.insert(0, {here!r})
kind, directory = sys.argv[1], sys.argv[2]
import numpy as np
if kind == "before":
    from colmap_reader_before import read_colmap
else:
    from orientviz.io.colmap import read_colmap
def hwm_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
def rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
base = rss_mb()
t = time.perf_counter()
r0 = resource.getrusage(resource.RUSAGE_SELF)
block = read_colmap(directory)
wall = time.perf_counter() - t
r1 = resource.getrusage(resource.RUSAGE_SELF)
cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
peak = hwm_mb()
o, p = block.observations, block.points
kept = sum(a.nbytes for a in (o.image, o.point, o.xy, o.sigma, p.xyz, p.xyz_known, p.sigma, p.role)) / 2**20
print(json.dumps({{"wall_s": wall, "cpu_s": cpu, "peak_over_base_mb": peak - base, "kept_mb": kept,
                  "observations": len(o), "images": block.n_images, "points": block.n_points}}))
"""


def generate(
    directory: Path, size_mb: float, keypoints: int, matched: float, seed: int = 1
) -> dict:
    """Write the text and binary model; return its counts (reuses an existing one)."""
    meta_path = directory / "model.json"
    if meta_path.exists():
        meta = json.loads(meta_path.read_text())
        if (
            meta["size_mb"] == size_mb
            and meta["keypoints"] == keypoints
            and meta["matched"] == matched
        ):
            return meta
    rng = np.random.default_rng(seed)
    directory.mkdir(parents=True, exist_ok=True)
    txt = directory / "text"
    txt.mkdir(exist_ok=True)
    w, h = 6000, 4000
    (txt / "cameras.txt").write_text(
        f"# Camera list\n1 OPENCV {w} {h} 4000.5 3999.25 3001.5 1998.75 -0.05 0.01 0.0002 -0.0001\n"
    )
    pool_u = rng.uniform(0, w, 50_000)
    pool_v = rng.uniform(0, h, 50_000)
    pool = np.array([f"{a:.6f} {b:.6f} -1".encode() for a, b in zip(pool_u, pool_v)], dtype=object)
    per_image = keypoints * 27 + 100
    n_images = max(2, int(size_mb * 2**20 / per_image))
    n_match = int(keypoints * matched)
    n_points = max(n_match * n_images // 4, n_match)
    obs_point = []
    with open(txt / "images.txt", "wb") as f:
        f.write(b"# Image list with two lines of data per image:\n")
        for i in range(n_images):
            q = rng.normal(size=4)
            q /= np.linalg.norm(q)
            t = rng.normal(size=3)
            f.write(
                f"{i + 1} {q[0]} {q[1]} {q[2]} {q[3]} {t[0]} {t[1]} {t[2]} 1 img_{i:05d}.jpg\n".encode()
            )
            line = pool[rng.integers(0, pool.size, keypoints)]
            pts = rng.choice(n_points, n_match, replace=False) + 1
            slots = rng.choice(keypoints, n_match, replace=False)
            uv = rng.uniform(100, [w - 100, h - 100], (n_match, 2))
            line[slots] = [f"{a:.6f} {b:.6f} {p}".encode() for (a, b), p in zip(uv, pts)]
            f.write(b" ".join(line.tolist()) + b"\n")
            obs_point.append(np.column_stack([np.full(n_match, i + 1), pts]))
    op = np.concatenate(obs_point)
    order = np.argsort(op[:, 1], kind="stable")
    op = op[order]
    starts = np.searchsorted(op[:, 1], np.arange(1, n_points + 2))
    xyz = rng.normal(size=(n_points, 3)) * 10
    with open(txt / "points3D.txt", "wb") as f:
        f.write(b"# 3D point list\n")
        for p in range(n_points):
            tr = op[starts[p] : starts[p + 1], 0]
            track = " ".join(f"{i} 0" for i in tr.tolist())
            f.write(
                f"{p + 1} {xyz[p, 0]} {xyz[p, 1]} {xyz[p, 2]} 128 128 128 0.5 {track}\n".encode()
            )
    sys.path.insert(0, str(HERE.parent / "src"))
    from orientviz.io.colmap_bin import write_binary_model
    from orientviz.io.colmap_text_model import read_text_model

    write_binary_model(read_text_model(txt), directory / "binary")
    meta = {"size_mb": size_mb, "keypoints": keypoints, "matched": matched, "images": n_images,
            "images_txt_mb": (txt / "images.txt").stat().st_size / 2**20,
            "images_bin_mb": (directory / "binary" / "images.bin").stat().st_size / 2**20}  # fmt: skip
    meta_path.write_text(json.dumps(meta))
    return meta


def run(kind: str, directory: Path) -> dict:
    code = WORKER.format(here=str(HERE))
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", code, kind, str(directory)], capture_output=True,
                         text=True, env=env, check=True)  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size-mb", type=float, default=1000.0)
    ap.add_argument("--keypoints", type=int, default=12000)
    ap.add_argument("--matched", type=float, default=0.10)
    ap.add_argument("--readers", default="new,binary,before")
    ap.add_argument("--dir", type=Path, default=None)
    ap.add_argument("--reps", type=int, default=1, help="runs per reader, alternating; best CPU kept")
    args = ap.parse_args(argv)
    directory = args.dir or Path(tempfile.gettempdir()) / "orientviz-bench-colmap"
    t = time.perf_counter()
    meta = generate(directory, args.size_mb, args.keypoints, args.matched)
    print(f"model: {meta['images']} images, images.txt {meta['images_txt_mb']:.0f} MB, "
          f"images.bin {meta['images_bin_mb']:.0f} MB, {args.keypoints} keypoints/image, "
          f"{args.matched:.0%} matched (ready in {time.perf_counter() - t:.0f} s)")  # fmt: skip
    print(f"load average {os.getloadavg()[0]:.2f} (2 cores shared)")
    res: dict[str, dict] = {}
    for _ in range(max(1, args.reps)):  # alternate the readers: the load hits each alike
        for kind in args.readers.split(","):
            d = directory / ("binary" if kind == "binary" else "text")
            r = run(kind, d)
            if kind not in res or r["cpu_s"] < res[kind]["cpu_s"]:
                res[kind] = r
    print(f"load average after the runs {os.getloadavg()[0]:.2f}")
    base, binary = res.get("before"), res.get("binary")
    print(
        "| reader | wall_s | cpu_s | peak over start MB | kept MB | peak − kept MB | observations | cpu / binary | cpu / before | peak / before |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for kind, r in res.items():
        bratio = f"{r['cpu_s'] / binary['cpu_s']:.2f}" if binary else "—"
        ratio = f"{r['cpu_s'] / base['cpu_s']:.3f}" if base else "—"
        pratio = f"{r['peak_over_base_mb'] / base['peak_over_base_mb']:.3f}" if base else "—"
        print(f"| {kind} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | {r['peak_over_base_mb']:.0f} | {r['kept_mb']:.0f} | "
              f"{r['peak_over_base_mb'] - r['kept_mb']:.0f} | {r['observations']} | {bratio} | {ratio} | {pratio} |")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
