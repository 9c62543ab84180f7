"""The units the viewer names: those of the problem file it shows.

Inside, the viewer works in the block's units (object m, image mm, angles rad). On the
panel and in the scene's labels it speaks the file's language (:class:`ViewUnits`):

* lengths in m (µm … km as they read best), or in *model units* for a reconstruction
  whose scale is arbitrary (a file in ``"length": "model"``: an SfM model imported
  without control), never converted to mm or km there;
* angles in gon (the photogrammetric default) or in degrees when the file gives degrees;
* image quantities in µm, or in pixels when the file's image coordinates are pixels
  (``"image": "px"``: a COLMAP or BAL model, whose millimetres are only the importer's
  nominal pixel size).

Simulated blocks and demos are shown in m, gon and µm (:data:`ViewUnits` defaults).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..units import MODEL_UNIT, length_name

#: Lengths in m as they read best: (unit, metres per unit), largest first.
_METRIC = (("km", 1e3), ("m", 1.0), ("cm", 1e-2), ("mm", 1e-3), ("µm", 1e-6))


@dataclass(frozen=True)
class ViewUnits:
    """How the viewer names lengths, angles and image quantities.

    Attributes
    ----------
    length : {"m", "model"}
        ``"model"``: the block's lengths are a reconstruction's model units (arbitrary
        scale); ``"m"``: metres (every real length unit of a file is shown in m).
    angle : {"gon", "deg"}
        Unit of the angles on the panel (sliders, orientation text).
    pixel_mm : float or None
        mm per pixel when the file's image coordinates are pixels: image quantities are
        then shown in px; None: in µm.
    """

    length: str = "m"
    angle: str = "gon"
    pixel_mm: float | None = None

    @classmethod
    def of(cls, units: Any) -> ViewUnits:
        """The viewer's units of a problem file's ``units`` (:class:`orientviz.io.problem.Units`)."""
        px = float(units.pixel_size) if units.image == "px" and units.pixel_size else None
        return cls(
            length=MODEL_UNIT if units.length == MODEL_UNIT else "m",
            angle="deg" if units.angle == "deg" else "gon",
            pixel_mm=px,
        )

    @property
    def arbitrary_scale(self) -> bool:
        """True for a reconstruction's model units (no metres anywhere)."""
        return self.length == MODEL_UNIT

    @property
    def length_name(self) -> str:
        """``"m"`` or ``"model units"`` (slider labels, orientation text)."""
        return length_name(self.length)

    @property
    def image_name(self) -> str:
        """``"px"`` or ``"µm"``."""
        return "px" if self.pixel_mm else "µm"

    def length_text(self, value: float) -> str:
        """A length (m inside) as the panel writes it: ``"2 cm"``, ``"0.005 model units"``."""
        if self.arbitrary_scale:
            return f"{value:.3g} model units"
        for unit, f in _METRIC:
            if abs(value) >= f:
                return f"{value / f:g} {unit}"
        return f"{value:.3g} m"

    def image_value(self, mm: float) -> float:
        """An image length in mm as a number in :attr:`image_name` (px or µm)."""
        return mm / self.pixel_mm if self.pixel_mm else mm * 1e3

    def image_text(self, mm: float, digits: int = 3) -> str:
        """An image length in mm as the panel writes it: ``"5.06 px"`` or ``"30.7 µm"``."""
        return f"{self.image_value(mm):.{digits}g} {self.image_name}"
