"""Simulated blocks and what is studied with them (not solvers).

* :func:`simulate_block` → :class:`SimulatedBlock` (flight plan, :class:`Terrain`,
  control layouts, noise, gross and systematic errors);
* :mod:`orientviz.simulate.systematic`: image error models (a public module of
  callables ``(xy_mm, image) -> Δxy_mm``);
* deformation fields of systematic errors: :func:`image_field`, :func:`model_field`,
  :func:`model_fields`, :func:`split_field`, :func:`animate`, :func:`frames`;
* accuracy laws of blocks: :func:`planimetric_precision`, :func:`height_precision` →
  :class:`BlockPrecision`, :func:`fit_log_law`;
* a camera calibration on a target field with a known lens: :func:`simulate_calibration`
  → :class:`SimulatedCalibration`;
* auxiliary data and check-point errors: :func:`simulate_auxiliary`,
  :func:`height_control_at_ends`, :func:`check_differences`, :func:`check_errors`.
"""

from . import systematic
from ._accuracy import BlockPrecision, fit_log_law, height_precision, planimetric_precision
from ._auxiliary import check_differences, check_errors, height_control_at_ends, simulate_auxiliary
from ._block import CAMERAS, SimulatedBlock, simulate_block
from ._calibration import SimulatedCalibration, simulate_calibration
from ._deformation import (
    FieldSplit,
    ImageField,
    ModelField,
    animate,
    frames,
    image_field,
    model_field,
    model_fields,
    split_field,
)
from ._terrain import Terrain

__all__ = [
    "CAMERAS",
    "SimulatedBlock",
    "simulate_block",
    "SimulatedCalibration",
    "simulate_calibration",
    "Terrain",
    "systematic",
    "FieldSplit",
    "ImageField",
    "ModelField",
    "animate",
    "frames",
    "image_field",
    "model_field",
    "model_fields",
    "split_field",
    "BlockPrecision",
    "fit_log_law",
    "height_precision",
    "planimetric_precision",
    "check_differences",
    "check_errors",
    "height_control_at_ends",
    "simulate_auxiliary",
]
