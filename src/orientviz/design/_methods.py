"""The design's precision for another adjustment method than the bundle.

* ``"bundle"`` — :class:`orientviz.design.LiveDesign` (the bundle's normal equations);
* ``"models"`` — independent models: :func:`orientviz.stereo_models.independent_models`
  (rigorous 7-parameter method, weighted control, precision on) at the design block. Its
  observations are the model coordinates formed from the error-free image coordinates, so
  the first step is zero and the cofactors of the points (a-priori σ0 = 1; σ of a model
  coordinate σ_img·m_B in planimetry, √2·H/B·σ_img·m_B in height, the library's default)
  are the design's. The models have no image rays: redundancy numbers, MDB and δ̄0 of the
  rays are not defined (NaN);
* ``"polynomial"`` — the polynomial strip/block adjustment has no precision in the
  library (:func:`orientviz.polynomial.polynomial_adjust` returns no cofactors): no design
  precision, said in words by :data:`METHODS`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..stereo_models import independent_models
from ._quality import DesignQuality, summarise, weak_spots

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: method → (name in words, None or why there is no design precision)
METHODS: dict[str, tuple[str, str | None]] = {
    "bundle": ("bundle adjustment", None),
    "models": ("independent models (7 parameters per model)", None),
    "polynomial": (
        "polynomial strip adjustment",
        "the polynomial adjustment gives no precision (no cofactors) in orientviz, so it "
        "has no design precision; the colours and the summary stay those of the bundle",
    ),
}


def assess_models(
    block: Block, spec: dict[str, Any], *, level: float = 0.95, auxiliary: list | None = None
) -> DesignQuality:
    """The design's precision if the block is adjusted by independent models.

    Parameters
    ----------
    block : Block
        A design block (planned geometry, error-free observations, weighted control with
        ``points.sigma`` > 0 m; ``images.strip`` set).
    spec : dict
        Needs ``base_m`` (air base, m; for the weak spots' distances).
    level : float
        Probability of the confidence ellipsoids.
    auxiliary : list of Auxiliary, optional
        Statoscope / APR data of the design, adjusted jointly (rigorous method).

    Returns
    -------
    DesignQuality
        ``point_sigma``/``point_cov`` (m, m²) of every block point in a model (NaN for
        the others), ``station_sigma`` with σ of the projection centres (m) in columns
        0-2 (NaN for the angles); redundancy numbers, MDB, δ̄0 and point shifts NaN (the
        models have no image rays); weak spots and summary.
    """
    res = independent_models(
        block, control="weighted", precision=True, max_iter=3, auxiliary=auxiliary or None
    )
    Q = np.asarray(res.cofactor_groups["points"])
    k = np.asarray(res.point_index)
    ci = np.asarray(res.centre_image)
    return models_quality(block, spec, Q[: k.size], k, Q[k.size : k.size + ci.size], ci, level)


def models_quality(
    block: Block, spec: dict[str, Any], point_q: F64, points: I64, centre_q: F64,
    centres: I64, level: float = 0.95,
) -> DesignQuality:  # fmt: skip
    """A :class:`DesignQuality` of a models design from its cofactor blocks.

    Parameters
    ----------
    block : Block
    spec : dict
        Needs ``base_m`` (m).
    point_q : ndarray, shape (k, 3, 3)
        Cofactor blocks (m², σ0 = 1) of the block points ``points`` (k,).
    centre_q : ndarray, shape (c, 3, 3)
        Those of the projection centres of the images ``centres`` (c,).
    level : float
        Probability of the confidence ellipsoids.
    """
    p, m, n = block.n_points, block.n_images, block.n_observations
    cov = np.full((p, 3, 3), np.nan)
    cov[points] = point_q
    st = np.full((m, 6), np.nan)
    if centres.size:
        st[centres, :3] = np.sqrt(np.clip(np.einsum("nii->ni", centre_q), 0.0, None))
    sig = np.sqrt(np.clip(np.einsum("nii->ni", cov), 0.0, None))
    nan_n = np.full(n, np.nan)
    q = DesignQuality(
        point_sigma=sig, point_cov=cov, station_sigma=st, level=level, redundancy=np.full((n, 2), np.nan), mdb=nan_n,
        external=nan_n.copy(), point_shift=nan_n.copy(),
        control=np.isfinite(block.points.xyz_known).any(axis=1),
    )  # fmt: skip
    with warnings.catch_warnings():  # the rays' measures are all NaN here
        warnings.simplefilter("ignore", RuntimeWarning)
        q.weak_spots = weak_spots(q, block, float(spec["base_m"]))
        q.summary = summarise(q)
    q.summary.update(untestable_rays=0, mdb_max_mm=float("nan"), external_max=float("nan"))
    return q
