"""Bias of the principal distance: the exact camera model against the old correction form.

The old form estimated a change dc of the principal distance as a correction evaluated
at the *observed* image coordinates, ``Δx = (x_obs − x0)/c · dc`` (the ``dc`` term of
:class:`orientviz.bundle.Brown`). The regressor then carries the observation's noise e,
and E[A(x_obs)ᵀ e] = Σ ∂A/∂x σ² ≠ 0: with n image points the estimate is biased by about

    bias(c) ≈ 2 n σ_c² / c        (σ_c the standard deviation of ĉ, all in mm),

i.e. by 2n·σ_c/c of its own standard deviation — a bias that *grows* with the data (σ_c
falls like 1/√n, so the ratio grows like √n). The exact model
(:class:`orientviz.bundle.LensModel`: c inside the projection) has no such term.
:func:`principal_distance_bias` measures both on simulated calibrations with known
truth (:func:`orientviz.simulate.simulate_calibration`), for growing blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..bundle import LensModel, bundle_adjust
from ._calibration import simulate_calibration

F64 = NDArray[np.float64]

__all__ = ["BiasRow", "principal_distance_bias", "ObservedScale"]


@dataclass
class ObservedScale:
    """The old form of a principal-distance change: one additional parameter ``dc`` (µm)
    with the design (x_obs − x0, y_obs − y0)/c evaluated at the observed coordinates."""

    c: float
    x0: float = 0.0
    y0: float = 0.0
    name: str = "observed-scale"

    @property
    def names(self) -> list[str]:
        return ["dc"]

    def design(self, xy: ArrayLike) -> F64:
        a = np.asarray(xy, dtype=float)
        out = np.empty((a.shape[0], 2, 1))
        out[:, 0, 0] = (a[:, 0] - self.x0) / self.c * 1e-3
        out[:, 1, 0] = (a[:, 1] - self.y0) / self.c * 1e-3
        return out


@dataclass
class BiasRow:
    """One block size: mean estimation errors of c over the repeats, in units of σ_c.

    Attributes
    ----------
    n_images, n_points : int
        Images of the block and image points per repeat (mean).
    redundancy : float
        Mean redundancy.
    sigma_c : float
        Mean σ of ĉ (mm) reported by the exact model.
    exact, old : float
        Mean (ĉ − c) / σ_c of the exact model and of the old form.
    exact_se, old_se : float
        Standard errors of those means (σ units).
    difference, difference_se : float
        Mean (ĉ_old − ĉ_exact) / σ_c and its standard error: both estimates see the same
        noise, so their difference shows the old form's bias with little scatter.
    predicted_old : float
        2 n σ_c / c: the old form's bias in σ units by the formula above.
    """

    n_images: int
    n_points: float
    redundancy: float
    sigma_c: float
    exact: float
    exact_se: float
    old: float
    old_se: float
    predicted_old: float
    difference: float
    difference_se: float


def principal_distance_bias(
    rng: np.random.Generator,
    *,
    n_images: tuple[int, ...] = (6, 12, 24),
    repeats: int = 20,
    sigma_mm: float = 0.003,
    c: float = 7.3,
    grid: int = 7,
) -> list[BiasRow]:
    """Mean error of ĉ with the exact model and with the old form, as the block grows.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness.
    n_images : tuple of int
        Block sizes (images on the cone about the target field).
    repeats : int
        Noise realisations per size.
    sigma_mm : float
        σ of the image coordinates, mm (large noise makes the bias visible in few repeats).
    c : float
        True principal distance, mm (the nominal camera is 0.2 % off).
    grid : int
        Targets per side of the field.
    """
    rows = []
    for m in n_images:
        e_new, e_old, sig, red, npts = [], [], [], [], []
        for _ in range(repeats):
            sim = simulate_calibration(rng, c=c, camera={"c": c * 1.002}, n_images=m,
                                       grid=grid, sigma_mm=sigma_mm)  # fmt: skip
            truth = sim.camera["c"]
            new = bundle_adjust(sim.block, additional=LensModel("backward", free=("c",)))
            value, s = new.camera.get("c")
            old = bundle_adjust(sim.block, additional=ObservedScale(c))
            c_old = c + 1e-3 * float(old.additional[0])
            e_new.append((value - truth) / s)
            e_old.append((c_old - truth) / s)
            sig.append(s)
            red.append(new.redundancy)
            npts.append(sim.block.n_observations)
        e_new, e_old = np.array(e_new), np.array(e_old)
        sc, n = float(np.mean(sig)), float(np.mean(npts))
        se = lambda e: float(e.std(ddof=1) / np.sqrt(repeats))  # noqa: E731
        rows.append(BiasRow(m, n, float(np.mean(red)), sc, float(e_new.mean()), se(e_new),
                            float(e_old.mean()), se(e_old), 2 * n * sc / c,
                            float((e_old - e_new).mean()), se(e_old - e_new)))  # fmt: skip
    return rows
