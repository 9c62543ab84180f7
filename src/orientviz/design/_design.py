"""Design without measurements: the bundle's normal equations of a planned block.

:func:`assess_design` forms the normal equations of the bundle adjustment at the design
block (:func:`orientviz.design.design_block`: the planned geometry, error-free image
coordinates) by running :func:`orientviz.bundle.bundle_adjust` on it. The observations
agree with the geometry, so the first Gauss-Newton step is zero and the result's
precision (a-priori σ0 = 1: weights 1/σ² of image coordinates, control and GNSS) is the
design's: covariances of points and orientations, redundancy numbers, the rays' gains,
and from them the reliability (:func:`orientviz.bundle.ray_reliability`). No random
number enters.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..blas import blas_threads
from ..block import Block
from ..bundle import BundleResult, bundle_adjust, ray_reliability
from ..simulate import height_precision, planimetric_precision
from ._layout import FlightDesign, design_auxiliary, design_block
from ._quality import DesignQuality, quality_from_arrays


@dataclass
class DesignAssessment:
    """A design, its block and what the bundle predicts for it.

    Attributes
    ----------
    design : FlightDesign or None
        The plan (None when assessed from a block).
    block : Block
        The design block (planned geometry, error-free observations).
    spec : dict
        Geometry of the plan (``flying_height_m``, ``base_m``, ``strip_spacing_m`` …).
    result : BundleResult
        The bundle's result at the design block (its precision fields are the design's).
    quality : DesignQuality
        σ, ellipsoids, redundancy, MDB, external reliability, weak spots, summary.
    law : dict
        Ebner's accuracy laws for the same layout (:func:`accuracy_law`).
    """

    design: FlightDesign | None
    block: Block
    spec: dict[str, Any]
    result: BundleResult
    quality: DesignQuality
    law: dict[str, Any]


def assess_block(
    block: Block, spec: dict[str, Any], *, level: float = 0.95, alpha0: float = 0.001,
    beta0: float = 0.80, solver: str = "auto", auxiliary: list | None = None,
) -> tuple[BundleResult, DesignQuality]:  # fmt: skip
    """Precision and reliability of a design block (error-free observations).

    Parameters
    ----------
    block : Block
        Planned geometry; control weighted (``points.sigma`` > 0, m); image σ in
        ``observations.sigma`` (mm).
    spec : dict
        Needs ``base_m`` (the air base in m, for the weak spots' distances).
    level : float
        Probability of the confidence ellipsoids.
    alpha0, beta0 : float
        Test level and power of the reliability (δ0 = 4.13 for 0.1 %, 80 %).
    solver : str
        The bundle's solver of the reduced system.
    auxiliary : list of Auxiliary, optional
        Statoscope / APR / GNSS data of the design (:func:`orientviz.design.design_auxiliary`),
        adjusted jointly with their strip offsets.

    Returns
    -------
    result : BundleResult
    quality : DesignQuality
    """
    res = bundle_adjust(
        block, control="weighted", precision=True, max_iter=3, solver=solver,
        auxiliary=auxiliary or None,
    )  # fmt: skip
    rel = ray_reliability(res, block, alpha0=alpha0, beta0=beta0)
    n = block.n_observations
    red = np.asarray(res.redundancy_numbers[: 2 * n]).reshape(n, 2)
    q = quality_from_arrays(
        block, res.cofactor_groups["points"], res.cofactor_groups["exterior"], red, rel,
        float(spec["base_m"]), level,
    )  # fmt: skip
    return res, q


@functools.lru_cache(maxsize=64)
def _mu_xy(strips: int, models_per_strip: int, control_spacing: int) -> float:
    """μ_xy/σ0 of Ebner's planimetric law for a layout (kept per layout: it depends on
    nothing else; BLAS on one thread, as the designs' other work)."""
    with blas_threads(1):
        return planimetric_precision(
            strips, models_per_strip=models_per_strip, control_spacing=control_spacing
        ).mu


@functools.lru_cache(maxsize=64)
def _mu_z(chain_spacing: int, strips: int, models_per_strip: int) -> float:
    """μ_z/σ0z of Ebner's height law for a layout (kept per layout; BLAS on one thread)."""
    with blas_threads(1):
        return height_precision(
            chain_spacing, n_strips=strips, models_per_strip=models_per_strip
        ).mu


def accuracy_law(design: FlightDesign, spec: dict[str, Any]) -> dict[str, Any]:
    """Ebner's accuracy laws (independent models) for the design's layout, in m.

    The laws give μ = σ/σ0 for σ0 the σ of a model coordinate, the unit weight of the
    independent-model adjustment they model: in planimetry σ0 = σ_image · m_B (the image σ
    at ground scale), in height σ0z = √2 · σ_image · m_B · H/B, the σ of a model height
    from the x-parallax of two image coordinates (the normal case: σ_Z = √2 · H/B · m_B ·
    σ_x). Both are the σ of the model coordinates that
    :func:`orientviz.stereo_models.independent_models` weights by default. Planimetry:
    perimeter control every ``control_spacing`` bases
    (:func:`orientviz.simulate.planimetric_precision`); height: chains every
    ``chain_spacing`` bases (:func:`orientviz.simulate.height_precision`). Other layouts
    have no law: NaN with a reason.

    The height law weights every coordinate of its height block alike, also the
    projection centres' X, Y (which hold the tilts between models); the designs weight the
    centres' planimetry with σ0 (√2 · H/B times better than a model height), so the law is
    pessimistic against them, the more so the wider the chains (benchmarks/README.md, "the
    σ0 of Ebner's laws").

    Returns
    -------
    dict
        ``sigma_xy`` and ``sigma_z`` (RMS σ of the non-control points, m, or NaN),
        ``note`` (what the numbers are).
    """
    s0 = design.sigma_image_mm * 1e-3 * design.scale
    s0z = np.sqrt(2.0) * s0 * spec["flying_height_m"] / spec["base_m"]
    out: dict[str, Any] = {"sigma_xy": float("nan"), "sigma_z": float("nan")}
    notes = []
    if design.control in ("perimeter", "chains"):
        mu = _mu_xy(design.strips, design.images_per_strip - 1, design.control_spacing)
        out["sigma_xy"] = mu * s0
        notes.append(
            f"μ_xy = {mu:.2f} σ0, σ0 = σ·m_B = {s0 * 1e3:.0f} mm (perimeter every "
            f"{design.control_spacing} bases)"
        )
    else:
        notes.append(f"no planimetric law for control {design.control!r}")
    if design.control == "chains":
        mu = _mu_z(design.chain_spacing, design.strips, design.images_per_strip - 1)
        out["sigma_z"] = mu * s0z
        notes.append(
            f"μ_z = {mu:.2f} σ0z, σ0z = √2·σ·m_B·H/B = {s0z * 1e3:.0f} mm (chains every "
            f"{design.chain_spacing} bases; the law weights the projection centres like model "
            "heights, the designs better: the law is the more pessimistic the wider the chains)"
        )
    else:
        notes.append("height law needs control='chains'")
    out["sigma0_xy"], out["sigma0_z"] = s0, s0z
    out["note"] = "Ebner, independent models: " + "; ".join(notes)
    return out


def assess_design(
    design: FlightDesign, *, level: float = 0.95, law: bool = True, solver: str = "auto"
) -> DesignAssessment:
    """Design without measurements: the predicted quality of a planned block.

    Parameters
    ----------
    design : FlightDesign
        Camera, image scale, overlaps, strips, control layout with σ (m), GNSS,
        statoscope and APR σ (m), image σ (mm).
    level : float
        Probability of the confidence ellipsoids.
    law : bool
        Also compute Ebner's accuracy laws for the layout (:func:`accuracy_law`).
    solver : str
        Solver of the bundle's reduced system.

    Returns
    -------
    DesignAssessment
        ``quality.point_sigma`` (p, 3) m, ``quality.station_sigma`` (m, 6) m/rad,
        ellipsoids, redundancy numbers, MDB (mm), δ̄0, weak spots in words, summary.

    Examples
    --------
    >>> from orientviz.design import FlightDesign, assess_design
    >>> a = assess_design(FlightDesign(strips=2, images_per_strip=5), law=False)
    >>> a.quality.point_sigma.shape[1]
    3
    """
    block, spec = design_block(design)
    aux = design_auxiliary(block, design)
    res, q = assess_block(block, spec, level=level, solver=solver, auxiliary=aux)
    lw = accuracy_law(design, spec) if law else {}
    return DesignAssessment(design, block, spec, res, q, lw)
