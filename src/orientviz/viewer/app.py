"""The orientviz viewer application: a viser server with a block scene and its GUI.

Use it from the command line (``orientviz view [FILE | DEMO] [--host] [--port]
[--export FILE.html]``), or from Python / a notebook::

    from orientviz.viewer import open_viewer
    app = open_viewer(block, port=8080)      # a Block, (Block, Adjustment) or a demo name
    app.show()                               # inline in Jupyter (an IFrame of the live server)
    app.export_html("block.html")            # a self-contained static snapshot

The server binds to 127.0.0.1 unless ``host`` is given. Errors while loading or while
adjusting are shown in the viewer (a message in the panel and a notification) and on
the terminal; the server keeps running.
"""

from __future__ import annotations

import argparse
import socket
import sys
import time
from pathlib import Path
from typing import Any

from ..block import Block
from ..errors import InputError, OrientvizError
from ..io.safeio import write_atomic
from ..io.solve import failure
from .background import FIRST_BROWSER_WAIT
from .callbacks import CallbackGate
from .demo import Demo
from .demos import DEMOS, demo_from_block, load_demo
from .geometry import VIEW_FOV
from .keys import keep_arrow_keys_on_sliders
from .snapshot import panel_markdown, with_panel
from .solved import (
    Solved,
    block_description,
    finite_state,
    last_finite_record,
    solution_demo,
    solve_target,
)

DEFAULT_DEMO = "block"
PROG = "orientviz view"


def check_host(host: str) -> None:
    """Raise :class:`InputError` if ``host`` is no address of this machine to listen on."""
    import errno

    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise InputError(f"--host {host}: not a valid host name or address ({exc})") from None
    for family, kind, proto, _, addr in infos:
        with socket.socket(family, kind, proto) as s:
            try:
                s.bind((addr[0], 0))
                return
            except OSError as exc:
                if exc.errno != errno.EADDRNOTAVAIL:
                    return
    raise InputError(f"--host {host}: no interface of this machine has that address")


def port_is_free(host: str, port: int) -> bool:
    """True if a TCP server could bind ``(host, port)`` now (port 0 is always free).

    The probe binds as viser's server does, with ``SO_REUSEADDR``: the closed connections
    of a viewer stopped a moment ago (TCP's TIME_WAIT, about a minute) do not hold the
    port, while a server still listening on it does.
    """
    if port == 0:
        return True
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def no_tunnel(server: Any) -> None:
    """Switch viser's share button off, and refuse a share request that comes anyway.

    viser's share button asks a public relay for a tunnel to the viewer, past the
    binding to 127.0.0.1; orientviz never opens one (``--host`` exposes it on purpose).
    """
    server.gui.configure_theme(show_share_button=False)

    def refused(verbose: bool = True) -> None:
        print("orientviz view: sharing through a public relay is off", file=sys.stderr)
        return None

    server.request_share_url = refused


def light_scene(server: Any) -> None:
    """Light the scene by viser's default lights only, without its environment map.

    viser lights a scene by an HDR environment map by default; the browser filters it
    (PMREM) on the first frame. Without a GPU (a projector laptop's software WebGL,
    headless Chromium) that blocks the page for ~15 s before the first picture. The
    viewer's lines and points are unlit, its meshes (ellipsoids, spheres, planes) read as
    well under the default lights; shadows are off (nothing here casts one).
    """
    server.scene.configure_environment_map(None)
    server.scene.configure_default_lights(True, cast_shadow=False)


class ViewerApp:
    """A running viewer: viser server, scene and GUI for one block (or demo).

    Parameters
    ----------
    content : Block, tuple (Block, Adjustment), Demo, str or None
        What to show: a block (start values), a block with its adjustment, a
        :class:`~orientviz.viewer.demo.Demo`, a demo name or a problem file path.
        None shows an empty scene (e.g. after a load error, see ``error``).
    host : str
        Interface to bind (default 127.0.0.1, local only).
    port : int
        TCP port (0 = any free port).
    error : str, optional
        A message to show at start (e.g. why a file could not be loaded).
    verbose : bool
        Print the URL to open.
    first_browser_wait : float
        Seconds a solve that runs in the background (a large imported model) waits for
        a first browser before it begins; a browser connecting meanwhile gets its first
        picture first (``orientviz view``:
        :data:`~orientviz.viewer.background.FIRST_BROWSER_WAIT`; default 0: at once).

    Raises
    ------
    InputError
        If the port is already in use.
    """

    def __init__(
        self,
        content: Any = None,
        *,
        host: str = "127.0.0.1",
        port: int = 8080,
        error: str | None = None,
        verbose: bool = True,
        first_browser_wait: float = 0.0,
    ) -> None:
        import viser

        check_host(host)
        if not port_is_free(host, port):
            raise InputError(f"port {port} on {host} is already in use; choose another with --port")
        self.server = viser.ViserServer(host=host, port=port, label="orientviz", verbose=False)
        if port and self.server.get_port() != port:  # lost a race for the port
            self.server.stop()
            raise InputError(f"port {port} on {host} is already in use; choose another with --port")
        self.host, self.port = host, self.server.get_port()
        no_tunnel(self.server)
        light_scene(self.server)
        keep_arrow_keys_on_sliders(self.server)
        self.verbose = verbose
        self.scene = None
        self.panel = None
        self.demo = None
        self.extra: dict[str, Any] = {}
        #: the solve started at opening (:mod:`orientviz.viewer.background`), or None
        self.background: Any = None
        self.messages: list[str] = []
        #: every GUI callback of this viewer runs through it; closed by :meth:`stop`
        self.gate = CallbackGate(self.report)
        self.first_browser_wait = float(first_browser_wait)
        self._message_md = self.server.gui.add_markdown("")
        self._message_md.visible = False
        if error:
            self.report(error)
        if verbose:  # the page loads while the scene is built (a browser gets it whole)
            print(f"orientviz viewer: open {self.url} in a browser (Ctrl-C to stop)", flush=True)
        if content is not None:
            try:
                with self.server.atomic():
                    self.load(content)
            except KeyboardInterrupt:  # Ctrl-C while building: leave no server thread behind
                self.server.stop()
                raise
            except Exception as exc:  # any load failure is shown; the server keeps running
                self.report(
                    str(exc) if isinstance(exc, OrientvizError) else f"{type(exc).__name__}: {exc}"
                )

    # ------------------------------------------------------------------ content
    @property
    def url(self) -> str:
        """The address to open in a browser."""
        return f"http://{self.host}:{self.port}"

    def load(self, content: Any) -> None:
        """Build the scene and GUI for ``content`` (see the class docstring)."""
        demo = resolve_content(content, background=True)  # a live viewer: see resolve_content
        self.demo = demo
        self._build(demo)

    def _build(self, demo: Any) -> None:
        from .block_geometry import BlockGeometry  # after the address: the page loads meanwhile
        from .panel import BlockPanel  # after the address, as BlockGeometry
        from .scene import BlockScene  # after the address, as BlockGeometry

        gui = self.server.gui
        self._head = gui.add_markdown(f"### {demo.title}\n{demo.description}")
        if demo.message:
            self.report(demo.message)
        if demo.state is not None:
            geo = BlockGeometry(demo.state)
            self.scene = BlockScene(self.server.scene, geo).build()
            self.panel = BlockPanel(self.server, self.scene, self.report, self.gate).build()
            self.panel.title = demo.title
            self._set_camera(*geo.default_camera(), geo.frame.size, up=geo.up)
        if demo.extra is not None:
            self.extra = demo.extra(self) or {}
            cam = self.extra.get("camera")
            if cam is not None and demo.state is None:
                self._set_camera(*cam)
        self.background = demo.background if self.panel is not None else None
        if self.background is not None:  # the solve runs while the start values are shown
            self.panel.show_pending(self.background)
            job = self.background  # a browser's first picture first, then the solve
            self.server.on_client_connect(lambda _c: job.hold() if job.running else None)
            job.start(self.take_background, self.panel.show_pending, self.first_browser_wait)

    def take_background(self, job: Any) -> None:
        """The solve started at opening has ended: show its solution (or its error).

        The block state takes the solution (:meth:`~orientviz.viewer.state.BlockState.
        adopt`), scene and panel are redrawn with the residual scale kept (the vectors
        shrink from the file's start values to the solution).
        """
        demo, panel = self.demo, self.panel
        if job.error is not None:
            panel.state.pending = None
            failed = failure(PROG, demo.name, job.error)
            self.report(failed[0] if failed else f"{type(job.error).__name__}: {job.error}")
            panel.show_pending(None)
            return
        solved = job.result
        demo.solution = solved.solution
        demo.description = block_description(solved)
        self._head.content = f"### {demo.title}\n{demo.description}"
        adj = solved.solution.adjustment
        panel.take_result(adj)
        if not finite_state(panel.state):  # NaN at the end: the last finite record, no blank
            panel.replay(last_finite_record(panel.state))
        if not adj.converged:
            self.report(f"the adjustment did not converge: {adj.reason}")

    def _set_camera(
        self, position: Any, look_at: Any, size: float, up: Any = (0.0, 0.0, 1.0)
    ) -> None:
        cam = self.server.initial_camera
        cam.position = tuple(float(v) for v in position)
        cam.look_at = tuple(float(v) for v in look_at)
        cam.up = tuple(float(v) for v in up)
        cam.fov = VIEW_FOV
        cam.near = max(size * 1e-4, 1e-3)
        cam.far = size * 50.0

    # ------------------------------------------------------------------ messages
    def guard(self, fn: Any) -> Any:
        """Wrap a GUI callback: an exception is reported, not raised; callbacks run one at
        a time, and not at all once the viewer is stopped (:meth:`stop`)."""
        if self.panel is not None:  # the panel's own slider echoes are skipped too
            return self.panel.guard(fn)
        return self.gate.wrap(fn)

    def report(self, message: str) -> None:
        """Show an error in the panel, as a notification and on the terminal."""
        self.messages.append(message)
        print(f"orientviz view: {message}", file=sys.stderr, flush=True)
        self._message_md.content = "**⚠ " + message.replace("\n", "  \n") + "**"
        self._message_md.visible = True
        for client in self.server.get_clients().values():
            try:
                client.add_notification("orientviz", message, color="red", auto_close_seconds=15.0)
            except Exception:  # a client that just went away
                pass

    # ------------------------------------------------------------------ output
    def export_html(self, path: str | Path) -> Path:
        """Write a self-contained static HTML snapshot of the scene (no server needed).

        Uses viser's own serializer (``scene.as_html``): the viser client with the
        recorded scene embedded (GUI controls are not part of a static snapshot), with
        the panel's read-out (σ̂0, state, largest residual) and legend in a box.
        """
        title = self.demo.title if self.demo is not None else ""
        page = with_panel(self.server.scene.as_html(), title, panel_markdown(self))
        return write_atomic(path, page)

    def show(self, height: int = 600, static: bool = False) -> Any:
        """Display the viewer inline in Jupyter.

        Parameters
        ----------
        height : int
            Height in pixels.
        static : bool
            False (default): an IFrame of the live server (sliders and buttons work while
            the kernel runs). True: viser's embedded static snapshot of the scene, which
            stays in the saved notebook (no controls).
        """
        if static:
            self.server.scene.show(height=height)
            return None
        from IPython.display import IFrame, display

        frame = IFrame(self.url, width="100%", height=height)
        display(frame)
        return frame

    def stop(self) -> None:
        """Stop the server (and a solve still running in the background).

        A GUI callback still running (a redraw after a click) ends first, and any that
        arrives later does nothing: nothing is sent to a server that has stopped.
        """
        if self.background is not None:
            self.background.cancel()
        self.gate.close()
        self.server.stop()

    def wait(self) -> None:
        """Block until Ctrl-C, then stop the server."""
        try:
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            print("\norientviz viewer: stopped", file=sys.stderr)
        finally:
            self.stop()


def resolve_content(
    content: Any, options: dict[str, Any] | None = None, background: bool = False
) -> Any:
    """Turn what :class:`ViewerApp` accepts into a :class:`~orientviz.viewer.demo.Demo`.

    ``options`` override a problem file's (``--free``, ``--fix``, ``--max-iter``);
    ``background``: a large imported model opens at its start values and is solved in
    the background (:func:`~orientviz.viewer.solved.solve_target`).

    Raises
    ------
    InputError
        Unknown demo, unreadable file or an object the viewer cannot show.
    """
    if isinstance(content, str | Path):
        name = str(content)
        if name in DEMOS and options:
            raise InputError(
                f"--free, --fix and --max-iter apply to problem files, not the demo {name!r}"
            )
        return load_demo(name) if name in DEMOS else demo_from_file(name, options, background)
    if isinstance(content, Solved):
        return solution_demo(content)
    if isinstance(content, Demo):
        return content
    if isinstance(content, Block):
        return demo_from_block(content)
    if isinstance(content, tuple) and len(content) == 2 and isinstance(content[0], Block):
        return demo_from_block(content[0], content[1])
    raise InputError(
        f"cannot show a {type(content).__name__}; expected a Block, (Block, Adjustment) or a demo name"
    )


def demo_from_file(
    target: str, options: dict[str, Any] | None = None, background: bool = False
) -> Any:
    """Solve a problem file or shipped data set as ``orientviz solve`` does; its demo.

    ``options`` override the file's (``--free``, ``--fix``, ``--max-iter``). Raises what
    ``solve`` reports (:func:`orientviz.io.solve.failure`), before any server.
    ``background``: see :func:`~orientviz.viewer.solved.solve_target` (the demo then
    carries the solve still to run, ``Demo.background``).
    """
    return solution_demo(solve_target(target, options, background))


def open_viewer(
    content: Any = DEFAULT_DEMO, host: str = "127.0.0.1", port: int = 8080, **kw: Any
) -> ViewerApp:
    """Start a viewer on ``content`` (Block, (Block, Adjustment), demo name or file) and return it."""
    return ViewerApp(content, host=host, port=port, **kw)


def export_html(content: Any, path: str | Path) -> Path:
    """Build the scene of ``content`` on a private server and write a static HTML snapshot."""
    import contextlib
    import io

    demo = resolve_content(content)  # load errors are raised here, before any server starts
    if demo.background is not None:  # a snapshot shows the solution: solve it now
        demo = solution_demo(demo.background.run())
    # viser prints its server box and "Server stopped" whatever `verbose` says; this
    # server is private and never announced, so its prints go nowhere
    with contextlib.redirect_stdout(io.StringIO()):
        app = ViewerApp(demo, host="127.0.0.1", port=0, verbose=False)
        try:
            if app.messages:
                raise InputError(app.messages[0])
            return app.export_html(path)
        finally:
            app.stop()


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz view [FILE | NAME | DEMO] [--host] [--port] [--export FILE.html]``;
    ``orientviz view design FILE``: the design studio on a problem file's geometry.

    A file or data set that cannot be solved gets ``orientviz solve``'s one line and exit
    code before any server starts. Returns the exit code.
    """
    target = args.target or DEFAULT_DEMO
    options = {k: getattr(args, k) for k in ("fix", "free", "max_iter")
               if getattr(args, k, None) is not None}  # fmt: skip
    plan_from = getattr(args, "file", None)
    if plan_from and target != "design":
        print(f"{PROG}: a second argument (FILE) goes with `design` only", file=sys.stderr)
        return 2
    try:
        if plan_from:  # the design studio on a problem file's geometry
            from .demos import design_from_file  # the design studio: for its demo only

            content, target = design_from_file(plan_from), plan_from
        else:
            # a bad file: refused before a server; a large imported model opens at its
            # start values while it is solved (not for a snapshot, which shows the solution)
            live = not getattr(args, "export", None)
            content = resolve_content(target, options, background=live)
    except Exception as exc:
        failed = failure(PROG, target, exc)
        if failed is None:
            raise
        print(failed[0], file=sys.stderr)
        return failed[1]
    if getattr(args, "export", None):
        try:
            out = export_html(content, args.export)
        except OrientvizError as exc:
            print(f"{PROG}: {exc}", file=sys.stderr)
            return exc.exit_code
        print(f"{PROG}: wrote {out}")
        return 0
    app = None
    try:
        app = ViewerApp(
            content, host=args.host, port=args.port, first_browser_wait=FIRST_BROWSER_WAIT
        )
        while True:
            time.sleep(0.5)
    except InputError as exc:
        print(f"orientviz view: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\norientviz view: stopped", file=sys.stderr)
    finally:
        if app is not None:
            app.stop()
    return 0
