"""What :func:`orientviz.stereo_models.independent_models` returns: a typed result."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import BlockAdjustment

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass(frozen=True)
class DeformationEstimates:
    """Model deformation parameters estimated with the block (self-calibration of models).

    Attributes
    ----------
    values : ndarray, shape (groups, k)
        The parameters, mm at a model corner.
    sigma : ndarray, shape (groups, k)
        Their standard deviations (a posteriori), mm.
    analysis : APAnalysis
        t-tests, correlations, undetermined parameters
        (:class:`orientviz.bundle.APAnalysis`).
    groups : ndarray of int, shape (models,)
        Group of each model.
    set : ModelDeformation
        The deformation set (terms and their fields).
    """

    values: F64
    sigma: F64
    analysis: Any
    groups: I64
    set: Any


@dataclass
class ModelsResult(BlockAdjustment):
    """The result of a block adjustment with independent models.

    Besides :class:`~orientviz.block.BlockAdjustment` (``points`` (p, 3): all block
    points, check points from their model coordinates, NaN if in no model;
    ``check_points``; ``auxiliary``; ``exterior`` is None: models carry no image
    orientation):

    Attributes
    ----------
    method : str
        ``"rigorous"`` or ``"pat-m"``.
    models : ModelSet
        The stereo models that were joined.
    centres : ndarray, shape (m, 3)
        Projection centres of the images (m, from their models; NaN if in none).
    point_index : ndarray of int
        Block index of each point unknown (the order of the ``"points"`` block of x).
    centre_image : ndarray of int
        Image of each projection centre among the point unknowns.
    sigma0_planimetry, sigma0_height : float
        σ̂0 of the planimetric and the height residuals separately.
    sigma0_m : float
        σ̂0 in m of model coordinates.
    rms_xy_m, rms_z_m : float
        RMS model residuals in planimetry and height, m.
    sigma_model : tuple of float
        A-priori σ of model coordinates (planimetry, height), m.
    deformation : DeformationEstimates or None
        Estimated model deformation (None without).
    """

    method: str = "rigorous"
    models: Any = None
    centres: F64 | None = None
    point_index: I64 | None = None
    centre_image: I64 | None = None
    sigma0_planimetry: float = math.nan
    sigma0_height: float = math.nan
    sigma0_m: float = math.nan
    rms_xy_m: float = math.nan
    rms_z_m: float = math.nan
    sigma_model: tuple[float, float] = (math.nan, math.nan)
    deformation: DeformationEstimates | None = None
