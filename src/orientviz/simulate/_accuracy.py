"""Theoretical precision of blocks adjusted by independent models (Ebner's laws).

Ackermann (1974, §17-19, Bild 3 and 4 after H. Ebner) summarises the theory of block
accuracy under purely random, uncorrelated errors of the model coordinates:

* **Planimetry** (Bild 3): with control points along the block perimeter the mean
  planimetric standard deviation μ_xy (μ_x ≈ μ_y) of a square block grows only
  *logarithmically* with the number of strips n_s, and stays below 2 σ0 even for very
  large blocks.
* **Height** (Bild 4): with chains of height control across the strips every i bases,
  μ_z and the largest σ_z grow with the spacing i; for bridging distances of 4-5 bases
  the block height is as good as a single model (≈ 0.1 ‰ of the flying height).

Both are computed here the way the theory does it: from the inverse of the normal
matrix of the *linear* model-block adjustments of :mod:`orientviz.stereo_models`:

* planimetry: a 4-parameter similarity per model, X = a x − b y + X0, Y = b x + a y + Y0,
  on the standard (Gruber) points of the models, *without* projection centres; every
  model coordinate has σ0 (unit weight); XY control fixed.
* height: 3 parameters per model, Z = z + Z0 + ω (y − ȳ) − φ (x − x̄), on the standard
  points *and* the two projection centres of each model, the centres with all three
  coordinates (a tilt moves a centre sideways by its height above the model times the
  tilt; without this consecutive models could turn about their common line of points,
  which lies right below their common centre); every model coordinate has σ0; Z control
  fixed. This is the height step of the PAT-M iteration
  (:func:`orientviz.stereo_models.independent_models`, ``method="pat-m"``).

The geometry comes from :func:`~orientviz.simulate.simulate_block` (flat terrain,
exact flight plan, 60 % / 20 % overlap, wide angle); μ values are RMS over all
non-control points, in units of σ0. The empirical counterpart adds random errors σ0 to
the model coordinates, solves, and takes the RMS of the true errors.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..block import CONTROL
from ..stereo_models import model_pairs, scalar_cofactors, solve_rows
from ._block import simulate_block

F64 = NDArray[np.float64]


@dataclass
class BlockPrecision:
    """Theoretical (and optionally empirical) precision of one block configuration.

    Attributes
    ----------
    kind : {"planimetry", "height"}
    n_strips, n_models : int
        Strips and models of the block.
    spacing : int
        Control spacing in bases (perimeter spacing, or chain spacing i).
    mu : float
        RMS standard deviation of the non-control points in units of σ0 (μ_xy = RMS of
        σ_X and σ_Y; μ_z of σ_Z).
    max : float
        Largest standard deviation (σ_xy,max or σ_z,max) in units of σ0.
    sd : ndarray, shape (p,) or (p, 2)
        Standard deviations of the non-control points (σ0 = 1).
    xy : ndarray, shape (p, 2)
        Their positions in m.
    control_xy : ndarray, shape (k, 2)
        Positions of the control points in m.
    empirical : float or None
        RMS of the true errors over ``replicates`` simulations, in units of σ0.
    replicates : int
    """

    kind: str
    n_strips: int
    n_models: int
    spacing: int
    mu: float
    max: float
    sd: F64
    xy: F64
    control_xy: F64
    empirical: float | None = None
    replicates: int = 0
    extra: dict = field(default_factory=dict)


def _geometry(n_strips: int, images: int, control: str, spacing: int, kind: str, **kw):
    sim = simulate_block(
        n_strips, images, rng=np.random.default_rng(0), relief=0.0, extra=None,
        sigma_image_mm=0.0, start_error=None, flight_jitter=(0.0, 0.0, 0.0, 0.0),
        control=control, control_spacing=spacing, chain_spacing=spacing, control_kind=kind, **kw,
    )  # fmt: skip
    b = sim.truth
    models = sim.layout.models
    j, ol, _ = model_pairs(b, models)
    pt = b.observations.point[ol]
    order = np.argsort(j, kind="stable")
    return sim, models, j[order], pt[order]


def planimetric_precision(
    n_strips: int,
    *,
    models_per_strip: int | None = None,
    control_spacing: int = 2,
    replicates: int = 0,
    rng: np.random.Generator | None = None,
) -> BlockPrecision:
    """μ_xy/σ0 of a block of independent models with XY control on the perimeter.

    Parameters
    ----------
    n_strips : int
        Number of strips n_s.
    models_per_strip : int, optional
        Default 2·n_s: a square block at 60 % / 20 % overlap (strip spacing = 2 bases).
    control_spacing : int
        Perimeter control every ``control_spacing`` bases (and as often across).
    replicates : int
        Number of simulations with random model-coordinate errors (needs ``rng``).
    rng : numpy.random.Generator, optional

    Returns
    -------
    BlockPrecision
    """
    nm = 2 * n_strips if models_per_strip is None else int(models_per_strip)
    sim, models, j, pt = _geometry(n_strips, nm + 1, "perimeter", control_spacing, "xyz")
    b = sim.truth
    X = b.points.xyz[:, :2]
    cen = np.zeros((models.shape[0], 2))
    cnt = np.bincount(j, minlength=models.shape[0])
    for c in range(2):
        cen[:, c] = np.bincount(j, X[pt, c], minlength=models.shape[0]) / cnt
    x = X[pt] - cen[j]  # model coordinates (centred; exact geometry)
    k = x.shape[0]
    J = np.zeros((k, 2, 4))
    J[:, 0] = np.column_stack([x[:, 0], -x[:, 1], np.ones(k), np.zeros(k)])
    J[:, 1] = np.column_stack([x[:, 1], x[:, 0], np.zeros(k), np.ones(k)])
    ctrl = b.points.role == CONTROL
    free = np.unique(pt[~ctrl[pt]])
    scalar = np.full((b.n_points, 2), -1, np.int64)
    scalar[free] = np.arange(2 * free.size).reshape(-1, 2)
    rows = scalar[pt].ravel()
    sol = solve_rows(
        np.repeat(j, 2), J.reshape(2 * k, 4), rows, np.ones(2 * k), np.zeros(2 * k),
        models.shape[0], 2 * free.size, context="planimetric block", solve=False,
    )  # fmt: skip
    Q = scalar_cofactors(sol, scalar[free], centres=cen)
    sd = np.sqrt(np.einsum("nii->ni", Q))
    out = BlockPrecision(
        "planimetry", n_strips, int(models.shape[0]), control_spacing,
        float(np.sqrt(np.mean(sd**2))), float(np.max(np.sqrt(np.sum(sd**2, axis=1) / 2))),
        sd, X[free], X[ctrl],
    )  # fmt: skip
    if replicates:
        errs = []
        for _ in range(int(replicates)):
            r = rng.normal(0.0, 1.0, 2 * k)  # errors of the model coordinates (σ0 = 1)
            # at the truth (θ = identity) the misclosures are the model-coordinate errors,
            # and the corrections dX are the errors of the adjusted coordinates
            _, dX = sol.resolve(r)
            errs.append(dX)
        e = np.concatenate(errs)
        out.empirical, out.replicates = float(np.sqrt(np.mean(e**2))), int(replicates)
    return out


def height_precision(
    chain_spacing: int,
    *,
    n_strips: int = 4,
    models_per_strip: int = 24,
    replicates: int = 0,
    rng: np.random.Generator | None = None,
) -> BlockPrecision:
    """μ_z/σ0 and σ_z,max/σ0 with height-control chains every ``chain_spacing`` bases.

    Parameters
    ----------
    chain_spacing : int
        Spacing i of the chains of height control across the strips, in bases.
    n_strips, models_per_strip : int
        Block size (default 4 strips of 24 models).
    replicates : int
        Simulations with random model heights (needs ``rng``).
    rng : numpy.random.Generator, optional

    Returns
    -------
    BlockPrecision
    """
    sim, models, j, pt = _geometry(n_strips, models_per_strip + 1, "chains", chain_spacing, "xy+z")
    b = sim.truth
    nmod = models.shape[0]
    P = b.points.xyz
    zc = b.points.sigma[:, 2] == 0  # height control (given Z)
    # rows: heights of the model points and of both projection centres of each model,
    # then X and Y of the centres (a tilt moves a centre sideways by H·tilt)
    H = float(np.mean(b.images.X0[:, 2]) - np.mean(P[:, 2]))
    pc_xy = b.images.X0[models][:, :, :2].reshape(-1, 2)
    jm = np.repeat(np.arange(nmod), 2)
    jj = np.concatenate([j, jm])
    xy = np.concatenate([P[pt, :2], pc_xy])
    cnt = np.bincount(jj, minlength=nmod)
    cen = np.column_stack([np.bincount(jj, xy[:, c], minlength=nmod) / cnt for c in range(2)])
    zc_m = (
        np.bincount(jj, np.concatenate([np.zeros(pt.size), np.full(jm.size, H)]), minlength=nmod)
        / cnt
    )
    d = xy - cen[jj]
    dz = H - zc_m[jm]  # height of the centres above the model centre
    zero = np.zeros(jm.size)
    J = np.vstack([
        np.column_stack([np.ones(jj.size), d[:, 1], -d[:, 0]]),
        np.column_stack([zero, zero, dz]),
        np.column_stack([zero, -dz, zero]),
    ])  # fmt: skip
    free = np.unique(pt[~zc[pt]])
    scalar = np.full(b.n_points, -1, np.int64)
    scalar[free] = np.arange(free.size)
    centres = np.unique(models.ravel())
    nc = centres.size
    c_of = np.full(b.n_images, -1, np.int64)
    c_of[centres] = free.size + np.arange(nc)
    cm = c_of[models].ravel()
    rows = np.concatenate([scalar[pt], cm, cm + nc, cm + 2 * nc])
    n_sc = free.size + 3 * nc
    jr = np.concatenate([jj, jm, jm])
    args = (jr, J, rows, np.ones(jr.size))
    sol = solve_rows(*args, np.zeros(jr.size), nmod, n_sc, context="height block", solve=False)
    groups = np.arange(free.size)[:, None]
    sd = np.sqrt(scalar_cofactors(sol, groups, centres=cen)[:, 0, 0])
    out = BlockPrecision(
        "height", n_strips, int(nmod), chain_spacing, float(np.sqrt(np.mean(sd**2))),
        float(sd.max()), sd, P[free, :2], P[zc, :2],
    )  # fmt: skip
    if replicates:
        errs = [
            sol.resolve(rng.normal(0.0, 1.0, jr.size))[1][: free.size]
            for _ in range(int(replicates))
        ]
        e = np.concatenate(errs)
        out.empirical, out.replicates = float(np.sqrt(np.mean(e**2))), int(replicates)
    return out


def fit_log_law(n_strips, mu) -> tuple[float, float]:
    """Least-squares fit μ = a + b · log10(n_s); returns (a, b)."""
    n = np.asarray(n_strips, dtype=float)
    A = np.column_stack([np.ones(n.size), np.log10(n)])
    a, b = np.linalg.lstsq(A, np.asarray(mu, dtype=float), rcond=None)[0]
    return float(a), float(b)
