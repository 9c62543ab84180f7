"""The bundle block adjustment: all image bundles of a block at once (collinearity).

The face of the bundle's house. What a user calls:

* :func:`bundle_adjust` — the adjustment (Schur complement on the reduced camera
  system, self-calibration, auxiliary data, exact precision);
* self-calibration: :func:`ap_set` (:class:`Ebner12`, :class:`Brown`, :class:`Gruen44`,
  the :class:`AdditionalParameters` protocol), :func:`analyse` → :class:`APAnalysis`,
  :func:`self_calibrate` → :class:`SelfCalibration`; the camera itself (c, principal
  point, affinity, shear, radial and decentring distortion, backward or forward) inside
  the projection: :class:`LensModel` → ``result.camera`` (:class:`LensEstimates`);
* gross errors: :func:`clean_block`, :func:`bundle_solver`, :func:`cleaned_block`,
  :func:`ray_labels`; reliability per ray: :func:`ray_reliability` →
  :class:`RayReliability`;
* auxiliary data by alternation (teaching): :func:`adjust_with_auxiliary`.

The parts behind it (private modules, one job each): ``_adjust`` (the loop and the
problem), ``_checks`` (datum and determinability checks before solving), ``_kernel``
(collinearity and its derivatives, vectorised), ``_reduced`` (the reduced camera system:
structure, orderings, factorisation), ``_ap_normal`` / ``_border`` (the border of the
additional parameters and its solves), ``_auxiliary`` / ``_auxiliary_border`` (GNSS,
statoscope, APR rows and their offsets/drifts), ``_precision`` / ``_precision_ap``
(cofactor blocks, redundancy numbers), ``_result`` (the result), ``_additional``
(additional-parameter sets), ``_selfcal``, ``_cleaning``, ``_reliability``,
``_alternation``, ``_lens`` (the camera model inside the projection). The numerical building blocks that tests and benchmarks use are
exported too (second group of ``__all__``).
"""

from ._additional import AdditionalParameters, APAnalysis, Brown, Ebner12, Gruen44, analyse, ap_set
from ._adjust import bundle_adjust
from ._alternation import AuxiliaryResult, adjust_with_auxiliary
from ._auxiliary import AuxRows, BundleAuxiliary, auxiliary_rows
from ._border import (
    band_backward_solve,
    band_forward_solve,
    form_preconditioner,
    solve_bordered,
    solve_bordered_pcg,
)
from ._checks import PointSetup, datum_defect, image_condition_deficit, point_setup
from ._cleaning import bundle_solver, clean_block, cleaned_block, ray_labels
from ._kernel import collinearity_block, normalised_block, project_block
from ._lens import BoundLens, LensEstimates, LensModel, lens_model
from ._normal import APBorder, AuxBorder, NormalEquations
from ._parts import (
    AdditionalBlock,
    BorderSolver,
    ExteriorBlock,
    ImageObservations,
    InteriorOrientation,
    PointBlock,
)
from ._precision import banded_selected_inverse
from ._problem import BundleProblem
from ._reduced import SOLVERS, ReducedStructure, factor_reduced, geometric_orderings, inv3
from ._reliability import RayReliability, ray_reliability
from ._result import BundleResult, ExteriorPairs, RayGains
from ._selfcal import SelfCalibration, self_calibrate
from ._state import BundleState

__all__ = [
    # the adjustment and its companions
    "bundle_adjust",
    "BundleResult",
    "RayGains",
    "ExteriorPairs",
    "BundleProblem",
    "BundleState",
    "NormalEquations",
    "APBorder",
    "AuxBorder",
    "ImageObservations",
    "InteriorOrientation",
    "ExteriorBlock",
    "PointBlock",
    "AdditionalBlock",
    "BorderSolver",
    "AdditionalParameters",
    "APAnalysis",
    "LensModel",
    "LensEstimates",
    "lens_model",
    "Brown",
    "Ebner12",
    "Gruen44",
    "analyse",
    "ap_set",
    "SelfCalibration",
    "self_calibrate",
    "bundle_solver",
    "clean_block",
    "cleaned_block",
    "ray_labels",
    "RayReliability",
    "ray_reliability",
    "AuxiliaryResult",
    "adjust_with_auxiliary",
    # numerical building blocks (tests, benchmarks, advanced use)
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
    "collinearity_block",
    "normalised_block",
    "project_block",
    "BoundLens",
    "banded_selected_inverse",
    "SOLVERS",
    "ReducedStructure",
    "factor_reduced",
    "geometric_orderings",
    "inv3",
]
