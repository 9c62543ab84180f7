"""The parts of a bundle problem, one job each: observations and the parameter blocks.

A :class:`~orientviz.bundle.problem.BundleProblem` is composed of

* :class:`ImageObservations` — the rays that enter the adjustment (image, point, x, y,
  1/σ), sorted by the track length of their point, then by point (the order of the
  point reductions, :mod:`orientviz.bundle.reduced._tracks`: they work on contiguous slices);
* :class:`InteriorOrientation` — c, x0, y0 of each image's camera (mm, held fixed);
* :class:`ExteriorBlock` — the exterior orientations' observed values and weights
  (GNSS/INS-like observations of X0 and ω, φ, κ);
* :class:`PointBlock` — which points are unknowns, their columns, and the weighted
  pseudo-observations of control coordinates;
* :class:`AdditionalBlock` — self-calibration parameters (design, groups, weights of
  their pseudo-observations and the index orders of their border);
* the auxiliary data (:class:`orientviz.bundle.problem._auxiliary.BundleAuxiliary`).

All parts are constant over the iterations; the iterate is a
:class:`~orientviz.bundle.problem._state.BundleState`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ...block import Block
from ...errors import InputError
from ..model._lens import BoundLens, LensModel
from ..reduced import ReducedStructure
from ._ap_structure import APStructure
from ._checks import PointSetup

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass(frozen=True)
class ImageObservations:
    """The image observations that enter the adjustment, in track order (by the number
    of rays of their point unknown, then by point, then by image; fixed points last).

    Attributes
    ----------
    index : ndarray of int, shape (n,)
        Row of each ray in ``block.observations``.
    image, point : ndarray of int, shape (n,)
        Image and point of each ray.
    xy : ndarray, shape (n, 2)
        Observed image coordinates, mm.
    weight : ndarray, shape (n, 2)
        1/σ of x and y, 1/mm (the square root of the weights).
    column : ndarray of int, shape (n,)
        Point unknown of each ray (−1 for fixed points).
    var_rays : slice or ndarray of int
        The rays of point unknowns in the order of the point unknowns (a slice when that
        is the rays' order).
    """

    index: I64
    image: I64
    point: I64
    xy: F64
    weight: F64
    column: I64
    var_rays: slice | I64

    @property
    def n(self) -> int:
        """Number of rays."""
        return int(self.index.size)


@dataclass(frozen=True)
class InteriorOrientation:
    """Interior orientation of each image (its camera's), mm; held fixed in the bundle."""

    c: F64
    x0: F64
    y0: F64


@dataclass(frozen=True)
class ExteriorBlock:
    """Observed exterior orientations as weighted pseudo-observations.

    Attributes
    ----------
    X0_w, angles_w : ndarray, shape (m, 3)
        Weights 1/σ² of the observed projection centres (1/m²) and attitudes (1/rad²);
        0 where not observed.
    X0_obs, angles_obs : ndarray, shape (m, 3)
        Observed values (m, rad; 0 where not observed).
    """

    X0_w: F64
    X0_obs: F64
    angles_w: F64
    angles_obs: F64

    @property
    def m(self) -> int:
        """Number of images."""
        return int(self.X0_w.shape[0])


@dataclass(frozen=True)
class PointBlock:
    """The object points: which are unknowns, and their coordinate pseudo-observations.

    Attributes
    ----------
    unknown : ndarray of int, shape (p_var,)
        Indices of the point unknowns.
    column : ndarray of int, shape (p,)
        Unknown's position of each block point (−1 for fixed points).
    prior_w : ndarray, shape (p_var, 3)
        Weights 1/σ² (1/m²) of given coordinates of weighted control; 0 where none.
    prior_obs : ndarray, shape (p_var, 3)
        The given coordinates, m (0 where none).
    """

    unknown: I64
    column: I64
    prior_w: F64
    prior_obs: F64

    @property
    def n(self) -> int:
        """Number of point unknowns."""
        return int(self.unknown.size)


@dataclass
class BorderSolver:
    """What the solve of the additional parameters' border remembers between iterations.

    Attributes
    ----------
    hold : bool
        The parameters are held in this iteration (first step from a poor start).
    reuse : bool
        E and F of the last iteration may be reused (the geometry stood still).
    border : tuple or None
        (E, F0) of the last iteration.
    preconditioner : object or None
        Single-precision Cholesky factor of Fs for the CG solves.
    log : list of str
        One entry per solve ("held", "Fs formed (float32), cg1", …).
    """

    hold: bool = False
    reuse: bool = False
    border: tuple | None = None
    preconditioner: object | None = None
    log: list[str] = field(default_factory=list)


class _Terms:
    """What the design's sparse form and the border's index orders are formed from, shared
    by an :class:`AdditionalBlock` and the blocks it makes (:meth:`AdditionalBlock.with_design`);
    both are formed on first use (the cameras inside the images' blocks,
    :mod:`._camera_blocks`, need neither while they iterate).

    ``Aw`` is the weighted design of the last block made (the structure's values are
    those of the latest design, as if refreshed at every :meth:`~AdditionalBlock.with_design`).
    """

    def __init__(self, cols: I64, shape: tuple[int, int], args: tuple, Aw: F64) -> None:
        self.cols, self.shape, self.args, self.Aw = cols, shape, args, Aw
        self.structure: APStructure | None = None
        self._indptr: I64 | None = None

    def csr(self, A: F64) -> sp.csr_matrix:
        """The design A (n, 2, k) as a (2n, q) CSR matrix (k entries per row; its index
        arrays are shared by the matrices of every design)."""
        if self._indptr is None:
            k = A.shape[2]
            self._indptr = np.arange(0, A.shape[0] * 2 * k + 1, k, dtype=self.cols.dtype)
        return sp.csr_matrix((A.reshape(-1), self.cols, self._indptr), shape=self.shape)

    def get_structure(self) -> APStructure:
        if self.structure is None:
            self.structure = APStructure(*self.args, self.Aw)
        return self.structure

    def refresh(self, Aw: F64) -> None:
        self.Aw = Aw
        if self.structure is not None:
            self.structure.refresh(Aw)


@dataclass(frozen=True)
class AdditionalBlock:
    """Self-calibration parameters: k per group, G groups, q = G·k unknowns.

    Attributes
    ----------
    k, G : int
        Parameters per group and number of groups (0 without parameters).
    group : ndarray of int, shape (m,)
        Group of each image.
    A : ndarray, shape (n, 2, k)
        Design at the observed coordinates (mm per unit), ``Aw`` weighted by 1/σ.
    w : ndarray, shape (q,)
        Weights of the pseudo-observations a = 0 (0 = free).
    names : list of str
        ``"<name>@g<group>"``.
    ray_length : float
        Median ray length, m (the scale of the reuse test of E, F).
    lens : BoundLens or None
        An exact camera model (:mod:`orientviz.bundle.model._lens`): then A, Aw, A_csr are the
        design at the current iterate (:meth:`AdditionalBlock.with_design`).
    terms : _Terms or None
        What :attr:`A_csr` and :attr:`structure` are formed from (on first use).

    Properties :attr:`A_csr` (A of all rays as one (2n, q) sparse matrix: the model term
    A·a in one product) and :attr:`structure` (the border's index orders,
    :class:`APStructure`) are formed when first read.
    """

    k: int = 0
    G: int = 0
    group: I64 | None = None
    A: F64 | None = None
    Aw: F64 | None = None
    w: F64 | None = None
    names: list[str] = field(default_factory=list)
    ray_length: float = 1.0
    lens: BoundLens | None = None
    terms: _Terms | None = None

    @property
    def q(self) -> int:
        """Number of parameters, G·k."""
        return self.k * self.G

    @cached_property
    def A_csr(self) -> sp.csr_matrix | None:
        """A of all rays as one (2n, q) CSR matrix (formed on first use)."""
        return None if self.terms is None else self.terms.csr(self.A)

    @property
    def structure(self) -> APStructure | None:
        """Index orders of the border's terms (formed on first use, shared by the blocks
        :meth:`with_design` makes)."""
        return None if self.terms is None else self.terms.get_structure()

    def with_design(self, A: F64, weight: F64) -> AdditionalBlock:
        """This block with the design ``A`` (n, 2, k) mm per unit (rays weighted by
        ``weight`` (n, 2), 1/mm); the structure's value terms are refreshed in place."""
        Aw = A * weight[:, :, None]
        self.terms.refresh(Aw)
        return replace(self, A=A, Aw=Aw)


def image_observations(block: Block, setup: PointSetup, pt_col: I64) -> ImageObservations:
    """The used rays, sorted by the track length of their point unknown, then by point
    unknown, then by image; the rays of fixed points last, by image. The order of
    :class:`orientviz.bundle.reduced._tracks.TrackGroups` (its per-ray arrays are then slices of
    the evaluations' arrays, no gathers)."""
    obs = block.observations
    uobs = np.flatnonzero(setup.used_obs)
    oi, opt = np.take(obs.image, uobs), np.take(obs.point, uobs)
    col = np.take(pt_col, opt)
    var = col >= 0
    n_var = int(pt_col.max(initial=-1)) + 1
    k = np.bincount(col[var], minlength=n_var)  # track length of each point unknown
    order = _track_order(k, col, var, oi, block.n_images)
    uobs = np.take(uobs, order)
    take = lambda a: np.take(a, order, axis=0)  # noqa: E731
    xy, sigma = np.take(obs.xy, uobs, axis=0), np.take(obs.sigma, uobs, axis=0)
    return ImageObservations(uobs, take(oi), take(opt), xy, 1.0 / sigma, take(col), slice(0))


def _track_order(k: I64, col: I64, var, oi: I64, m: int) -> I64:
    """The rays by (track length, point unknown) of their point, then by image, then in
    their order; the rays of fixed points last, by image: ``np.lexsort((oi, key))`` with
    key = k·n_var + point. As two stable 16-bit sorts (NumPy's radix sort: by image, then
    by the points' rank in that order) when the counts allow; the same order."""
    n_var = k.size
    if max(n_var, m) >= np.iinfo(np.int16).max:
        key = np.where(var, np.take(k, col, mode="clip") * n_var + col, np.iinfo(np.int64).max)
        return np.lexsort((oi, key))
    rank = np.empty(n_var + 1, np.int16)  # of each point unknown by (k, point); fixed: last
    rank[np.argsort(k, kind="stable")] = np.arange(n_var, dtype=np.int16)
    rank[n_var] = n_var
    by_image = np.argsort(oi.astype(np.int16), kind="stable")
    key = rank[np.where(var, col, n_var)[by_image]]
    return by_image[np.argsort(key, kind="stable")]


def with_var_rays(obs: ImageObservations, struct: ReducedStructure) -> ImageObservations:
    """``obs`` with ``var_rays`` set from the reduced structure's point order."""
    nv = int(np.sum(obs.column >= 0))
    pv = struct.pt_obs
    vo = slice(0, nv) if np.array_equal(pv, np.arange(nv)) else pv
    return ImageObservations(obs.index, obs.image, obs.point, obs.xy, obs.weight, obs.column, vo)


def interior_orientation(block: Block) -> InteriorOrientation:
    """c, x0, y0 (mm) of each image's camera."""
    cam = block.images.camera
    cams = block.cameras
    return InteriorOrientation(cams.c[cam], cams.x0[cam], cams.y0[cam])


def _weights(o: F64, s: F64) -> tuple[F64, F64]:
    ok = np.isfinite(o) & np.isfinite(s) & (s > 0)
    return np.where(ok, 1.0 / np.where(ok, s, 1.0) ** 2, 0.0), np.nan_to_num(o)


def exterior_block(block: Block) -> ExteriorBlock:
    """Observed projection centres and attitudes of the block's images as weights/values."""
    img = block.images
    X0_w, X0_l = _weights(img.X0_obs, img.X0_sigma)
    ang_w, ang_l = _weights(img.angles_obs, img.angles_sigma)
    return ExteriorBlock(X0_w, X0_l, ang_w, ang_l)


def point_block(block: Block, setup: PointSetup) -> PointBlock:
    """The point unknowns and their coordinate pseudo-observations (weighted control)."""
    var_pts = np.flatnonzero(setup.unknown)
    pt_col = -np.ones(block.n_points, np.int64)
    pt_col[var_pts] = np.arange(var_pts.size)
    ps = setup.prior_sigma[var_pts]
    prior_w = np.where(np.isfinite(ps), 1.0 / ps**2, 0.0)
    return PointBlock(var_pts, pt_col, prior_w, np.nan_to_num(setup.known[var_pts]))


def additional_block(
    block: Block,
    obs: ImageObservations,
    points: PointBlock,
    struct: ReducedStructure,
    additional,
    ap_group,
    ap_sigma,
) -> AdditionalBlock:
    """The self-calibration part (an empty block without ``additional``).

    Parameters
    ----------
    additional : AdditionalParameters, LensModel, str or None
        ``design(xy (n, 2) mm) -> (n, 2, k)``, evaluated at the observed coordinates; a
        string is a set's name for :func:`~orientviz.bundle.ap_set`.
    ap_group : array_like of int, shape (m,), optional
        Group of each image (default: one group).
    ap_sigma : float or array_like (k,), optional
        σ of the pseudo-observations a = 0 (units of the parameters); None = free.
    """
    if additional is None:
        return AdditionalBlock()
    if isinstance(additional, str):  # a set's name, as on the command line
        from ..model._additional import ap_set  # the sets: only when one is named

        additional = ap_set(additional)
    elif not isinstance(additional, LensModel) and not (
        callable(getattr(additional, "design", None)) and hasattr(additional, "names")
    ):
        raise InputError(
            "additional: expected a set's name (e.g. 'ebner12'), ap_set(name, ...) or a "
            f"LensModel, got {type(additional).__name__}"
        )
    m, n = block.n_images, obs.n
    lens = None
    if isinstance(additional, LensModel):  # the camera itself: one group per camera
        default = block.images.camera
    else:
        default = np.zeros(m, np.int64)
    grp = default if ap_group is None else np.asarray(ap_group, np.int64)
    if grp.shape != (m,) or grp.min() < 0:
        raise InputError(f"ap_group: expected {m} non-negative group indices")
    G = int(grp.max()) + 1
    if isinstance(additional, LensModel):
        lens = additional.bind(block, obs.xy, obs.image, grp)
        if lens.k == 0:  # a known calibration applied, nothing estimated
            return AdditionalBlock(G=G, group=grp, lens=lens)
        A = np.zeros((n, 2, lens.k))  # the design at the iterate: set at each linearisation
        if ap_sigma is None:
            ap_sigma = lens.sigma.reshape(-1) if G else np.inf
    else:
        A = np.asarray(additional.design(obs.xy), dtype=float)
    if A.ndim != 3 or A.shape[:2] != (n, 2):
        raise InputError(f"additional.design: expected shape (n, 2, k), got {A.shape}")
    k = A.shape[2]
    # a camera model's design is set at each linearisation: zeros until then (untouched)
    Aw = np.zeros(A.shape) if lens is not None else A * obs.weight[:, :, None]
    # the design's column indices (k per row), of the index type the sparse form keeps
    it = np.int32 if max(2 * n * k, G * k) < 2**31 else np.int64
    cols = np.empty((n, 2, k), it)
    cols[:] = (grp[obs.image].astype(it) * it(k))[:, None, None] + np.arange(k, dtype=it)
    cols = cols.reshape(-1)
    s = np.inf if ap_sigma is None else ap_sigma
    s = np.asarray(s, dtype=float)
    s = (
        s.reshape(-1)
        if s.size == G * k and lens is not None
        else np.tile(np.broadcast_to(s, (k,)), G)
    )
    w = np.where(np.isfinite(s) & (s > 0), 1.0 / s**2, 0.0)
    names = [f"{nm}@g{g}" for g in range(G) for nm in additional.names]
    # the design's sparse form (k entries per row, in column order: CSR directly) and the
    # border's index orders, formed on first use
    terms = _Terms(
        cols, (2 * n, G * k), (obs.image, obs.column, struct.pt_obs, points.n, grp, G), Aw
    )
    d = np.take(block.points.xyz, obs.point, axis=0)
    d -= np.take(block.images.X0, obs.image, axis=0)
    r = np.linalg.norm(d, axis=1)
    ray_length = float(np.nanmedian(r) if np.isnan(r).any() else np.median(r)) if r.size else 1.0
    return AdditionalBlock(k, G, grp, A, Aw, w, names, ray_length, lens, terms)
