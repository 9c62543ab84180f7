"""``orientviz view`` on a large imported model: the server first, the evaluation while the page loads.

A large block whose file gives every start value (an imported reconstruction,
:func:`~orientviz.viewer.solved.opens_before_solve`) is read and validated, its geometry
checked (:func:`orientviz.io.solve.check_geometry`) and its datum prepared as
``orientviz solve`` prepares it (:func:`orientviz.io.kinds.block.prepare`) before any
server starts: a file ``solve`` refuses there, or a datum with a defect or an image with
too few conditions (e.g. a model without control opened without ``--free``), gets
``solve``'s line and exit code without a server, as every other file does (those two
through the ordinary path, which evaluates first). Only then does the server start and print its address; the evaluation
at the file's start values (σ̂0, the residuals and their colours) and the scene are
computed while the browser loads the viewer's page, which shows them when they arrive.
An evaluation that fails after all (a block that is not connected or not determinable)
ends the command with ``solve``'s line and exit code, and the server stops.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..bundle.problem import datum_defect, image_condition_deficit, point_setup
from ..io.kinds.block import check_mode, prepare, with_check_rays
from ..io.solve import check_geometry
from .solved import opens_before_solve, solution_demo, start_values


@dataclass
class LargeModel:
    """A loaded large imported model that opens before its evaluation (see the module).

    ``problem``: the loaded problem (:func:`~orientviz.viewer.solved.load_target`);
    ``target``: its name or path as given on the command line.
    """

    problem: Any
    target: str

    def loading_text(self) -> str:
        """Markdown the panel shows while the model is evaluated."""
        b = self.problem.data
        return (
            f"### {self.problem.name or self.target}\n"
            f"evaluating {b.n_images} images, {b.n_points} points and "
            f"{b.n_observations} image points at the file's start values …"
        )

    def demo(self) -> Any:
        """The viewer's demo at the file's start values, the solve still to run."""
        return solution_demo(start_values(self.problem))


def opens_before_evaluation(problem: Any) -> bool:
    """True for a model that opens before its evaluation (see the module): a large
    imported model whose geometry passes ``solve``'s checks and whose prepared datum has
    no defect.

    Raises
    ------
    InputError, AdjustmentError, …
        What ``orientviz solve`` raises in those checks (before any server).
    """
    if problem.kind != "block" or not opens_before_solve(problem):
        return False
    check_geometry(problem)
    block, _ = prepare(problem)
    if check_mode(problem) == "rays":
        block = with_check_rays(block)
    setup = point_setup(block, str(problem.options.get("control", "fixed")))
    return not image_condition_deficit(block, setup).any() and datum_defect(block, setup)[0] == 0
