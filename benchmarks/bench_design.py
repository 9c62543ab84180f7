"""Every change the design studio offers, on a 1 000-image block: update against a new assessment.

A design block of ``--strips`` × ``--images`` images (default 20 × 50 = 1 000, standard
points, perimeter control every 4 bases, σ 5 µm, control σ 2 cm) is made live once
(:class:`orientviz.design.LiveDesign`: the bundle's precision and reliability and the
factorised normal equations). Then each kind of change the studio makes is timed as the
studio runs it — the update of σ of all points and stations, redundancy numbers, MDB,
external reliability, ellipsoids, weak spots and summary:

* control added / its σ changed / undone (``set_control``, ``undo``);
* an image added, removed, moved (``add_images``, ``remove_images``, both);
* a cross strip added and a strip removed (a new assessment: the step would need more
  than ``max_columns`` columns; ``--forced`` also times the update forced through);
* the same design with statoscope and APR readings (offsets per strip): control added, an
  image removed and added (their readings with them), a cross strip (new offsets: a new
  design);
* a change of the plan (image σ): a new design, formed and factored;
* the suggestion of the next control point (40 candidates);
* the method switched to independent models (:class:`orientviz.design.LiveModels`): its
  design (models formed, normal equations factored, selected inverse), control added /
  changed / undone (updates), a new structure (an image removed: a new factorisation);
  the same with statoscope and APR (the offsets' border); peer:
  :func:`orientviz.design.assess_models` (one run each, ``--models-peer``).

The peer in the same run: a new :func:`orientviz.design.assess_block` of the changed
design. Each kind is run ``--repeat`` times (median, max). With ``--threads both`` the
whole sequence runs with the default BLAS threads and then with one
(``threadpoolctl``), in the same process. Wall time and the process's CPU time (all its
threads) are printed: on the shared machine a change waits for a core, its CPU time is
its cost. ``LiveDesign`` itself runs its BLAS on one
thread (``blas_threads=1``, its default); ``--uncapped`` leaves it on the process's
threads (the peer ``assess_block`` always is).

    python benchmarks/bench_design.py                       # 1 000 images, both thread settings
    python benchmarks/bench_design.py --strips 4 --images 10 --threads 1
"""

from __future__ import annotations

import argparse
import functools
import os
import time
from contextlib import nullcontext

import numpy as np
from threadpoolctl import threadpool_limits

from orientviz.block import CONTROL, TIE
from orientviz.design import (
    FlightDesign,
    LiveDesign,
    LiveModels,
    assess_block,
    assess_models,
    cross_strip_images,
    design_auxiliary,
    design_block,
    suggest_control,
)

CPU: list[float] = []  # the process's CPU time of the last _t (all threads), s


def _t(f):
    t, c = time.perf_counter(), time.process_time()
    out = f()
    CPU.append(time.process_time() - c)
    return time.perf_counter() - t, out


def run(args, label: str) -> list[tuple[str, list[float], list[float]]]:
    plan = FlightDesign(strips=args.strips, images_per_strip=args.images)
    block, spec = design_block(plan)
    print(f"\n== {label}: {block.n_images} images, {block.n_points} points, "
          f"{block.n_observations} rays; load {os.getloadavg()[0]:.1f}")  # fmt: skip
    cap = None if args.uncapped else 1
    dt, live = _t(lambda: LiveDesign(block, spec, blas_threads=cap))
    print(f"base assessment + factorisation: {dt:.2f} s")
    rows: list[tuple[str, list[float], list[float]]] = []
    rng = np.random.default_rng(1)
    tie = np.flatnonzero(block.points.role == 0)
    I = block.images
    R = args.repeat

    def kind(name, f):
        ts, cs = [], []
        for k in range(R):
            dt, out = _t(functools.partial(f, k))
            ts.append(dt)
            cs.append(CPU[-1])
        if isinstance(out, LiveDesign) and "{how}" in name:  # update or new assessment
            fresh = any("formed and factored" in t for t in out.history[-2:])
            name = name.format(how="new assessment" if fresh else "update")
        rows.append((name, ts, cs))
        print(
            f"  {name:<44} median {1e3 * np.median(ts):7.0f} ms  max {1e3 * max(ts):7.0f} ms"
            f"  CPU median {1e3 * np.median(cs):7.0f} ms"
        )

    picks = rng.choice(tie, size=R, replace=False)
    kind("control added", lambda k: live.add_control(int(picks[k]), 0.02))
    kind("control σ changed (height only, 5 cm)",
         lambda k: live.set_control(int(picks[k]), (np.nan, np.nan, 0.05)))  # fmt: skip
    kind("undo (control)", lambda k: live.undo())
    inner = np.flatnonzero((I.strip > 0) & (I.strip < plan.strips - 1))
    imgs = rng.choice(inner, size=R, replace=False)
    # an image moved a third of a base towards the block's middle (it keeps seeing points)
    B = float(spec["base_m"])
    towards = np.sign(I.X0[:, :2].mean(axis=0) - I.X0[:, :2])
    shift = np.column_stack([B / 3 * towards, np.zeros(block.n_images)])  # (m, 3)
    kind("image removed ({how})", lambda k: live.remove_images([int(imgs[k])]))
    kind("image added ({how})",
         lambda k: live.add_images(I.X0[imgs[k]] + shift[imgs[k]], I.angles[imgs[k]],
                                   strip=int(I.strip[imgs[k]])))  # fmt: skip

    def move(k):
        i = int(imgs[k])
        return live.remove_images([i]).add_images(
            I.X0[i] + shift[i], I.angles[i], strip=int(I.strip[i])
        )

    kind("image moved (removed + added)", move)
    xs = rng.uniform(I.X0[:, 0].min(), I.X0[:, 0].max(), size=R)
    cs = [cross_strip_images(live.block, spec, float(x)) for x in xs]
    kind(f"cross strip ({len(cs[0][3])} images, {{how}})",
         lambda k: live.add_images(cs[k][0], cs[k][1], strip=cs[k][2], ids=cs[k][3]))  # fmt: skip
    edge = np.flatnonzero(I.strip == plan.strips - 1)
    kind(f"strip removed ({edge.size} images, {{how}})", lambda k: live.remove_images(edge))
    if args.forced:
        live.max_columns = 10**9
        kind("cross strip ({how}, forced)",
             lambda k: live.add_images(cs[k][0], cs[k][1], strip=cs[k][2], ids=cs[k][3]))  # fmt: skip
        kind("strip removed ({how}, forced)", lambda k: live.remove_images(edge))
        live.max_columns = 400
    kind("plan changed (image σ 4 µm: new design)",
         lambda k: LiveDesign(*design_block(plan.with_(sigma_image_mm=0.004)),
                              blas_threads=cap))  # fmt: skip
    dt, sug = _t(lambda: suggest_control(live, criterion="sigma_z"))
    rows.append(("suggestion (40 candidates)", [dt], [CPU[-1]]))
    print(f"  suggestion ({sug.candidates.size} candidates): {dt:.2f} s")
    aplan = plan.with_(sigma_statoscope=0.3, sigma_apr=0.5)
    ablock, aspec = design_block(aplan)
    aux = design_auxiliary(ablock, aplan)
    dt, alive = _t(lambda: LiveDesign(ablock, aspec, auxiliary=aux, blas_threads=cap))
    print(f"with statoscope + APR: base {dt:.2f} s")
    kind("control added (statoscope + APR)", lambda k: alive.add_control(int(picks[k]), 0.02))

    def of(b):
        return design_auxiliary(b, aplan)

    kind("image removed (statoscope + APR, {how})",
         lambda k: alive.remove_images([int(imgs[k])], auxiliary=of))  # fmt: skip
    kind("image added (statoscope + APR, {how})",
         lambda k: alive.add_images(I.X0[imgs[k]] + shift[imgs[k]], I.angles[imgs[k]],
                                    strip=int(I.strip[imgs[k]]), auxiliary=of))  # fmt: skip
    kind("cross strip (statoscope + APR, {how})",
         lambda k: alive.add_images(cs[k][0], cs[k][1], strip=cs[k][2], ids=cs[k][3],
                                    auxiliary=of))  # fmt: skip
    # the method switched to independent models: one factorisation, control by updates
    mb = block.copy()
    dt, lm = _t(lambda: LiveModels(mb, spec, blas_threads=cap))
    rows.append(("models: design (formed, factored, inverted)", [dt], [CPU[-1]]))
    print(f"  models: design {1e3 * dt:.0f} ms (CPU {1e3 * CPU[-1]:.0f} ms)")

    def models_control(k, sigma):
        P, j = mb.points, int(picks[k])
        P.sigma[j] = sigma
        P.xyz_known[j] = np.where(np.isfinite(sigma), P.xyz[j], np.nan)
        P.role[j] = CONTROL if np.isfinite(sigma).any() else TIE
        return lm.sync()

    kind("models: control added (update)", lambda k: models_control(k, np.full(3, 0.02)))
    kind("models: control σ changed (height only, 5 cm)",
         lambda k: models_control(k, np.array([np.nan, np.nan, 0.05])))  # fmt: skip
    kind("models: undo (control back to tie, update)",
         lambda k: models_control(k, np.full(3, np.nan)))  # fmt: skip
    # an image at a strip's end (inside a strip its neighbours would form no model)
    ends = np.array([np.flatnonzero(I.strip == s)[-1] for s in range(plan.strips)])
    ends = rng.choice(ends, size=min(R, ends.size), replace=False)
    kind("models: strip's end image removed (bundle update + models factored)",
         lambda k: LiveModels(live.remove_images([int(ends[k % ends.size])]).block, spec,
                              blas_threads=cap))  # fmt: skip
    if args.models_peer:
        dt, _ = _t(lambda: assess_models(mb, spec))
        rows.append(("peer: models assessment (assess_models)", [dt], [CPU[-1]]))
        print(f"  peer assess_models: {dt:.2f} s (CPU {CPU[-1]:.2f} s)")
    # independent models with statoscope + APR (the offsets' border of the factor)
    amb = ablock.copy()
    dt, alm = _t(lambda: LiveModels(amb, aspec, auxiliary=aux, blas_threads=cap))
    rows.append(("models, statoscope + APR: design", [dt], [CPU[-1]]))
    print(f"  models, statoscope + APR: design {1e3 * dt:.0f} ms (CPU {1e3 * CPU[-1]:.0f} ms)")

    def aux_models_control(k):
        P, j = amb.points, int(picks[k])
        P.sigma[j] = 0.02
        P.xyz_known[j] = P.xyz[j]
        P.role[j] = CONTROL
        return alm.sync()

    kind("models, statoscope + APR: control added (update)", aux_models_control)
    if args.models_peer:
        dt, _ = _t(lambda: assess_models(amb, aspec, auxiliary=aux))
        rows.append(("peer: models assessment with statoscope + APR", [dt], [CPU[-1]]))
        print(f"  peer assess_models with statoscope + APR: {dt:.2f} s (CPU {CPU[-1]:.2f} s)")
    kind("peer: new assessment (assess_block)", lambda k: assess_block(live.block, spec))
    kind("peer: new assessment with statoscope + APR",
         lambda k: assess_block(alive.block, aspec, auxiliary=aux))  # fmt: skip
    return rows


def print_thread_tables(run, args) -> None:
    """Run ``run(args, title)`` per BLAS-thread setting of ``args.threads`` ("both", "default"
    or "1") and print one markdown table: per change, wall median / max and CPU median (ms)."""
    settings = {"both": ("default", "1"), "default": ("default",), "1": ("1",)}[args.threads]
    tables = {}
    for s in settings:
        ctx = threadpool_limits(1, "blas") if s == "1" else nullcontext()
        with ctx:
            tables[s] = run(args, f"BLAS threads: {s}")
    head = " | ".join(f"{s} thread(s): wall median / max, CPU median ms" for s in settings)
    print(f"\n| change | {head} |")
    print("| --- |" + " --- |" * len(settings))
    for i, (name, *_) in enumerate(tables[settings[0]]):
        cells = []
        for s in settings:
            _, ts, cs = tables[s][i]
            cells.append(
                f"{1e3 * np.median(ts):.0f} / {1e3 * max(ts):.0f}, {1e3 * np.median(cs):.0f}"
            )
        print(f"| {name} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strips", type=int, default=20)
    ap.add_argument("--images", type=int, default=50)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", choices=("both", "default", "1"), default="both")
    ap.add_argument("--forced", action="store_true", help="also force strips through the update")
    ap.add_argument(
        "--models-peer", action="store_true",
        help="also time assess_models once (≈ 14 s CPU on the 1 000-image block)",
    )  # fmt: skip
    ap.add_argument(
        "--uncapped", action="store_true",
        help="LiveDesign(blas_threads=None): the design's BLAS on the process's threads",
    )  # fmt: skip
    args = ap.parse_args()
    print_thread_tables(run, args)


if __name__ == "__main__":
    main()
