"""The bundle block adjustment: all image bundles of a block at once (collinearity).

The face of the bundle's house. What a user calls:

* :func:`bundle_adjust` — the adjustment (Schur complement on the reduced camera
  system, self-calibration, auxiliary data, exact precision), its knobs one value:
  :class:`BundleOptions` (with :class:`ReducedOptions`);
* self-calibration: :func:`ap_set` (:class:`Ebner12`, :class:`Brown`, :class:`Gruen44`,
  the :class:`AdditionalParameters` protocol), :func:`analyse` → :class:`APAnalysis`,
  :func:`self_calibrate` → :class:`SelfCalibration`; the camera itself (c, principal
  point, affinity, shear, radial and decentring distortion, backward or forward) inside
  the projection: :class:`LensModel` → ``result.camera`` (:class:`LensEstimates`); a
  block's own camera models (``block.cameras.model``, as a problem file or an import
  states them) as :func:`bundle_adjust`'s keywords: :func:`block_camera_options`;
* gross errors: :func:`clean_block`, :func:`bundle_solver`, :func:`cleaned_block`,
  :func:`ray_labels`; reliability per ray: :func:`ray_reliability` →
  :class:`RayReliability`;
* auxiliary data by alternation (teaching): :func:`adjust_with_auxiliary`.

Start reading at :mod:`orientviz.bundle.reference`: the textbook Gauss-Newton iteration
(``solver="reference"``); every fast path is tested against it.

The rooms behind it (each a sub-package with its own door):

* ``model`` — the photogrammetric model: collinearity and its derivatives, rotations of
  the image frames, the camera (lens) model, additional-parameter sets;
* ``problem`` — the bundle problem: checks, typed parts, the iterate, one Gauss-Newton
  step (normal equations, border of additional parameters and auxiliary data);
* ``reduced`` — the reduced camera system: form → factor → solve → back-substitute,
  the choice of solver inside (banded, dense, sparse);
* ``loop`` — :func:`bundle_adjust`: the iterations over the problem's steps and the
  result;
* ``precision`` — cofactor blocks, redundancy numbers, reliability per ray.

Beside them: ``reference`` with ``_reference_data`` (the textbook iteration), ``_result``
(the typed result), ``_options`` (:class:`BundleOptions`), ``_block_cameras`` (the block's camera models), ``_selfcal``, ``_cleaning``,
``_alternation`` (procedures built on :func:`bundle_adjust`) and ``sparsity`` (the
sparsity of the normal equations drawn for the lessons). ``__all__`` is the public face;
the numerical building blocks are reached through the rooms' doors
(``orientviz.bundle.problem``, ``orientviz.bundle.reduced``, ``orientviz.bundle.model``,
``orientviz.bundle.precision``, ``orientviz.bundle.loop``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..faces import lazy_names

__all__ = [
    # the adjustment, its options and its result
    "bundle_adjust",
    "BundleOptions",
    "ReducedOptions",
    "BundleResult",
    "RayGains",
    "ExteriorPairs",
    # self-calibration and the camera
    "AdditionalParameters",
    "APAnalysis",
    "LensModel",
    "LensEstimates",
    "block_camera_options",
    "lens_model",
    "Brown",
    "Ebner12",
    "Gruen44",
    "analyse",
    "ap_set",
    "SelfCalibration",
    "self_calibrate",
    # gross errors and reliability
    "bundle_solver",
    "clean_block",
    "cleaned_block",
    "ray_labels",
    "RayReliability",
    "ray_reliability",
    # auxiliary data by alternation
    "AuxiliaryResult",
    "adjust_with_auxiliary",
]

#: Public name → the module holding it; each loads on first use, so a solve imports
#: neither self-calibration, cleaning nor the alternation (nor their dependencies).
_FACE = {
    "AuxiliaryResult": "._alternation",
    "adjust_with_auxiliary": "._alternation",
    "block_camera_options": "._block_cameras",
    "bundle_solver": "._cleaning",
    "clean_block": "._cleaning",
    "cleaned_block": "._cleaning",
    "ray_labels": "._cleaning",
    "BundleOptions": "._options",
    "BundleResult": "._result",
    "ExteriorPairs": "._result",
    "RayGains": "._result",
    "SelfCalibration": "._selfcal",
    "self_calibrate": "._selfcal",
    "bundle_adjust": ".loop",
    "AdditionalParameters": ".model",
    "APAnalysis": ".model",
    "Brown": ".model",
    "Ebner12": ".model",
    "Gruen44": ".model",
    "LensEstimates": ".model",
    "LensModel": ".model",
    "analyse": ".model",
    "ap_set": ".model",
    "lens_model": ".model",
    "RayReliability": ".precision",
    "ray_reliability": ".precision",
    "ReducedOptions": ".reduced",
}

__getattr__ = lazy_names(__name__, _FACE, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ._alternation import AuxiliaryResult, adjust_with_auxiliary
    from ._block_cameras import block_camera_options
    from ._cleaning import bundle_solver, clean_block, cleaned_block, ray_labels
    from ._options import BundleOptions
    from ._result import BundleResult, ExteriorPairs, RayGains
    from ._selfcal import SelfCalibration, self_calibrate
    from .loop import bundle_adjust
    from .model import (
        AdditionalParameters,
        APAnalysis,
        Brown,
        Ebner12,
        Gruen44,
        LensEstimates,
        LensModel,
        analyse,
        ap_set,
        lens_model,
    )
    from .precision import RayReliability, ray_reliability
    from .reduced import ReducedOptions
