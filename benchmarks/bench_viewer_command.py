"""What a user of ``orientviz view`` waits for: the command typed → the page's first rendered picture.

Each run starts ``orientviz view TARGET [--free] --port P`` as a user does (a fresh process:
interpreter, imports, reading, evaluation, scene); a headless Chromium that is already
running (software WebGL, the test suite's flags, 1280 × 800) opens the page the moment the
command prints its address. No screenshots are taken while waiting (each one makes the
software renderer draw a frame and would slow the page it measures): a script in the page
counts the primitives of the WebGL draw calls of each frame. The first picture is the
first frame that draws ≥ 90 % of the primitives of the settled scene (learnt in one
calibration run per target that is not counted); right after that frame the page reads
one pixel back, which waits until the GPU process (SwiftShader) has finished drawing it.

Printed per run and as medians (seconds from the command's start): ``ready_s`` the address
printed; ``ws_s`` the page's websocket open (viser's page started); ``msgs_s`` the last
websocket frame before the picture; ``drawn_s`` the frame's draw calls issued;
``rendered_s`` that frame finished by the GPU (what the user waits for); ``py_cpu_s`` the
command's CPU and ``chrome_cpu_s`` Chromium's (all processes) at that moment. With two
``--tree`` the trees alternate and the ratios B/A are printed; several targets (``;``)
alternate too (e.g. a model and the radar demo, the page's floor).

The command runs in its own session (as a terminal and a browser are). The kernel shares the
cores between sessions (autogroups), not by nice values: ``--group-nice -10`` (root) raises the
command's and the browser's groups, a quiet machine emulated on a busy one.

Run:  python benchmarks/bench_viewer_command.py "soft.json;radar" --free --tree . --repeat 5
Never asserted; report the command and ``uptime`` with the numbers.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import statistics
import subprocess
import tempfile
import time

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]  # fmt: skip
SHARE = 0.9  # share of the settled frame's primitives that makes the first picture
PAGE = r"""
(() => {
  const st = window.__frames = {list: [], prims: 0, last: 0, gl: null, rendered: null};
  for (const P of [WebGL2RenderingContext.prototype, WebGLRenderingContext.prototype]) {
    for (const k of ['drawArrays', 'drawElements', 'drawArraysInstanced', 'drawElementsInstanced']) {
      const f = P[k];
      P[k] = function (...a) {
        const n = a[k.startsWith('drawArrays') ? 2 : 1] * (k.endsWith('Instanced') ? a[a.length - 1] : 1);
        st.prims += n; st.last = performance.now(); st.gl = this;
        return f.apply(this, a);
      };
    }
  }
  (function frame() {
    if (st.prims > 0) {
      st.list.push([performance.timeOrigin + st.last, st.prims]);
      if (window.__threshold && st.prims >= window.__threshold && st.rendered === null) {
        st.gl.readPixels(0, 0, 1, 1, st.gl.RGBA, st.gl.UNSIGNED_BYTE, new Uint8Array(4));
        st.rendered = performance.timeOrigin + performance.now();
      }
      st.prims = 0;
    }
    requestAnimationFrame(frame);
  })();
})();
"""
KEYS = ("ready_s", "ws_s", "msgs_s", "drawn_s", "rendered_s", "py_cpu_s", "chrome_cpu_s")
HZ = os.sysconf("SC_CLK_TCK")


def _cpu(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` (0 if it has gone)."""
    try:
        stat = open(f"/proc/{pid}/stat").read()
    except OSError:
        return 0.0
    rest = stat[stat.rindex(")") + 2 :].split()
    return (int(rest[11]) + int(rest[12])) / HZ


def _chromium() -> dict[int, float]:
    """CPU seconds of each Chromium process below this one (the playwright driver's)."""
    kids: dict[int, list[int]] = {}
    for d in filter(str.isdigit, os.listdir("/proc")):
        try:
            stat = open(f"/proc/{d}/stat").read()
        except OSError:
            continue
        kids.setdefault(int(stat[stat.rindex(")") + 2 :].split()[1]), []).append(int(d))
    out, stack = {}, [os.getpid()]
    while stack:
        for k in kids.get(stack.pop(), []):
            stack.append(k)
            try:
                if "chrom" in open(f"/proc/{k}/comm").read():
                    out[k] = _cpu(k)
            except OSError:
                pass
    return out


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _group_nice(pid: int | str, nice: int | None) -> None:
    """Set the nice value of the scheduler's autogroup (the session) of ``pid``."""
    if nice is not None:
        with open(f"/proc/{pid}/autogroup", "w") as f:
            f.write(str(nice))


def run(browser, tree: str, target: str, free: bool, threshold: float | None,
        group_nice: int | None = None) -> dict:  # fmt: skip
    """One ``orientviz view`` from its start to the first rendered picture (see the module)."""
    port = _port()
    env = dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(tree), "src"))
    arg = os.path.abspath(target) if os.path.isfile(target) else target
    cmd = ["orientviz", "view", arg, "--port", str(port)] + (["--free"] if free else [])
    c0 = _chromium()
    t0 = time.time()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True, cwd=tempfile.gettempdir(), start_new_session=True)  # fmt: skip
    _group_nice(proc.pid, group_nice)
    for line in proc.stdout:
        if "open http" in line:
            break
    out: dict = {"ready_s": time.time() - t0}
    page = browser.new_page(viewport={"width": 1280, "height": 800})
    if threshold:
        page.add_init_script(f"window.__threshold = {threshold};")
    page.add_init_script(PAGE)
    frames: list[float] = []

    def websocket(ws) -> None:
        out.setdefault("ws_s", time.time() - t0)
        ws.on("framereceived", lambda _f: frames.append(time.time() - t0))

    page.on("websocket", websocket)
    page.goto(f"http://127.0.0.1:{port}", wait_until="commit")
    best, since, cpu = 0, time.time(), None
    while time.time() - t0 < 60:  # until the scene has settled (2 s without a larger frame)
        time.sleep(0.1)
        state = page.evaluate("() => [Math.max(0, ...window.__frames.list.map(f => f[1])), "
                              "window.__frames.rendered]")  # fmt: skip
        if cpu is None and state[1] is not None:
            cpu = (_cpu(proc.pid), sum(c - c0.get(k, 0.0) for k, c in _chromium().items()))
        if state[0] > best:
            best, since = state[0], time.time()
        elif best and time.time() - since > 2.0 and (threshold is None or cpu is not None):
            break
    listed = page.evaluate("() => [window.__frames.list, window.__frames.rendered]")
    page.close()
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        proc.kill()
    out["prims"] = max(f[1] for f in listed[0])
    if threshold is None:  # the calibration run
        return out
    drawn = next(f[0] for f in listed[0] if f[1] >= threshold) / 1e3 - t0
    out.update(drawn_s=drawn, rendered_s=listed[1] / 1e3 - t0)
    out["msgs_s"] = max((f for f in frames if f <= drawn), default=float("nan"))
    out.update(py_cpu_s=cpu[0], chrome_cpu_s=cpu[1])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("targets", help="problem file(s) or demo name(s), separated by ';'")
    ap.add_argument("--free", action="store_true", help="--free for the problem files")
    ap.add_argument("--tree", action="append", default=[])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--group-nice", type=int, default=None,
        help="nice value of the command's and the browser's scheduler groups (root for < 0)",
    )  # fmt: skip
    a = ap.parse_args()
    _group_nice("self", a.group_nice)
    from playwright.sync_api import sync_playwright

    trees, targets = a.tree or ["."], a.targets.split(";")
    combos = [(t, g) for _ in range(a.repeat) for t in trees for g in targets]
    results: dict[tuple[str, str], list[dict]] = {}
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                    args=FLAGS)  # fmt: skip
        free = {g: a.free and os.path.isfile(g) for g in targets}
        gn = a.group_nice
        threshold = {
            g: SHARE * run(browser, trees[0], g, free[g], None, gn)["prims"] for g in targets
        }
        for tree, g in combos:
            r = run(browser, tree, g, free[g], threshold[g], gn) | {"load": os.getloadavg()[0]}
            results.setdefault((tree, g), []).append(r)
            print(tree, g, {k: round(v, 2) for k, v in r.items()}, flush=True)
        browser.close()
    med = {c: {k: statistics.median(r[k] for r in rs) for k in KEYS} for c, rs in results.items()}
    for (tree, g), m in med.items():
        print("median", tree, g, {k: round(v, 2) for k, v in m.items()})
    if len(trees) == 2:
        for g in targets:
            A, B = med[(trees[0], g)], med[(trees[1], g)]
            print("ratio B/A", g, {k: round(B[k] / A[k], 3) for k in KEYS if A[k]})


if __name__ == "__main__":
    main()
