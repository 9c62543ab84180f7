"""A block design from geometry alone: the flight plan, the control and the σ.

:class:`FlightDesign` holds what a planner decides before the flight (camera, image scale,
overlaps, strips, control layout, the σ of image coordinates, control and GNSS projection
centres). :func:`design_block` turns it into the *design block*: the planned images and
points of :func:`orientviz.simulate.simulate_block` (exact flight plan, no jitter) with
error-free image coordinates, i.e. the block's geometry itself. The bundle's normal
equations formed at this block are the design's normal equations.

Control in a design is always *weighted* (σ > 0): then every point is an unknown and
adding or removing a control point changes the values of the normal equations, not
their structure (:mod:`orientviz.design._live` uses that).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..block import CONTROL, TIE, Auxiliary, Block
from ..errors import InputError
from ..simulate import simulate_auxiliary, simulate_block


@dataclass(frozen=True)
class FlightDesign:
    """What a planner chooses before the flight (all lengths in m unless said).

    Attributes
    ----------
    strips, images_per_strip : int
        Parallel strips along +X and images per strip.
    camera : str or float
        ``"wide"`` (c = 152 mm), ``"superwide"`` (88 mm) or c in mm (format 230 mm).
    scale : float
        Image scale number m_B; flying height H = c · m_B.
    forward_overlap, side_overlap : float
        Overlaps as fractions.
    relief : float
        Peak-to-peak terrain relief as a fraction of H (0 = flat).
    control : {"perimeter", "chains", "full", "corners", "none"}
        Control layout of :func:`orientviz.simulate.simulate_block`.
    control_spacing, chain_spacing : int
        Perimeter spacing and height-chain spacing in bases.
    control_kind : {"xyz", "xy+z"}
        Full control everywhere, or XY on the perimeter and Z in the chains.
    sigma_image_mm : float
        σ of an image coordinate, mm.
    sigma_control : float
        σ of a given control coordinate, m (> 0: control is weighted).
    sigma_gnss : float or None
        σ of GNSS-observed projection centres (X0, Y0, Z0), m, absolute (no offsets);
        None = no GNSS.
    gnss_offsets : bool
        GNSS positions with an unknown shift per strip (X, Y, Z; as the bundle's joint
        auxiliary data, :func:`design_auxiliary`) instead of absolute ones.
    sigma_statoscope, sigma_apr : float or None
        σ (m) of statoscope readings of every projection centre's height and of APR
        terrain heights (the tie point nearest each image's nadir), each with an unknown
        offset per strip (:func:`design_auxiliary`); None = none.
    extra : {"grid"} or int or None
        Tie points besides the standard (Gruber) ones (see ``simulate_block``).
    terrain_seed : int
        Seed of the terrain's hills (relief > 0); the design itself is deterministic.
    """

    strips: int = 3
    images_per_strip: int = 8
    camera: str | float = "wide"
    scale: float = 10_000.0
    forward_overlap: float = 0.6
    side_overlap: float = 0.2
    relief: float = 0.0
    control: str = "perimeter"
    control_spacing: int = 4
    chain_spacing: int = 4
    control_kind: str = "xyz"
    sigma_image_mm: float = 0.005
    sigma_control: float = 0.02
    sigma_gnss: float | None = None
    gnss_offsets: bool = False
    sigma_statoscope: float | None = None
    sigma_apr: float | None = None
    extra: str | int | None = None
    terrain_seed: int = 0
    options: dict[str, Any] = field(default_factory=dict, compare=False)

    def with_(self, **changes: Any) -> FlightDesign:
        """A copy with some choices changed."""
        return replace(self, **changes)


def design_block(design: FlightDesign) -> tuple[Block, dict[str, Any]]:
    """The design block of a flight design: planned geometry, error-free observations.

    Parameters
    ----------
    design : FlightDesign

    Returns
    -------
    block : Block
        True (planned) orientations and points; image coordinates without errors with
        σ = ``sigma_image_mm`` (mm); control points with their true coordinates given with
        σ = ``sigma_control`` (m); with ``sigma_gnss`` the projection centres observed
        (``images.X0_obs``, ``X0_sigma``, m).
    spec : dict
        The simulator's geometry (``flying_height_m``, ``base_m``, ``strip_spacing_m``,
        ``grid_rows``, ``grid_cols`` …).

    Raises
    ------
    InputError
        For σ ≤ 0 or impossible geometry.
    """
    if not design.sigma_image_mm > 0:
        raise InputError(f"sigma_image_mm: expected σ > 0 mm, got {design.sigma_image_mm}")
    if not design.sigma_control > 0:
        raise InputError(
            f"sigma_control: a design weights its control, expected σ > 0 m, got "
            f"{design.sigma_control}"
        )
    if design.sigma_gnss is not None and not design.sigma_gnss > 0:
        raise InputError(f"sigma_gnss: expected σ > 0 m or None, got {design.sigma_gnss}")
    truth, spec = _planned(design)
    block = truth.copy()
    # the σ of the plan: the same geometry for every σ (only these fields depend on them)
    block.observations.sigma[:] = design.sigma_image_mm
    given = np.isfinite(block.points.sigma)
    block.points.sigma[given] = design.sigma_control
    spec.update(sigma_image_mm=design.sigma_image_mm, control_sigma=design.sigma_control)
    block.meta = {"source": "orientviz.design.design_block"}
    if design.sigma_gnss is not None and not design.gnss_offsets:
        block.images.X0_obs[:] = block.images.X0
        block.images.X0_sigma[:] = design.sigma_gnss
    return block, spec


#: The planned blocks of the last few layouts (the studio changes a σ of the plan often).
_PLANNED: dict[str, tuple[Block, dict[str, Any]]] = {}
_PLANNED_KEEP: int = 4


def _planned(design: FlightDesign) -> tuple[Block, dict[str, Any]]:
    """The simulator's planned block of a design's layout (kept for the last
    :data:`_PLANNED_KEEP` layouts: everything but the σ of image coordinates and control)
    and its geometry; the block is not to be changed (copy it)."""
    key = repr(
        (design.strips, design.images_per_strip, design.camera, design.scale,
         design.forward_overlap, design.side_overlap, design.relief, design.control,
         design.control_spacing, design.chain_spacing, design.control_kind, design.extra,
         design.terrain_seed, sorted(design.options.items()))
    )  # fmt: skip
    if key not in _PLANNED:
        sim = simulate_block(
            design.strips, design.images_per_strip,
            rng=np.random.default_rng(design.terrain_seed), camera=design.camera,
            scale=design.scale, forward_overlap=design.forward_overlap,
            side_overlap=design.side_overlap, relief=design.relief, extra=design.extra,
            control=design.control, control_spacing=design.control_spacing,
            chain_spacing=design.chain_spacing, control_kind=design.control_kind,
            control_sigma=design.sigma_control, sigma_image_mm=design.sigma_image_mm,
            start_error=None, flight_jitter=(0.0, 0.0, 0.0, 0.0), **design.options,
        )  # fmt: skip
        while len(_PLANNED) >= _PLANNED_KEEP:
            _PLANNED.pop(next(iter(_PLANNED)))
        _PLANNED[key] = (sim.truth, dict(sim.spec))
    truth, spec = _PLANNED[key]
    return truth, dict(spec)


def set_control(block: Block, point: int, sigma_xyz) -> Block:
    """A copy of ``block`` with point ``point`` made control (or tie) in place.

    Parameters
    ----------
    block : Block
        A design block (true coordinates in ``points.xyz``).
    point : int
        Point index.
    sigma_xyz : array_like, shape (3,)
        σ of the given X, Y, Z in m; NaN = that coordinate not given. All NaN makes the
        point a tie point.
    """
    b = block.copy()
    s = np.asarray(sigma_xyz, float).reshape(3)
    given = np.isfinite(s)
    if np.any(s[given] <= 0):
        raise InputError(f"sigma_xyz: a design weights its control, expected σ > 0, got {s}")
    P = b.points
    P.sigma[point] = np.where(given, s, np.nan)
    P.xyz_known[point] = np.where(given, P.xyz[point], np.nan)
    P.role[point] = CONTROL if given.any() else TIE
    return b


def design_auxiliary(block: Block, design: FlightDesign) -> list[Auxiliary]:
    """The plan's auxiliary data of a design block: error-free values (the planned
    positions and heights), σ from the plan, an unknown offset per strip (GNSS with
    ``gnss_offsets``, statoscope and APR).

    Parameters
    ----------
    block : Block
        The design block (planned geometry).
    design : FlightDesign
        ``sigma_gnss`` with ``gnss_offsets``, ``sigma_statoscope``, ``sigma_apr`` (m; None =
        none).

    Returns
    -------
    list of Auxiliary
        For :func:`orientviz.bundle.bundle_adjust`'s ``auxiliary`` (empty: none).
    """
    out = []
    holder = SimpleNamespace(truth=block)
    gnss = design.sigma_gnss if design.gnss_offsets else None
    for kind, sig in (
        ("gnss", gnss), ("statoscope", design.sigma_statoscope), ("apr", design.sigma_apr),
    ):  # fmt: skip
        if sig is None:
            continue
        if not sig > 0:
            raise InputError(f"sigma_{kind}: expected σ > 0 m or None, got {sig}")
        a = simulate_auxiliary(
            holder, kind, rng=np.random.default_rng(0), sigma=sig, offset_sigma=0.0
        )
        if kind == "gnss":
            a.values = block.images.X0[a.index].copy()  # the planned positions: no errors
        elif kind == "statoscope":
            a.values = block.images.X0[a.index, 2].copy()
        else:
            a.values = block.points.xyz[a.index, 2].copy()
        a.truth = {}
        out.append(a)
    return out
