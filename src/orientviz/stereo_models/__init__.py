"""Block adjustment with independent models: the stereo models of a block, joined in 3-D.

"Model" means one thing in orientviz: the stereo model, formed by the relative
orientation of two consecutive images of a strip. This package forms all models of a
block at once (:func:`form_models` → :class:`ModelSet`) and adjusts them by 3-D
similarity transformations (:func:`independent_models`, rigorous or PAT-M, with model
deformation parameters and auxiliary data).

Private parts: ``_formation`` (model formation), ``_setup`` (tie points and datum),
``_adjust`` (the method), ``_joint`` (joint systems with deformation/auxiliary
unknowns), ``_normal`` (sparse reduced systems), ``_deformation`` (deformation sets).
"""

from ._adjust import default_model_sigma, independent_models
from ._deformation import (
    MODEL_SETS,
    TERMS,
    DeformationField,
    ModelDeformation,
    deformation_table,
    model_ap_set,
    similarity_columns,
)
from ._formation import ModelSet, form_models, model_pairs, model_to_object
from ._joint import deformed, joint_setup, model_rows
from ._normal import LinearSolution, scalar_cofactors, solve_rows, solve_sparse
from ._result import DeformationEstimates, ModelsResult
from ._setup import TieSetup, check_datum, tie_setup

__all__ = [
    "independent_models",
    "ModelsResult",
    "DeformationEstimates",
    "ModelSet",
    "form_models",
    "model_to_object",
    "ModelDeformation",
    "DeformationField",
    "MODEL_SETS",
    "TERMS",
    "deformation_table",
    "model_ap_set",
    "similarity_columns",
    # building blocks (tests, benchmarks, the precision laws)
    "TieSetup",
    "tie_setup",
    "check_datum",
    "default_model_sigma",
    "joint_setup",
    "deformed",
    "model_rows",
    "model_pairs",
    "LinearSolution",
    "scalar_cofactors",
    "solve_rows",
    "solve_sparse",
]
