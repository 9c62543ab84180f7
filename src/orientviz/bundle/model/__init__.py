"""The photogrammetric model of the bundle: collinearity, rotations, the camera.

* :mod:`._kernel` — collinearity for all rays at once: image coordinates
  (:func:`project_block`), normalised coordinates (:func:`normalised_block`) and their
  Jacobians by the exterior orientation and the points (:func:`collinearity_block`,
  :class:`RayProjection` + :func:`ray_jacobians`);
* :mod:`._local_rotation` — steps as rotations of the image frames and the map between
  them and steps in ω, φ, κ (:func:`apply_local`, :func:`angle_map`);
* :mod:`._lens` — the camera inside the projection (:class:`LensModel`: c, principal
  point, affinity, shear, radial and decentring distortion, backward or forward; the
  parameter names :data:`BACKWARD_NAMES`, :data:`FORWARD_NAMES` and the rays' lens terms
  :func:`evaluate_lens`); :mod:`._lens_rays` evaluates it on a block's rays with only the
  terms that act and the estimated parameters' derivatives (what the bundle calls);
* :mod:`._additional` — additional-parameter sets of self-calibration
  (:class:`Ebner12`, :class:`Brown`, :class:`Gruen44`, :func:`ap_set`, :func:`analyse`)
  and the six image deformations of the exterior orientation (:func:`eo_deformations`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...faces import lazy_names
from ._kernel import (
    RayProjection,
    collinearity_block,
    normalised_block,
    project_block,
    ray_jacobians,
)
from ._lens import (
    BACKWARD_NAMES,
    FORWARD_NAMES,
    BoundLens,
    LensEstimates,
    LensModel,
    evaluate_lens,
    lens_model,
)
from ._local_rotation import angle_map, apply_local, frame_axials

__all__ = [
    "AdditionalParameters",
    "APAnalysis",
    "Brown",
    "Ebner12",
    "Gruen44",
    "analyse",
    "ap_set",
    "eo_deformations",
    "RayProjection",
    "collinearity_block",
    "normalised_block",
    "project_block",
    "ray_jacobians",
    "BoundLens",
    "LensEstimates",
    "LensModel",
    "lens_model",
    "evaluate_lens",
    "BACKWARD_NAMES",
    "FORWARD_NAMES",
    "angle_map",
    "apply_local",
    "frame_axials",
]

#: Names loaded on first use: a bundle without additional-parameter sets never loads them.
_LAZY = {
    "AdditionalParameters": "._additional",
    "APAnalysis": "._additional",
    "Brown": "._additional",
    "Ebner12": "._additional",
    "Gruen44": "._additional",
    "analyse": "._additional",
    "ap_set": "._additional",
    "eo_deformations": "._additional",
}

__getattr__ = lazy_names(__name__, _LAZY, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ._additional import (
        AdditionalParameters,
        APAnalysis,
        Brown,
        Ebner12,
        Gruen44,
        analyse,
        ap_set,
        eo_deformations,
    )
