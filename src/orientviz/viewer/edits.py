"""What the user changed in a block from the viewer, and the block that is then adjusted.

No viser here. :class:`Edits` holds the switches and values the viewer's actions set —
observations, images and control points on/off, moved control coordinates, weight
factors of observations — on top of an unchanged :class:`~orientviz.block.Block`.
:func:`effective_block` turns block + edits into the block the bundle adjusts (the
*sub-block*: only what is switched on, with the current estimates as start values, so
the adjustment is warm-started), and :func:`expand_result` maps the sub-block's result
back onto the whole block, so that the viewer keeps indexing images, points and
observations as loaded.

Rules of the sub-block:

* an observation enters if it is on and its image is on; its σ is σ / √(weight factor);
* a control point switched off becomes a check point (its coordinates are not used;
  the bundle intersects it and reports its check residual);
* tie points left with fewer than two rays, and images left with fewer than three
  observations, leave the sub-block (repeated until nothing changes); they keep their
  current values and are reported as ``dropped``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, Block

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass
class Edits:
    """The viewer's changes to a block (all arrays indexed as in the block).

    Attributes
    ----------
    obs_on : ndarray of bool, shape (n,)
    image_on : ndarray of bool, shape (m,)
    control_on : ndarray of bool, shape (p,)
        False for a control point switched off (used as a check point).
    known : ndarray, shape (p, 3)
        Given coordinates of the control points (m), as moved by the user.
    weight : ndarray, shape (n,)
        Weight factor of each observation (1 = as given; σ becomes σ / √factor).
    """

    obs_on: NDArray[np.bool_]
    image_on: NDArray[np.bool_]
    control_on: NDArray[np.bool_]
    known: F64
    weight: F64

    @classmethod
    def of(cls, block: Block) -> Edits:
        """No changes: everything on, the given coordinates, unit weight factors."""
        return cls(
            np.ones(block.n_observations, bool),
            np.ones(block.n_images, bool),
            np.ones(block.n_points, bool),
            block.points.xyz_known.copy(),
            np.ones(block.n_observations),
        )

    def copy(self) -> Edits:
        return Edits(*(getattr(self, f.name).copy() for f in fields(self)))

    def equals(self, other: Edits) -> bool:
        """True if both hold the same switches and values (NaN equal to NaN)."""
        return all(
            np.array_equal(getattr(self, f.name), getattr(other, f.name), equal_nan=True)
            for f in fields(self)
        )


@dataclass
class Mapping:
    """Where the sub-block's images, points and observations sit in the whole block.

    Attributes
    ----------
    images, points, obs : ndarray of int
        Block indices of the sub-block's images, points and observations (in order).
    dropped_images, dropped_points : ndarray of int
        Images and points that had to leave (too few observations left).
    cameras : ndarray of int or None
        Block indices of the sub-block's cameras where cameras with a model (one group of
        camera terms each) were left without images; None: all cameras kept.
    """

    images: I64
    points: I64
    obs: I64
    dropped_images: I64 = field(default_factory=lambda: np.zeros(0, np.int64))
    dropped_points: I64 = field(default_factory=lambda: np.zeros(0, np.int64))
    cameras: I64 | None = None


def effective_block(block: Block, edits: Edits) -> tuple[Block, Mapping]:
    """The block to adjust (see the module docstring) and where its parts come from.

    Parameters
    ----------
    block : Block
        The whole block at its current estimates (start values of the adjustment).
    edits : Edits
        The viewer's changes.
    """
    o, pts = block.observations, block.points
    keep = edits.obs_on & edits.image_on[o.image]
    role = pts.role.copy()
    role[(role == CONTROL) & ~edits.control_on] = CHECK
    img_keep = edits.image_on.copy()
    while True:  # drop lonely tie points and weak images until stable
        counted = keep & (role[o.point] != CHECK)
        rays = np.bincount(o.point[counted], minlength=block.n_points)
        lonely = (rays < 2) & (role != CONTROL)
        keep &= ~(lonely[o.point] & (role[o.point] != CHECK))
        per_img = np.bincount(o.image[keep & (role[o.point] != CHECK)], minlength=block.n_images)
        weak = img_keep & (per_img < 3)
        if not weak.any():
            break
        img_keep &= ~weak
        keep &= img_keep[o.image]
    # check points keep rays only if they have two or more (for their intersection)
    rays_all = np.bincount(o.point[keep], minlength=block.n_points)
    keep &= ~((role[o.point] == CHECK) & (rays_all[o.point] < 2))
    rays_all = np.bincount(o.point[keep], minlength=block.n_points)
    p_keep = rays_all > 0
    images = np.flatnonzero(img_keep)
    points = np.flatnonzero(p_keep)
    obs = np.flatnonzero(keep)
    sub = block.take(images, points, obs)
    sub.points.role = role[points].astype(pts.role.dtype)
    sub.points.xyz_known = edits.known[points].copy()
    sub.observations.sigma = o.sigma[obs] / np.sqrt(edits.weight[obs])[:, None]
    cameras = _drop_idle_cameras(sub, block)
    was_used = np.bincount(o.point[edits.obs_on], minlength=block.n_points) > 0
    mp = Mapping(
        images,
        points,
        obs,
        np.flatnonzero(edits.image_on & ~img_keep),
        np.flatnonzero(was_used & ~p_keep),
        cameras,
    )
    return sub, mp


def _drop_idle_cameras(sub: Block, block: Block) -> I64 | None:
    """Remove the cameras of ``sub`` left without images, if the cameras carry a model
    (each camera is a group of camera terms, and a group without images is not
    determinable); renumbers ``sub.images.camera``. Returns the kept cameras' indices in
    ``block`` (None: all kept)."""
    cams = block.cameras
    if not any(getattr(cams, "model", None) or []):
        return None
    kept = np.unique(sub.images.camera)
    n = len(cams.ids)
    if kept.size == n:
        return None
    new = np.full(n, -1, np.int64)
    new[kept] = np.arange(kept.size)
    rows = {}
    for f in fields(cams):
        v = getattr(cams, f.name)
        if isinstance(v, np.ndarray) and v.shape[:1] == (n,):
            rows[f.name] = v[kept].copy()
        elif isinstance(v, list) and len(v) == n:
            rows[f.name] = [v[i] for i in kept]
    sub.cameras = replace(cams, **rows)
    sub.images.camera = new[sub.images.camera]
    return kept


def expand_result(
    sub_result: Any, mp: Mapping, block: Block, sigma: F64, ap: F64 | None = None
) -> Any:
    """The sub-block's bundle result laid out for the whole ``block``.

    Parameters
    ----------
    sub_result : BundleResult
        Result of the adjustment of the sub-block (bundle residual order).
    mp : Mapping
        From :func:`effective_block`.
    block : Block
        The whole block at the start values of that adjustment (supplies the values of
        what was left out).
    sigma : ndarray, shape (n, 2)
        The σ (mm) of every image observation as weighted (edits applied).
    ap : ndarray, optional
        The camera terms of the whole block before the adjustment: those of cameras the
        sub-block left out (``mp.cameras``) keep these values (zero without them).

    Returns
    -------
    BundleResult
        ``x`` = [exterior (m·6), points (p·3)] of the whole block (left-out images and
        points at their start values), ``exterior``/``points`` likewise; image residuals
        v = f − l for *all* observations (left-out ones predicted from the adjusted
        orientations), then the sub-block's pseudo-observations; redundancy numbers and
        normalised residuals NaN for left-out observations; ``used_obs`` (n,);
        ``cofactor_groups`` ``"exterior"`` (m, 6, 6) and ``"points"`` (p, 3, 3) with NaN
        for what was left out; ``exterior_pairs`` with keys in block indices; ``history``
        with ``x`` in the whole layout (empty where the solver kept none).
    """
    m, p, n = block.n_images, block.n_points, block.n_observations
    base = np.concatenate(
        [np.hstack([block.images.X0, block.images.angles]).ravel(), block.points.xyz.ravel()]
    )
    ms, ps = mp.images.size, mp.points.size
    col = np.concatenate(
        [
            (6 * mp.images[:, None] + np.arange(6)).ravel(),
            6 * m + (3 * mp.points[:, None] + np.arange(3)).ravel(),
        ]
    )

    ap_sl = sub_result.groups.get("additional")
    q = 0 if ap_sl is None else ap_sl.stop - ap_sl.start
    ap_names = [] if ap_sl is None else list(sub_result.names[ap_sl])
    ap_idx, ap_fill = None, None
    if q and mp.cameras is not None:  # per-camera terms of the kept cameras → all cameras
        G, k = len(block.cameras.ids), q // mp.cameras.size
        ok = ap is not None and np.size(ap) == G * k
        ap_fill = np.asarray(ap, float).copy() if ok else np.zeros(G * k)
        ap_idx = (k * mp.cameras[:, None] + np.arange(k)).ravel()
        ap_names = [nm.rsplit("@g", 1)[0] + f"@g{g}" for g in range(G) for nm in ap_names[:k]]

    def full_x(xs: F64 | None, fill: F64 = base, increments: bool = False) -> F64 | None:
        if xs is None:
            return None
        if np.size(xs) < 6 * ms + 3 * ps + q:
            return np.zeros(0)
        out = fill.copy()
        out[col] = np.asarray(xs)[: 6 * ms + 3 * ps]
        if q:  # the camera terms follow the points (the bundle's layout)
            terms = np.asarray(xs)[ap_sl]
            if ap_idx is not None:  # cameras left out keep their terms (no increment)
                full = np.zeros_like(ap_fill) if increments else ap_fill.copy()
                full[ap_idx] = terms
                terms = full
            out = np.concatenate([out, terms])
        return out

    x = full_x(sub_result.x)
    zero = np.zeros_like(base)
    ext = x[: 6 * m].reshape(m, 6)
    xyz = x[6 * m : 6 * m + 3 * p].reshape(p, 3)
    # image residuals of every observation at the adjusted state (v = f − l)
    after = block.with_(
        images=replace(block.images, X0=ext[:, :3], angles=ext[:, 3:]),
        points=replace(block.points, xyz=xyz),
    )
    v_img = -after.residuals()
    n_sub = mp.obs.size
    v_sub = np.asarray(sub_result.residuals)
    v_img[mp.obs] = v_sub[: 2 * n_sub].reshape(n_sub, 2)
    tail = slice(2 * n_sub, None)

    def per_obs(a: Any) -> Any:
        if a is None:
            return None
        a = np.asarray(a, float)
        out = np.full((n, 2), np.nan)
        out[mp.obs] = a[: 2 * n_sub].reshape(n_sub, 2)
        return np.concatenate([out.ravel(), a[tail]])

    shift = 2 * (n - n_sub)
    slices = {"image": slice(0, 2 * n)}
    for k, s in sub_result.obs_slices.items():
        if k != "image":
            slices[k] = slice(s.start + shift, s.stop + shift)
    cb = {}
    for name, size, idx in (("exterior", m, mp.images), ("points", p, mp.points)):
        Q = diagonal_blocks(sub_result, name, 6 if name == "exterior" else 3)
        if Q is not None and np.ndim(Q) == 3:
            full = np.full((size,) + np.shape(Q)[1:], np.nan)
            full[idx] = Q
            cb[name] = full
    if sub_result.cofactor_groups.get("additional") is not None and ap_idx is None:
        cb["additional"] = sub_result.cofactor_groups["additional"]
    pairs = getattr(sub_result, "exterior_pairs", None)
    if pairs is not None:
        i, k = np.divmod(np.asarray(pairs.keys), max(ms, 1))
        keys = mp.images[i] * m + mp.images[k]
        order = np.argsort(keys)
        pairs = replace(pairs, keys=keys[order], blocks=np.asarray(pairs.blocks)[order])
    used = np.zeros(n, bool)
    sub_used = getattr(sub_result, "used_obs", None)
    used[mp.obs] = True if sub_used is None else np.asarray(sub_used, bool)
    history = [
        replace(it, x=full_x(it.x), dx=full_x(it.dx, zero, increments=True))
        for it in sub_result.history
    ]
    names = [
        f"{i}.{q}" for i in block.images.ids for q in ("X0", "Y0", "Z0", "omega", "phi", "kappa")
    ] + [f"{i}.{c}" for i in block.points.ids for c in "XYZ"]
    groups = {"exterior": slice(0, 6 * m), "points": slice(6 * m, 6 * m + 3 * p)}
    if q:
        names += ap_names
        groups["additional"] = slice(6 * m + 3 * p, 6 * m + 3 * p + len(ap_names))
    return replace(
        sub_result,
        x=x,
        names=names,
        groups=groups,
        residuals=np.concatenate([v_img.ravel(), v_sub[tail]]),
        sigma_obs=np.concatenate(
            [np.asarray(sigma, float).ravel(), np.asarray(sub_result.sigma_obs)[tail]]
        ),
        redundancy_numbers=per_obs(sub_result.redundancy_numbers),
        normalized_residuals=per_obs(sub_result.normalized_residuals),
        redundancy_xy=None,
        cofactor=None,
        cofactor_groups=cb,
        obs_slices=slices,
        obs_labels=None,
        history=history,
        **_typed(sub_result, ext, xyz, used, pairs),
    )


def _typed(res: Any, ext: F64, xyz: F64, used: NDArray[np.bool_], pairs: Any) -> dict:
    """The typed fields of a bundle result that this module lays out anew (those present)."""
    want = {"exterior": ext, "points": xyz, "used_obs": used, "exterior_pairs": pairs,
            "ray_gains": None, "subset": None}  # fmt: skip
    have = {f.name for f in fields(res)}
    return {k: v for k, v in want.items() if k in have}


def diagonal_blocks(res: Any, name: str, b: int) -> F64 | None:
    """Stacked b × b diagonal cofactor blocks of block ``name``: stored, or from the dense Q."""
    Q = res.cofactor_groups.get(name)
    if Q is not None and np.ndim(Q) == 3:
        return np.asarray(Q)
    if res.cofactor is None or name not in res.groups:
        return None
    sl = res.groups[name]
    idx = np.arange(sl.start, sl.stop).reshape(-1, b)
    return np.asarray(res.cofactor)[idx[:, :, None], idx[:, None, :]]
