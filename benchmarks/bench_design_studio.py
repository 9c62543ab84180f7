"""The studio's slow kinds of change on a 1 000-image block, timed as the studio runs them.

A :class:`orientviz.viewer.studio.Studio` on a design of ``--strips`` × ``--images`` images
(default 20 × 50 = 1 000; perimeter control every 4 bases), and the same with statoscope
and APR readings (offsets per strip). Each kind is a call of the studio's own method, as
its panel makes it, and what the panel then shows (:func:`shown`: the colour of every
point, the legend, the summary next to the accuracy law and the list of changes; not
viser's sending), followed by the studio's undo (not timed), ``--repeat`` times:

* the method switched to independent models (the first switch: the models design of the
  block is made; later switches of the same block reuse it);
* under independent models: an image at a strip's end removed (the models design of the
  new block; the bundle's update of the change waits until the bundle is shown,
  :mod:`orientviz.viewer.studio_live`), a control point added (an update), a control
  point added right after an image was removed (the bundle's update of the removal is
  made then), the method switched back to the bundle after an image was removed (the same);
* under the bundle: a cross strip; the plan changed: the image σ (a new design, the
  accuracy law of the same layout kept), the control spacing (a new design and law).

Peer in the same run: a new bundle assessment of the block (:func:`orientviz.design.assess_block`).
With ``--threads both`` everything runs with the default BLAS threads, then with one
(``threadpoolctl``), in the same process; wall and process CPU time (all threads) are
printed, medians and maxima. ``--heap viewer`` (default) first keeps large arrays on the
C heap as ``orientviz view design`` does when it builds the studio's view
(:func:`orientviz.viewer.studio_memory.keep_large_arrays_on_heap`); ``--heap glibc`` leaves
glibc's adaptive thresholds (a process setting: compare in two runs).

    python benchmarks/bench_design_studio.py                  # 1 000 images, both settings
    python benchmarks/bench_design_studio.py --strips 4 --images 10 --threads 1
"""

from __future__ import annotations

import argparse
import functools
import os
import time

import numpy as np
from bench_design import print_thread_tables  # a sibling script (benchmarks/ is on sys.path)

from orientviz.design import FlightDesign, _design, _layout, assess_block, design_auxiliary
from orientviz.viewer.studio import Studio, legend_html, scale_of
from orientviz.viewer.studio_memory import keep_large_arrays_on_heap


def shown(st: Studio) -> tuple:
    """What the studio's panel computes after a change (``StudioView.redraw`` and
    ``StudioPanel.refresh`` without the scene): the colours, the legend, the summary and
    the list of changes."""
    vals = st.values()
    scale = scale_of(vals, st.measure)
    return scale.colours(vals), legend_html(scale), st.summary_markdown(), st.changes_markdown()


def _timed(f) -> tuple[float, float]:
    t, c = time.perf_counter(), time.process_time()
    f()
    return time.perf_counter() - t, time.process_time() - c


def _kinds(st: Studio, plan: FlightDesign, tag: str, R: int, timed_kind) -> None:
    """Time every kind of change on the studio ``st`` and what it shows then
    (``timed_kind(name, setup, change, undo)``)."""

    def kind(name, setup, change, undo=None):
        timed_kind(name, setup, lambda k: (change(k), shown(st)), undo)

    b = st.block
    I = b.images
    ends = [int(np.flatnonzero(I.strip == s)[-1]) for s in range(plan.strips)]
    rng = np.random.default_rng(1)
    tie = rng.choice(np.flatnonzero(b.points.role == 0), size=R, replace=False)

    def nothing(k):
        return None

    def undo(k):
        st.undo()

    def to_models(k):
        st._models = None  # the first switch of this block: the models design is made
        st.set_method("models")

    def to_bundle(k):
        st.set_method("bundle")

    def remove_end(k):
        st.remove_images([ends[k % len(ends)]])

    def remove_again(k):
        st.set_method("models")
        remove_end(k)

    def control(k):
        st.set_control(int(tie[k]), 0.02)

    kind(f"method switched to independent models{tag}", to_bundle, to_models)
    kind(f"models: image at a strip's end removed{tag}", nothing, remove_end, undo)
    kind(f"models: control added (update){tag}", nothing, control, undo)
    kind(f"models: control added after an image removed{tag}", remove_end, control,
         lambda k: (st.undo(), st.undo()))  # fmt: skip
    kind(f"method switched back to the bundle after an image removed{tag}", remove_again,
         to_bundle, undo)  # fmt: skip
    xs = rng.uniform(I.X0[:, 0].min(), I.X0[:, 0].max(), size=R)
    kind(f"bundle: cross strip{tag}", nothing, lambda k: st.add_cross_strip(float(xs[k])), undo)
    kind(f"plan: image σ 4 µm (a new design){tag}", nothing,
         lambda k: st.set_plan(plan.with_(sigma_image_mm=0.004 + 1e-4 * k)), undo)  # fmt: skip

    def new_layout(k):  # a layout not seen before: its block and law made, not kept ones
        for f in (getattr(_design, "_mu_xy", None), getattr(_design, "_mu_z", None)):
            if f is not None:  # (a checkout without the kept laws computes them anyway)
                f.cache_clear()
        getattr(_layout, "_PLANNED", {}).clear()

    kind(f"plan: control every 3 bases (a new design and law){tag}", new_layout,
         lambda k: st.set_plan(plan.with_(control_spacing=3, sigma_image_mm=0.005 + 1e-4 * k)),
         undo)  # fmt: skip
    aux = design_auxiliary(b, plan) if st.live.auxiliary else None
    timed_kind(f"peer: new bundle assessment (assess_block){tag}", nothing,
         lambda k: assess_block(st.block, st.spec, auxiliary=aux))  # fmt: skip


def run(args, label: str) -> list[tuple[str, list[float], list[float]]]:
    rows: list[tuple[str, list[float], list[float]]] = []
    R = args.repeat

    def kind(name, setup, change, undo=None):
        ts, cs = [], []
        for k in range(R):
            setup(k)
            w, c = _timed(functools.partial(change, k))
            ts.append(w)
            cs.append(c)
            if undo is not None:
                undo(k)
        rows.append((name, ts, cs))
        print(
            f"  {name:<62} median {1e3 * np.median(ts):6.0f} ms  max {1e3 * max(ts):6.0f} ms"
            f"  CPU median {1e3 * np.median(cs):6.0f} ms"
        )

    for aux in (False, True):
        plan = FlightDesign(strips=args.strips, images_per_strip=args.images)
        if aux:
            plan = plan.with_(sigma_statoscope=0.3, sigma_apr=0.5)
        st = Studio(plan)
        b = st.block
        tag = " (statoscope + APR)" if aux else ""
        print(
            f"\n== {label}{tag}: {b.n_images} images, {b.n_points} points, "
            f"{b.n_observations} rays; load {os.getloadavg()[0]:.1f}"
        )
        _kinds(st, plan, tag, R, kind)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strips", type=int, default=20)
    ap.add_argument("--images", type=int, default=50)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", choices=("both", "default", "1"), default="both")
    ap.add_argument("--heap", choices=("viewer", "glibc"), default="viewer")
    args = ap.parse_args()
    if args.heap == "viewer":
        print("large arrays on the heap (as the viewer):", keep_large_arrays_on_heap())
    print_thread_tables(run, args)


if __name__ == "__main__":
    main()
