"""Model formation: relative orientation and intersection of every stereo pair of a block.

Each model is a pair of consecutive images of a strip (:func:`~.layout.block_layout`).
Its *model frame* is the frame of the left image (a dependent pair, as in
:mod:`orientviz.orientation.relative`): origin at the left projection centre O1, axes of
the left image (x along the flight direction, z up towards the camera), R1 = I; the right
projection centre is O2 = (b, by, bz) and the right image is turned by
R2 = matrix_from_opk(ω, φ, κ) (sequence ω-φ-κ, radians). The base component ``b`` is
fixed to the distance of the two approximate projection centres, so model coordinates
come out in (approximately) metres.

The five elements (by, bz, ω, φ, κ) and the model coordinates of all common points are
estimated *together*, by least squares on the image coordinates of both images (a
two-image bundle with the left image fixed); with the points eliminated per point
(3 × 3) the five elements of all models are solved at once in batched 5 × 5 systems, so
a block of 2 000 models is formed in well under a second. This is rigorous in the
image-space sense; the y-parallax relative orientation of the analog plotter
(:func:`orientviz.orientation.relative.relative_orientation`) is its first-order cousin.

Units: image coordinates in mm, model coordinates in m (model scale ≈ object scale),
angles in rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..adjust import Evaluation, Step, StopRule, iterate
from ..block import Block, BlockLayout, block_layout
from ..camera import collinearity_jacobian
from ..errors import NotDeterminableError
from ..rotation import opk_from_matrix

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Minimum number of common points of a model (5 elements of relative orientation).
MIN_POINTS: int = 5


@dataclass
class ModelSet:
    """The models of a block in their own model frames.

    Attributes
    ----------
    models : ndarray of int, shape (n, 2)
        (left, right) image indices.
    ids : list of str
        ``"<left id>+<right id>"``.
    strip : ndarray of int, shape (n,)
        Strip of each model.
    point_model, point : ndarray of int, shape (k,)
        Model index and block point index of each model point (sorted by model).
    xyz : ndarray, shape (k, 3)
        Model coordinates in m (left-image frame, see the module docstring).
    centres : ndarray, shape (n, 2, 3)
        Model coordinates of the left (0, 0, 0) and right (b, by, bz) projection centres.
    elements : ndarray, shape (n, 5)
        by, bz (m), ω, φ, κ (rad) of the right image (dependent pair).
    sigma0 : ndarray, shape (n,)
        A-posteriori σ0 of each relative orientation (image coordinates, mm); NaN if the
        model has no redundancy.
    n_points : ndarray of int, shape (n,)
        Common points per model.
    start_rotation, start_translation : ndarray, shapes (n, 3, 3) and (n, 3)
        Approximate similarity object = λ R m + T from the block's approximate
        orientation of the left image (λ ≈ 1).
    iterations : int
        Gauss-Newton iterations used.
    """

    models: I64
    ids: list[str]
    strip: I64
    point_model: I64
    point: I64
    xyz: F64
    centres: F64
    elements: F64
    sigma0: F64
    n_points: I64
    start_rotation: F64
    start_translation: F64
    iterations: int

    @property
    def n_models(self) -> int:
        return int(self.models.shape[0])


def model_pairs(block: Block, models: I64) -> tuple[I64, I64, I64]:
    """(model, left obs, right obs) of every point seen in both images of a model."""
    obs = block.observations
    P = max(block.n_points, 1)
    key = obs.image * P + obs.point
    order = np.argsort(key, kind="stable")
    skey = key[order]
    by_img = np.argsort(obs.image, kind="stable")
    counts = np.bincount(obs.image, minlength=block.n_images)
    starts = np.cumsum(counts) - counts
    left = models[:, 0]
    n_l = counts[left]
    j = np.repeat(np.arange(models.shape[0]), n_l)
    off = np.arange(j.size) - np.repeat(np.cumsum(n_l) - n_l, n_l)
    ol = by_img[starts[left][j] + off]
    want = models[j, 1] * P + obs.point[ol]
    pos = np.clip(np.searchsorted(skey, want), 0, max(skey.size - 1, 0))
    hit = skey[pos] == want if skey.size else np.zeros(0, bool)
    return j[hit], ol[hit], order[pos[hit]]


class _ModelPairs:
    """The relative orientations of all models as one problem of the engine's loop.

    The iterate is (θ (n, 5): by, bz, ω, φ, κ per model; X (k, 3): the model points in
    their left image's frame). A step solves every model's system at once: the points are
    eliminated per point (3 × 3), the 5 × 5 reduced systems of the models are independent.
    """

    def __init__(self, j, starts, ids, obs, b, left, right) -> None:
        self.j, self.starts, self.ids, self.obs, self.b = j, starts, ids, obs, b
        self.left, self.right = left, right  # (c, x0, y0) per point row
        self.zeros3 = np.zeros((j.size, 3))

    def evaluate(self, state, jacobian: bool) -> Evaluation:
        theta, Xp = state
        j, z3 = self.j, self.zeros3
        xl, xr, wl, wr = self.obs
        X0r = np.column_stack([self.b, theta[:, 0], theta[:, 1]])
        fl, _, Jlp, _ = collinearity_jacobian(Xp, z3, z3, *self.left)
        fr, Jre, Jrp, _ = collinearity_jacobian(Xp, X0r[j], theta[j, 2:], *self.right)
        rl, rr = xl - fl, xr - fr  # l − f(x)
        cost = float(np.sum(wl * rl**2) + np.sum(wr * rr**2))
        return Evaluation(cost, True, (fl, fr, Jlp, Jre[:, :, 1:], Jrp, rl, rr))  # by … κ

    def solve(self, state, ev: Evaluation, lam: float, iteration: int) -> Step:
        _, _, Jlp, Jt, Jrp, rl, rr = ev.data
        _, _, wl, wr = self.obs
        j = self.j
        Npp = np.einsum("nai,na,naj->nij", Jlp, wl, Jlp) + np.einsum(
            "nai,na,naj->nij", Jrp, wr, Jrp
        )
        Npt = np.einsum("nai,na,naj->nij", Jrp, wr, Jt)
        Ntt = np.einsum("nai,na,naj->nij", Jt, wr, Jt)
        bp = np.einsum("nai,na->ni", Jlp, wl * rl) + np.einsum("nai,na->ni", Jrp, wr * rr)
        bt = np.einsum("nai,na->ni", Jt, wr * rr)
        Ninv = np.linalg.inv(Npp)
        NtpNi = np.einsum("nji,njk->nik", Npt, Ninv)  # Ntp · Npp⁻¹
        S = np.add.reduceat(Ntt - NtpNi @ Npt, self.starts, axis=0)
        rhs = np.add.reduceat(bt - np.einsum("nij,nj->ni", NtpNi, bp), self.starts, axis=0)
        _check_models(S, self.ids)
        dt = np.linalg.solve(S, rhs[:, :, None])[:, :, 0]
        dX = np.einsum("nij,nj->ni", Ninv, bp - np.einsum("nij,nj->ni", Npt, dt[j]))
        return Step(float(np.max(np.abs(dt), initial=0.0)), None, (dt, dX))

    def apply(self, state, step: Step):
        theta, Xp = state
        return theta + step.data[0], Xp + step.data[1]

    def snapshot(self, state) -> F64:
        return np.empty(0)


def form_models(
    block: Block,
    layout: BlockLayout | None = None,
    *,
    exclude_roles: tuple[int, ...] = (),
    max_iter: int = 10,
    tol: float = 1e-10,
) -> ModelSet:
    """Relative orientation and intersection of all models of a block.

    Parameters
    ----------
    block : Block
        Observations (mm) and approximate exterior orientations (used only for the base
        length b, which fixes the model scale, and for the start similarity).
    layout : BlockLayout, optional
        Models to form (default :func:`block_layout` of ``block``).
    exclude_roles : tuple of int
        Point roles left out of the models (e.g. ``(CHECK,)``).
    max_iter : int
        Maximum Gauss-Newton iterations.
    tol : float
        Stop when the largest correction of the elements is below ``tol`` (m and rad).

    Returns
    -------
    ModelSet

    Raises
    ------
    NotDeterminableError
        If a model has fewer than 5 common points or its relative orientation is
        singular (the message names the model).
    """
    layout = layout or block_layout(block)
    models = layout.models
    n = models.shape[0]
    img_ids = block.images.ids
    ids = [f"{img_ids[a]}+{img_ids[b]}" for a, b in models]
    j, ol, orr = model_pairs(block, models)
    if exclude_roles:
        keep = ~np.isin(block.points.role[block.observations.point[ol]], exclude_roles)
        j, ol, orr = j[keep], ol[keep], orr[keep]
    order = np.argsort(j, kind="stable")
    j, ol, orr = j[order], ol[order], orr[order]
    npts = np.bincount(j, minlength=n)
    few = np.flatnonzero(npts < MIN_POINTS)
    if few.size:
        names = ", ".join(f"{ids[k]} ({npts[k]})" for k in few[:4])
        raise NotDeterminableError(
            f"{few.size} model(s) have fewer than {MIN_POINTS} common points for the relative "
            f"orientation: {names}",
            parameters=[ids[k] for k in few],
            defect=int(few.size),
        )
    obs = block.observations
    cam = block.images.camera
    c_l, c_r = block.cameras.c[cam[models[:, 0]]], block.cameras.c[cam[models[:, 1]]]
    x0l, y0l = block.cameras.x0[cam[models[:, 0]]], block.cameras.y0[cam[models[:, 0]]]
    x0r, y0r = block.cameras.x0[cam[models[:, 1]]], block.cameras.y0[cam[models[:, 1]]]
    X0 = block.images.X0
    R_all = block.rotations()
    b = np.linalg.norm(X0[models[:, 1]] - X0[models[:, 0]], axis=1)
    # start: normal case; points by parallax intersection in the left frame
    xl, xr = obs.xy[ol], obs.xy[orr]
    wl, wr = 1.0 / obs.sigma[ol] ** 2, 1.0 / obs.sigma[orr] ** 2
    cl, cr = c_l[j], c_r[j]
    ul = np.column_stack([xl[:, 0] - x0l[j], xl[:, 1] - y0l[j], -cl])
    ur = np.column_stack([xr[:, 0] - x0r[j], xr[:, 1] - y0r[j], -cr])
    # rotate the right ray into the left frame with the approximate relative rotation
    Rrel0 = np.einsum("nji,njk->nik", R_all[models[:, 0]], R_all[models[:, 1]])
    ur_l = np.einsum("nij,nj->ni", Rrel0[j], ur)
    px = ul[:, 0] / cl - ur_l[:, 0] / -ur_l[:, 2]
    px = np.where(np.abs(px) > 1e-6, px, 1e-6)
    lam = b[j] / px
    Xp = ul / cl[:, None] * lam[:, None]
    om, ph, ka = opk_from_matrix(Rrel0)
    theta = np.column_stack([np.zeros(n), np.zeros(n), om, ph, ka])
    pairs = _ModelPairs(j, np.cumsum(npts) - npts, ids, (xl, xr, wl, wr), b,
                        (cl, x0l[j], y0l[j]), (cr, x0r[j], y0r[j]))  # fmt: skip
    run = iterate(
        pairs, (theta, Xp), redundancy=int(np.sum(npts - 5)), max_iter=max_iter,
        stop=StopRule(step_test=lambda step: np.max(np.abs(step.data[0])) < tol),
    )  # fmt: skip
    theta, Xp = run.state
    iterations = len(run.history) - 1
    fl, fr = run.evaluation.data[:2]
    X0r = np.column_stack([b, theta[:, 0], theta[:, 1]])
    vtpv = np.bincount(
        j, np.sum(wl * (xl - fl) ** 2, axis=1) + np.sum(wr * (xr - fr) ** 2, axis=1), minlength=n
    )
    dof = 4 * npts - 3 * npts - 5
    with np.errstate(divide="ignore", invalid="ignore"):
        s0 = np.where(dof > 0, np.sqrt(vtpv / np.maximum(dof, 1)), np.nan)
    centres = np.zeros((n, 2, 3))
    centres[:, 1] = X0r
    return ModelSet(
        models=models,
        ids=ids,
        strip=layout.model_strip,
        point_model=j,
        point=obs.point[ol],
        xyz=Xp,
        centres=centres,
        elements=theta,
        sigma0=s0,
        n_points=npts,
        start_rotation=R_all[models[:, 0]].copy(),
        start_translation=X0[models[:, 0]].copy(),
        iterations=iterations,
    )


def _check_models(S: F64, ids: list[str]) -> None:
    """Raise for models whose reduced 5 × 5 normal matrix is singular."""
    d = np.sqrt(np.abs(np.einsum("nii->ni", S)))
    d = np.where(d > 0, d, 1.0)
    Ss = S / d[:, :, None] / d[:, None, :]
    w = np.linalg.eigvalsh(Ss)
    bad = np.flatnonzero(w[:, 0] < 1e-10 * np.maximum(w[:, -1], 1e-300))
    if bad.size:
        names = ", ".join(ids[k] for k in bad[:4])
        raise NotDeterminableError(
            f"the relative orientation of {bad.size} model(s) is not determinable "
            f"(points badly distributed or on a dangerous surface): {names}",
            parameters=[ids[k] for k in bad],
            defect=int(bad.size),
        )


def model_to_object(ms: ModelSet, scale: F64, R: F64, T: F64) -> tuple[F64, F64]:
    """Model points and projection centres transformed to object coordinates.

    ``X = λ_j R_j m + T_j`` per model j.

    Parameters
    ----------
    ms : ModelSet
    scale : ndarray, shape (n,)
    R : ndarray, shape (n, 3, 3)
    T : ndarray, shape (n, 3)

    Returns
    -------
    points : ndarray, shape (k, 3)
        Object coordinates (m) of the model points (rows of ``ms.xyz``).
    centres : ndarray, shape (n, 2, 3)
        Object coordinates of the projection centres.
    """
    j = ms.point_model
    pts = scale[j, None] * np.einsum("nij,nj->ni", R[j], ms.xyz) + T[j]
    cen = scale[:, None, None] * np.einsum("nij,nkj->nki", R, ms.centres) + T[:, None, :]
    return pts, cen
