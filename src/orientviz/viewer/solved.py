"""The viewer on a problem file or shipped data set: solved as ``orientviz solve`` solves it.

``orientviz view FILE|NAME`` (and ``open_viewer(path)``, the notebook's inline viewer)
load the problem with :func:`orientviz.io.solve.load_named` and solve it with
:func:`orientviz.io.solve.solve_problem` — the very call ``orientviz solve`` makes:
approximations where the file gives none, the file's options, camera models and
additional parameters, units. The viewer then shows the block the solve started from
(``Solution.start``) and replays the solve's own iterations (``adjustment.history``);
σ̂0 in the panel is the solution's.

A problem that cannot be loaded or solved raises here, before any server starts; the
command prints :func:`orientviz.io.solve.failure`'s one line and exit code. A solve that
does not converge is shown with its message and its last state.

The viewer's actions (a ray, an image or a control point off and on) re-solve with
:class:`FileAdjuster`, the bundle run of :func:`orientviz.io.kinds.block.adjust_block`
(the file's model and options), and the misclosures drawn follow the file's camera model
(:class:`CameraTerms`).

Large blocks (more than :data:`PRECISION_LIMIT` image observations) are solved without
the precision pass at the start — the estimates and σ̂0 are the same, the cofactors
(normalised residuals, ellipsoids) follow on request in the panel. A large block whose
file gives every start value (an imported reconstruction, :func:`opens_before_solve`)
opens at those values — evaluated by the solve's own model, datum and checks, no step —
while the solve runs in a thread (``solve_target(..., background=True)``); the viewer
then takes the solution (:meth:`orientviz.viewer.app.ViewerApp.take_background`). ``dbat_roma`` (DBAT's
ROMA bundle, :mod:`orientviz.reproduce.dbat_roma`; not a problem file) opens as the
problem its reproduction solves (:func:`roma_problem`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..blas import blas_threads
from ..block import Block
from ..bundle import block_camera_options
from ..bundle.problem import BundleProblem, BundleState, point_setup
from ..errors import InputError
from ..io.datasets import dataset_path
from ..io.kinds.block import adjust_block
from ..io.problem import Units, problem_from_block
from ..io.solve import load_named, solve_problem
from ..reproduce import dbat_roma as roma
from .background import BackgroundSolve
from .deformation import lens_deformation_extra
from .demo import Demo
from .geometry import framing
from .state import BlockState
from .view_units import ViewUnits

F64 = NDArray[np.float64]


#: Above this many image observations the viewer opens without the precision pass (the
#: cofactors of 10⁵ observations cost more than the solve); the panel says so and offers it.
PRECISION_LIMIT: int = 20_000


@dataclass
class Solved:
    """A problem file and its solution (what ``orientviz solve`` computes).

    ``pending``: the solution is the evaluation at the file's start values (no step
    taken) and the solve itself is still to run (:func:`solve_target`, ``background``).
    """

    problem: Any
    solution: Any
    pending: bool = False


def _large_block(problem: Any) -> bool:
    return (
        problem.kind == "block"
        and isinstance(problem.data, Block)
        and problem.data.n_observations > PRECISION_LIMIT
    )


def opens_before_solve(problem: Any) -> bool:
    """True for a block problem above :data:`PRECISION_LIMIT` image observations whose
    file gives start values for every image and point (an imported reconstruction)."""
    if not _large_block(problem):
        return False
    b = problem.data
    finite = np.isfinite
    return bool(
        finite(b.images.X0).all() and finite(b.images.angles).all() and finite(b.points.xyz).all()
    )


def solve_problem_as_viewer(problem: Any, callback: Any = None) -> Any:
    """``solve_problem`` as the viewer runs it: large blocks on one BLAS thread, without
    the precision pass (same estimates and σ̂0), every iteration's parameters kept."""
    if _large_block(problem):  # many small BLAS calls: one thread is faster
        kw = {"callback": callback} if callback is not None else {}
        with blas_threads(1):
            return solve_problem(problem, precision=False, history_x=True, **kw)
    return solve_problem(problem)


def solve_target(
    target: str, options: dict[str, Any] | None = None, background: bool = False
) -> Solved:
    """Load ``target`` (a path or a shipped data set's name) and solve it as ``solve`` does.

    ``options`` override the file's (as ``solve``'s ``--free``, ``--fix``, ``--max-iter``
    do). A block of more than :data:`PRECISION_LIMIT` image observations is solved
    without the precision pass (same estimates and σ̂0). With ``background`` such a
    block whose file gives every start value (:func:`opens_before_solve`) is only
    evaluated at those values here — the checks, the datum and the model of the solve,
    no step — and comes back ``pending``: the viewer shows it at once and solves it in a
    thread (:mod:`orientviz.viewer.background`).

    Raises
    ------
    InputError, AdjustmentError, …
        What ``orientviz solve`` reports (:func:`orientviz.io.solve.failure`).
    """
    problem = VIEWER_NAMES[target]() if target in VIEWER_NAMES else load_named(target)
    if options:
        problem.options = dict(problem.options, **options)
    if background and opens_before_solve(problem):
        with blas_threads(1):
            start = solve_problem(problem, precision=False, history_x=True, max_iter=0)
        return Solved(problem, start, pending=True)
    return Solved(problem, solve_problem_as_viewer(problem))


def roma_problem() -> Any:
    """DBAT's ROMA bundle as a block problem: what ``orientviz reproduce dbat-roma`` solves.

    60 images, 26 321 points, 90 561 image points (σ 1 px); the backward lens model with
    c, x0, y0, K1, K2 free from the camera file's values; the datum of DBAT's script (the
    first photo and one base component held, :func:`orientviz.reproduce.dbat_roma.block`).
    """
    block = roma.block()  # reads the measurements (read_roma) once
    cam = (
        ET.parse(dataset_path("dbat_sxb").parent / "roma" / "EOS5DMarkII.xml")
        .getroot()
        .find("cameras/camera")
    )
    K = [float(v) for v in cam.findtext("K").split(",")]
    spec = {"model": "backward", "free": list(roma.LENS_FREE), "sigma": {},
            "values": {"K1": K[0], "K2": K[1]}, "r0": None}  # fmt: skip
    block.cameras.model = [spec]
    pixel = float(block.observations.sigma[0, 0])  # σ = 1 px
    units = Units(length="m", angle="deg", image="px", pixel_size=pixel)
    desc = "DBAT's ROMA bundle (data/script/romabundledemo), self-calibrating, no control"
    opts = {"tol": roma.TOL, "max_iter": 50}
    return problem_from_block(block, units=units, name="dbat_roma", description=desc, options=opts)


#: names the viewer opens besides the shipped data sets (problems built in memory)
VIEWER_NAMES: dict[str, Any] = {"dbat_roma": roma_problem}


class FileAdjuster:
    """``adjuster(block, max_iter, precision=True)``: the bundle with the file's model.

    Runs :func:`orientviz.io.kinds.block.adjust_block` (the adjustment of
    ``orientviz solve``) on ``block`` with the iteration limit and precision the
    viewer asks for; the parameters of every iteration are kept for the scrubber.
    """

    def __init__(self, problem: Any) -> None:
        self.problem = problem

    def __call__(self, block: Block, max_iter: int, precision: bool = True) -> Any:
        adj, _ = adjust_block(
            self.problem, block, max_iter=max_iter, precision=precision, history_x=True
        )
        return adj


class CameraTerms:
    """Image misclosures (n, 2) mm through the file's camera model.

    The camera model (lens model or additional parameters of ``cameras[]``) is part of
    the bundle's projection; the misclosure of a state with camera terms ``ap`` (the
    result's ``"additional"`` block) is the bundle's own, from its public problem
    (:class:`orientviz.bundle.problem.BundleProblem`). Observations the bundle does not use
    (rays of independent check points) get the pinhole misclosure.
    """

    def __init__(self, options: dict[str, Any], control: str = "fixed") -> None:
        self.options = options
        self.control = control
        self._cache: tuple[Any, Any] | None = None

    @classmethod
    def of(cls, problem: Any, block: Block) -> CameraTerms | None:
        """The camera terms of ``problem`` (None if its cameras have no model)."""
        opts = block_camera_options(block)
        if not opts:
            return None
        return cls(opts, str(problem.options.get("control", "fixed")))

    def _problem(self, block: Block) -> Any:
        key = (id(block.observations), block.n_images, block.n_points)
        if self._cache is None or self._cache[0] != key:
            opts = block_camera_options(block)  # ap groups of this (sub-)block
            setup = point_setup(block, self.control)
            self._cache = (key, BundleProblem(block, setup, **opts))
        return self._cache[1]

    def misclosure(self, block: Block, ap: F64) -> F64:
        """l − f (n, 2) in mm at the block's orientations and points and terms ``ap``."""
        prob = self._problem(block)
        e = block.residuals()
        if np.size(ap) != prob.q:
            return e
        st = BundleState(
            block.images.X0, block.images.angles, block.points.xyz, np.asarray(ap, float),
            np.zeros(prob.na),
        )  # fmt: skip
        rw = prob.residuals(st, jac=False)[0]
        e[np.asarray(prob.obs.index)] = rw / prob.obs.weight
        return e


def solution_demo(solved: Solved, title: str | None = None) -> Demo:
    """The :class:`~orientviz.viewer.demo.Demo` of a solved problem file.

    Block problems: the block the solve started from, its iterations on the scrubber,
    the result at the end (σ̂0 the solution's), actions re-solving with the file's model.
    Other frame kinds (resection, intersection): the solved block. Kinds without images
    (pair, similarity, radar): the solution's report in the panel and its points.
    """
    problem, sol = solved.problem, solved.solution
    adj = sol.adjustment
    name = title or problem.name or problem.kind
    head = _head(solved)
    message = None
    if not adj.converged and not solved.pending:
        message = f"the adjustment did not converge: {adj.reason}"
    if problem.kind == "block" and sol.start is not None and "exterior" in adj.groups:
        block = sol.start
        state = BlockState(
            block, adj, adjuster=FileAdjuster(problem), camera=CameraTerms.of(problem, block),
            units=ViewUnits.of(problem.units),
        )  # fmt: skip
        if not finite_state(state):  # the last state has NaN: show the last finite record
            state.replay(last_finite_record(state))
        desc = block_description(solved)
        extra = lens_deformation_extra(problem, state) if state.camera is not None else None
        demo = Demo("file", name, desc, state, extra, message, sol)
        if solved.pending:
            demo.background = BackgroundSolve(
                lambda cb: Solved(problem, solve_problem_as_viewer(problem, cb)),
                float(adj.sigma0),
            )
            state.pending = "the solve started at opening is still running"
        return demo
    if isinstance(problem.data, Block):
        block = _solved_block(problem.data, sol)
        state = BlockState(
            block, adjuster=_not_stepped(problem.kind), units=ViewUnits.of(problem.units)
        )
        state.history[0].sigma0 = float(adj.sigma0)  # the solution's, not recomputed
        desc = f"{head}; σ̂0 = {adj.sigma0:.10g}. {block.summary()}."
        return Demo("file", name, desc, state, None, message, sol)
    desc = (
        f"{head}: σ̂0 = {adj.sigma0:.10g}, redundancy {adj.redundancy}, "
        f"{sol.n_iterations} iterations; {adj.reason}. The scene shows the solution's points."
    )
    return Demo("file", name, desc, None, _points_extra(sol), message, sol)


def _head(solved: Solved) -> str:
    p, method = solved.problem, solved.solution.method
    if solved.pending:
        return (
            f"{p.kind} problem, being solved by {method} in the background as `orientviz "
            "solve` solves it; shown until the solve ends: the file's own start values"
        )
    return f"{p.kind} problem, solved by {method} as `orientviz solve` solves it"


def block_description(solved: Solved) -> str:
    """The panel's description of a solved block problem (what was solved, the block)."""
    return f"{_head(solved)}. {solved.solution.start.summary()}."


def finite_state(state: Any) -> bool:
    """True if every orientation and point of the state is finite."""
    b = state.block
    return bool(np.all(np.isfinite(b.images.X0)) and np.all(np.isfinite(b.points.xyz)))


def last_finite_record(state: Any) -> int:
    """Index of the last history record without NaN (0 if none)."""
    for k in range(len(state.history) - 1, -1, -1):
        s = state.history[k]
        if np.all(np.isfinite(s.X0)) and np.all(np.isfinite(s.xyz)):
            return k
    return 0


def _solved_block(block: Block, sol: Any) -> Block:
    """``block`` with the solution's orientations and points where they were estimated."""
    out = block.copy()
    im = {k: i for i, k in enumerate(out.images.ids)}
    for k, ident in enumerate(sol.image_ids):
        if np.all(np.isfinite(sol.X0[k])):
            out.images.X0[im[ident]] = sol.X0[k]
            out.images.angles[im[ident]] = sol.angles[k]
    pt = {k: i for i, k in enumerate(out.points.ids)}
    for k, ident in enumerate(sol.point_ids):
        if ident in pt and np.all(np.isfinite(sol.xyz[k])):
            out.points.xyz[pt[ident]] = sol.xyz[k]
    return out


def _not_stepped(kind: str) -> Any:
    def adjuster(block: Block, max_iter: int, precision: bool = True) -> Any:
        raise InputError(
            f"a {kind!r} problem is shown as solved; stepping and actions apply to block problems"
        )

    return adjuster


def _points_extra(sol: Any) -> Any:
    """Extra content of kinds without a block: the solution's points, if any."""

    def extra(app: Any) -> dict:
        xyz = np.asarray(sol.xyz, dtype=float).reshape(-1, 3)
        xyz = xyz[np.all(np.isfinite(xyz), axis=1)]
        if xyz.shape[0] == 0:
            return {}
        centre = xyz.mean(axis=0)
        size = float(np.ptp(xyz, axis=0).max()) or 1.0
        P = (xyz - centre).astype(np.float32)
        app.server.scene.add_point_cloud(
            "/solution/points", P, (220, 40, 40), point_size=0.04 * size, point_shape="circle"
        )
        for k, ident in enumerate(sol.point_ids[: min(len(sol.point_ids), 40)]):
            if k < P.shape[0]:
                app.server.scene.add_label(f"/solution/labels/{k}", str(ident), position=P[k])
        pos, look = framing(P)
        return {"camera": (pos, look, size)}

    return extra
