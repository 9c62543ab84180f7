"""Design a block before flying it: predicted precision and reliability from geometry.

* :class:`FlightDesign` — the plan (camera, scale, overlaps, strips, control with σ,
  GNSS σ, image σ); :func:`design_block` → the design block (planned geometry,
  error-free observations); :func:`set_control` makes a point control or tie;
* :func:`assess_design` / :func:`assess_block` → :class:`DesignAssessment`,
  :class:`DesignQuality`: σ of every point and station, confidence ellipsoids,
  redundancy numbers, MDB, external reliability, weak spots in words, and Ebner's
  accuracy laws for the same layout (:func:`accuracy_law`);
* :class:`LiveDesign` — one change (a control point added, removed, its σ changed;
  images added or removed) updates the quality by a low-rank formula on the design's
  factorised normal equations, without forming them again; :func:`check_structure` —
  the determinability checks it makes of a changed block;
* :func:`suggest_control` — the next control point that most reduces the worst σ;
* :func:`cross_strip` (:func:`cross_strip_images`), :func:`add_images`,
  :func:`remove_images` — structural edits of a design block; :func:`design_from_block` — a design with the geometry of any block;
* :func:`assess_models` — the design's precision for independent models
  (:data:`METHODS`: the polynomial adjustment has none); :class:`LiveModels` — the same,
  factorised once per structure and updated per control change.

The package sits above :mod:`orientviz.bundle` and :mod:`orientviz.simulate` and uses
their machinery: the normal equations, the precision and reliability are the bundle's.
"""

from ._design import DesignAssessment, accuracy_law, assess_block, assess_design
from ._extend import (
    add_images,
    cross_strip,
    cross_strip_images,
    design_from_block,
    remove_images,
)
from ._layout import FlightDesign, design_auxiliary, design_block, set_control
from ._live import Change, LiveDesign
from ._live_parts import check_structure
from ._methods import METHODS, assess_models
from ._models_live import LiveModels
from ._quality import DesignQuality, ellipsoids
from ._suggest import Suggestion, suggest_control

__all__ = [
    "FlightDesign",
    "design_block",
    "design_auxiliary",
    "set_control",
    "DesignAssessment",
    "DesignQuality",
    "accuracy_law",
    "assess_block",
    "assess_design",
    "ellipsoids",
    "add_images",
    "cross_strip",
    "cross_strip_images",
    "design_from_block",
    "remove_images",
    "METHODS",
    "assess_models",
    "LiveModels",
    "Change",
    "LiveDesign",
    "check_structure",
    "Suggestion",
    "suggest_control",
]
