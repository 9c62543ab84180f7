"""The bundle problem: what is adjusted, and one Gauss-Newton step of it.

* :mod:`._checks` — how each point enters (:func:`point_setup` → :class:`PointSetup`),
  the datum and determinability checks before solving;
* :mod:`._parts` — the problem's typed parts (observations, interior and exterior
  orientation, points, additional parameters, the border's memory);
* :mod:`._state` — the iterate (:class:`BundleState`, a frozen value);
* :mod:`._run` — what one run writes (:class:`BundleRun`; the problem stays constant);
* :mod:`._problem` — :class:`BundleProblem`: misclosures and Jacobians at an iterate,
  vᵀPv, the point-reduced normal equations (through :mod:`orientviz.bundle.reduced`),
  the step and the next iterate;
* :mod:`._ap_normal`, :mod:`._border` — the border of the additional parameters and its
  solves; :mod:`._auxiliary`, :mod:`._auxiliary_border` — GNSS, statoscope and APR rows
  with their offsets/drifts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...faces import lazy_names
from ._border import (
    band_backward_solve,
    band_forward_solve,
    form_preconditioner,
    solve_bordered,
    solve_bordered_pcg,
)
from ._checks import PointSetup, datum_defect, image_condition_deficit, point_setup
from ._names import ParameterNames
from ._parts import (
    AdditionalBlock,
    BorderSolver,
    ExteriorBlock,
    ImageObservations,
    InteriorOrientation,
    PointBlock,
)
from ._problem import BundleProblem
from ._run import BundleRun
from ._state import BundleState, wrap

__all__ = [
    "AuxRows",
    "BundleAuxiliary",
    "auxiliary_rows",
    "band_backward_solve",
    "band_forward_solve",
    "form_preconditioner",
    "solve_bordered",
    "solve_bordered_pcg",
    "PointSetup",
    "datum_defect",
    "image_condition_deficit",
    "point_setup",
    "AdditionalBlock",
    "BorderSolver",
    "ExteriorBlock",
    "ImageObservations",
    "InteriorOrientation",
    "PointBlock",
    "BundleProblem",
    "ParameterNames",
    "BundleRun",
    "BundleState",
    "wrap",
]

#: Names loaded on first use: auxiliary data (GNSS, statoscope, APR) only in a block
#: that has them.
_LAZY = {
    "AuxRows": "._auxiliary",
    "BundleAuxiliary": "._auxiliary",
    "auxiliary_rows": "._auxiliary",
}

__getattr__ = lazy_names(__name__, _LAZY, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ._auxiliary import AuxRows, BundleAuxiliary, auxiliary_rows
