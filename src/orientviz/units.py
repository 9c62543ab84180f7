"""Angle units and their conversion factors (ρ).

The papers behind orientviz count angles in the centesimal system: a full circle is
400 gon, 1 gon = 100 c (centesimal minutes) = 10 000 cc (centesimal seconds).
Inside orientviz every angle is in **radians**; the other units appear only at the
edges (problem files, reports, sliders). Conversion is always explicit::

    >>> from orientviz.units import to_rad, from_rad
    >>> round(from_rad(to_rad(100.0, "gon"), "deg"), 12)
    90.0

The ρ constants are the number of units per radian, as in the classical formula
``dα[unit] = ρ[unit] · dα[rad]``; Kovarik writes ρ^c = 6366.2 c/rad.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

AngleUnit = Literal["rad", "deg", "gon", "c", "cc"]

#: Units accepted wherever an angle unit is named.
ANGLE_UNITS: tuple[str, ...] = ("rad", "deg", "gon", "c", "cc")

#: Degrees per radian.
RHO_DEG: float = 180.0 / math.pi
#: Gon (grad) per radian, ρ^g ≈ 63.662 gon.
RHO_GON: float = 200.0 / math.pi
#: Centesimal minutes per radian, ρ^c ≈ 6366.2 c.
RHO_C: float = 20_000.0 / math.pi
#: Centesimal seconds per radian, ρ^cc ≈ 636 620 cc.
RHO_CC: float = 2_000_000.0 / math.pi

#: Units per radian, by unit name.
RHO: dict[str, float] = {"rad": 1.0, "deg": RHO_DEG, "gon": RHO_GON, "c": RHO_C, "cc": RHO_CC}

Number = float | NDArray[np.floating]


def check_angle_unit(unit: str) -> str:
    """Return ``unit`` if it is a known angle unit, else raise ``ValueError``.

    Parameters
    ----------
    unit : str
        One of ``"rad"``, ``"deg"``, ``"gon"``, ``"c"``, ``"cc"``.
    """
    if unit not in RHO:
        raise ValueError(f"expected an angle unit out of {', '.join(ANGLE_UNITS)}, got {unit!r}")
    return unit


def to_rad(value: ArrayLike, unit: str = "gon") -> Number:
    """Convert an angle from ``unit`` to radians.

    Parameters
    ----------
    value : float or array_like
        Angle(s) in ``unit``.
    unit : {"rad", "deg", "gon", "c", "cc"}, default "gon"
        Unit of ``value``.

    Returns
    -------
    float or ndarray
        Angle(s) in radians.
    """
    rho = RHO[check_angle_unit(unit)]
    if np.isscalar(value):
        return float(value) / rho  # type: ignore[arg-type]
    return np.asarray(value, dtype=float) / rho


def from_rad(value: ArrayLike, unit: str = "gon") -> Number:
    """Convert an angle from radians to ``unit``.

    Parameters
    ----------
    value : float or array_like
        Angle(s) in radians.
    unit : {"rad", "deg", "gon", "c", "cc"}, default "gon"
        Target unit.

    Returns
    -------
    float or ndarray
        Angle(s) in ``unit``.
    """
    rho = RHO[check_angle_unit(unit)]
    if np.isscalar(value):
        return float(value) * rho  # type: ignore[arg-type]
    return np.asarray(value, dtype=float) * rho


def convert_angle(value: ArrayLike, from_unit: str, to_unit: str) -> Number:
    """Convert an angle between two units (e.g. gon → c: × 100).

    Parameters
    ----------
    value : float or array_like
        Angle(s) in ``from_unit``.
    from_unit, to_unit : {"rad", "deg", "gon", "c", "cc"}
        Source and target units.
    """
    return from_rad(to_rad(value, from_unit), to_unit)


def wrap_angle(value: ArrayLike) -> Number:
    """Wrap an angle in radians into the half-open interval [−π, π)."""
    wrapped = (np.asarray(value, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi
    return float(wrapped) if np.ndim(wrapped) == 0 else wrapped


def format_angle(value_rad: float, unit: str = "gon", digits: int | None = None) -> str:
    """Format an angle given in radians for a report, e.g. ``"12.3456 gon"``.

    Parameters
    ----------
    value_rad : float
        Angle in radians.
    unit : {"rad", "deg", "gon", "c", "cc"}, default "gon"
        Unit to print in.
    digits : int, optional
        Decimals; by default 4 for gon/deg, 2 for c, 1 for cc and 6 for rad
        (about 0.1 cc resolution where the unit allows).
    """
    default_digits = {"rad": 6, "deg": 4, "gon": 4, "c": 2, "cc": 1}
    d = default_digits[check_angle_unit(unit)] if digits is None else digits
    symbol = {"rad": "rad", "deg": "°", "gon": "gon", "c": "c", "cc": "cc"}[unit]
    sep = "" if unit == "deg" else " "
    return f"{from_rad(value_rad, unit):.{d}f}{sep}{symbol}"


#: Micrometres per millimetre (image residuals are usually reported in µm).
UM_PER_MM: float = 1000.0

#: The length unit of a model whose scale is arbitrary (a reconstruction from images
#: alone, without control: COLMAP, BAL): its lengths are numbers in the model's own unit,
#: read 1 : 1 where metres are expected, but never named metres.
MODEL_UNIT: str = "model"


def length_name(unit: str) -> str:
    """How a text names the length unit ``unit`` (a problem file's ``units.length``):
    ``"model units"`` for :data:`MODEL_UNIT`, else the unit itself (``"m"``, ``"ft"``, …)."""
    return "model units" if unit == MODEL_UNIT else unit
