"""What enters the textbook reference bundle (:mod:`orientviz.bundle.reference`).

The rays that are adjusted, their weights, which points are unknowns (the datum rules of
:func:`~orientviz.bundle.problem.point_setup`: control held fixed or weighted), the
weights of observed exterior orientations, and the additional parameters: a linear set's
design at the observed coordinates, or a :class:`~orientviz.bundle.LensModel` bound to
the block. Constant over the iterations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from .model import LensModel, ap_set
from .problem import point_setup

F64 = NDArray[np.float64]


@dataclass
class ReferenceData:
    """The rays that enter, the point unknowns, the weights (constant in a run).

    Per ray: ``image``, ``point``, ``l`` (observed x, y, mm), ``p`` (1/σ², 1/mm²),
    ``cam`` (c, x0, y0 mm) and, with additional parameters, ``group``; ``col`` the
    unknown of each block point (−1: held fixed), ``unknown`` the block point of each
    unknown; ``prior_w``, ``prior`` the weights (1/m²) and values (m) of control
    coordinates, ``eo_w``, ``eo`` of observed X0, Y0, Z0, ω, φ, κ (1/m², 1/rad²; m,
    rad); ``k`` parameters per group, ``design`` (n, 2, k) of a linear set or ``lens``,
    ``ap_w`` the weights of the pseudo-observations a = 0; ``xyz0`` the points' start.
    """

    image: NDArray[np.int64]  # per ray
    point: NDArray[np.int64]
    l: F64  # observed x, y (mm)
    p: F64  # weights 1/σ² (1/mm²)
    col: NDArray[np.int64]  # point unknown of each block point, −1 = held fixed
    unknown: NDArray[np.int64]  # block index of each point unknown
    prior_w: F64  # (p_var, 3) weights of control coordinates (1/m²), 0 = none
    prior: F64  # (p_var, 3) their given values (m)
    cam: tuple[F64, F64, F64]  # c, x0, y0 per ray (mm)
    eo_w: F64  # (m, 6) weights of observed X0, Y0, Z0, ω, φ, κ (1/m², 1/rad²)
    eo: F64  # (m, 6) their observed values
    k: int = 0  # additional parameters per group (q = G·k)
    group: NDArray[np.int64] | None = None  # group of each ray
    design: F64 | None = None  # (n, 2, k) constant design of a linear set (mm per unit)
    lens: object = None  # a bound LensModel: the projection itself
    ap_w: F64 = field(default_factory=lambda: np.zeros(0))  # weights of a = 0
    xyz0: F64 | None = None  # start values of all points, fixed ones at their given values

    @property
    def ap0(self) -> F64:
        return np.zeros(self.ap_w.size)


def reference_data(
    block: Block, control: str = "fixed", additional=None, ap_group=None, ap_sigma=None
) -> ReferenceData:
    """What enters the adjustment (arguments as :func:`orientviz.bundle.bundle_adjust`)."""
    s = point_setup(block, control)  # the library's datum rules: fixed / weighted control
    obs, img, cams = block.observations, block.images, block.cameras
    use = s.used_obs
    image, point = obs.image[use], obs.point[use]
    col = -np.ones(block.n_points, np.int64)
    unknown = np.flatnonzero(s.unknown)
    col[unknown] = np.arange(unknown.size)
    ps = s.prior_sigma[unknown]
    cam = img.camera[image]
    eo_s = np.hstack([img.X0_sigma, img.angles_sigma])
    eo_l = np.hstack([img.X0_obs, img.angles_obs])
    ok = np.isfinite(eo_s) & (eo_s > 0) & np.isfinite(eo_l)
    out = ReferenceData(
        image, point, obs.xy[use], 1.0 / obs.sigma[use] ** 2, col, unknown,
        np.where(np.isfinite(ps), 1.0 / ps**2, 0.0), np.nan_to_num(s.known[unknown]),
        (cams.c[cam], cams.x0[cam], cams.y0[cam]),
        np.where(ok, 1.0 / np.where(ok, eo_s, 1.0) ** 2, 0.0), np.nan_to_num(eo_l),
    )  # fmt: skip
    out.xyz0 = block.points.xyz.copy()
    fixed, known = s.fixed, s.known[s.fixed]
    out.xyz0[fixed] = np.where(np.isfinite(known), known, out.xyz0[fixed])
    if additional is None:
        return out
    if isinstance(additional, str):
        additional = ap_set(additional)
    is_lens = isinstance(additional, LensModel)
    default = img.camera if is_lens else np.zeros(block.n_images, np.int64)
    grp = np.asarray(default if ap_group is None else ap_group, np.int64)
    G = int(grp.max()) + 1
    out.group = grp[image]
    if is_lens:
        out.lens = additional.bind(block, out.l, image, grp)
        out.k = out.lens.k
        if ap_sigma is None:
            ap_sigma = out.lens.sigma.reshape(-1)
    else:
        out.design = np.asarray(additional.design(out.l), dtype=float)
        out.k = out.design.shape[2]
    sig = np.asarray(np.inf if ap_sigma is None else ap_sigma, dtype=float).reshape(-1)
    sig = sig if sig.size == G * out.k else np.tile(np.broadcast_to(sig, (out.k,)), G)
    out.ap_w = np.where(np.isfinite(sig) & (sig > 0), 1.0 / sig**2, 0.0)
    return out
