"""A robust run's rays beyond the scale: the joint step's model, and each point's search.

The reweighted model of a ray (its rows scaled by √ρ′, :mod:`._loss`) has the curvature
ρ′ along the ray's misclosure where Σρ has ρ′ + 2sρ″ — for Huber beyond its scale 0.
Two remedies act for the convex losses (Huber, soft-L1):

* :func:`tail_model` — in the run's tail (:data:`orientviz.bundle.loop._steps.ROBUST_TAIL`)
  the joint step's rays beyond the scale with the curvature along their misclosure
  lowered towards the true one, floored (a 2 × 2 per-ray model, Triggs et al. 2000);
* :func:`point_newton` and :func:`point_search` — in every robust step, the correction
  of each point with a ray beyond the scale sought anew.

Why the points: given the images' parameters Σρ is a sum over the points, each a
function of three coordinates. Where most of a point's rays lie beyond the scale — a
two-ray point with one gross error, whose misclosure splits between its two rays; a
point with two gross errors among four rays — Σρ is nearly flat along some direction of
the point until one ray's misclosure reaches the scale, and the reweighted steps creep
along it by a fraction of the way per step (a linear tail of tens of steps; the ratio of
true to modelled curvature of such points goes down to 0.04, while the images'
ratios after the points are eliminated stay ≥ 0.45; measurements: benchmarks/README.md,
issue 28 pt 3). :func:`point_newton` gives each such point its Newton correction under
the true Gauss-Newton model of its rays (the curvature ρ′ + 2sρ″ along each misclosure,
ρ′ across it, plus :data:`NEWTON_FLOOR` times the reweighted model) given the images'
correction of the step, and the fraction of it at which a ray first reaches the scale
from beyond (the end of the flat stretch, linearised). :func:`point_search` ranks per
point the Newton candidates (up to that breakpoint, :data:`FRACTIONS` of it) by the
linearised rays, and keeps the first-ranked one where the true misclosures at the
step's new image parameters give the point's rays (and prior) a lower Σρ than the joint
step's own correction. The points do not interact given the images, so the trial's Σρ
is at most the joint step's: the loop's test of the step is unchanged. The cost: one
evaluation of the active points' rays at both corrections (:func:`ray_misclosures`),
per-ray products over them and a 3 × 3 system per point (by cofactors).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..model import RayProjection, normalised_block
from ..problem import BundleProblem, BundleState
from ._loss import RobustLoss

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: :func:`point_newton`: the true model's curvature plus this times the reweighted one
#: (a point whose rays all lie beyond Huber's scale may have a flat direction).
NEWTON_FLOOR: float = 0.01
#: :func:`point_search`: the fractions of the Newton correction ranked per point beside
#: the first breakpoint (the nearly flat direction ends where a ray's misclosure reaches
#: the scale: the full correction may overshoot it). The breakpoint is ranked wherever it
#: lies along the correction, also far beyond it: the floor (:data:`NEWTON_FLOOR`) makes
#: the model's curvature along a flat direction positive, so the correction may stop short
#: of the breakpoint by any factor, and a point held to a multiple of it creeps along its
#: flat stretch (Σρ linear there) by about the same length in step after step. With no
#: breakpoint (no ray reaches the scale) the full correction is ranked twice.
FRACTIONS: tuple[float, ...] = (1.0, 0.5, 0.25, 0.125)
#: Upper-triangle index pairs of a symmetric 3 × 3 block (6 entries) …
_UPPER = (np.array([0, 0, 0, 1, 1, 2]), np.array([0, 1, 2, 1, 2, 2]))
#: … and the positions of its diagonal among them.
_DIAG = np.array([0, 3, 5])
#: The cofactors c00, c01, c02, c11, c12, c22 of such a block as N[p]·N[q] − N[r]·N[s]
#: (rows p, q, r, s of positions in :data:`_UPPER` order) …
_COF = np.array([[3, 2, 1, 0, 1, 0], [5, 4, 4, 5, 2, 3], [4, 1, 2, 2, 0, 1], [4, 5, 3, 2, 4, 1]])
#: … and the adjugate (3 × 3) from them.
_ADJ = np.array([[0, 1, 2], [1, 3, 4], [2, 4, 5]])


def _solve3(N: F64, g: F64) -> tuple[F64, F64]:
    """x = N⁻¹ g of symmetric 3 × 3 systems given by their upper triangles ``N`` (a, 6),
    in :data:`_UPPER` order, and ``g`` (a, 3) — by cofactors; returns (x (a, 3), det N
    (a,)). Rows with det N = 0 give inf/NaN (the caller tests det)."""
    C = N[:, _COF[0]] * N[:, _COF[1]] - N[:, _COF[2]] * N[:, _COF[3]]  # c00 c01 c02 c11 c12 c22
    det = N[:, 0] * C[:, 0] + N[:, 1] * C[:, 1] + N[:, 2] * C[:, 2]
    adj = C[:, _ADJ]  # (a, 3, 3), the adjugate
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        x = (
            adj[:, :, 0] * g[:, 0, None]
            + adj[:, :, 1] * g[:, 1, None]
            + adj[:, :, 2] * g[:, 2, None]
        )
        x *= inv[:, None]
    return x, det


def _sum3(x: F64) -> F64:
    """x[..., 0] + x[..., 1] + x[..., 2] (the sum over a last axis of length 3, in that order)."""
    return x[..., 0] + x[..., 1] + x[..., 2]


def tail_model(
    prob: BundleProblem, loss: RobustLoss, rw: F64, Je: F64, Jp: F64, scale: F64, floor: float
):
    """The rays beyond the scale with their curvature along the misclosure c·ρ′
    (c = max((ρ′ + 2sρ″)/ρ′, ``floor``)) — rows (I − (1 − √c) r̂r̂ᵀ) P½J (Je, Jp, the
    additional parameters' design) and misclosure P½r/√c: the gradient unchanged.

    ``rw``: P½r with the weights 1/σ·√ρ′ (``scale`` = √ρ′ per ray), ``Je``, ``Jp``
    unweighted (the normal equations weight them by the problem's ray weights). Returns
    (rw, Je, Jp, design to restore after the solve or None); the inputs unchanged when no
    ray lies beyond the scale.
    """
    s = np.einsum("ij,ij->i", rw, rw) / (scale * scale)
    b = loss.scale * loss.scale
    out = np.flatnonzero(s > b)
    if not out.size:
        return rw, Je, Jp, None
    c = np.maximum(loss.along(s[out]), floor)
    sw = prob.obs.weight[out][:, :, None]
    ro = rw[out]
    u = ro / np.sqrt(ro[:, 0] * ro[:, 0] + ro[:, 1] * ro[:, 1])[:, None]  # r̂
    f = (1.0 - np.sqrt(c))[:, None, None] * u[:, :, None]
    u0, u1 = u[:, 0, None], u[:, 1, None]

    def turn(X: F64) -> F64:  # unweighted rows X: (1/sw) (I − f r̂ᵀ) (sw X)
        Y = X * sw
        Y -= f * (u0 * Y[:, 0, :] + u1 * Y[:, 1, :])[:, None, :]
        Y /= sw
        return Y

    rw, Je, Jp = rw.copy(), Je.copy(), Jp.copy()
    Je[out], Jp[out] = turn(Je[out]), turn(Jp[out])
    rw[out] /= np.sqrt(c)[:, None]
    design = None
    if prob.q:  # the additional parameters' design at this linearisation: turned for this solve
        design = prob.run.ap
        A = design.A.copy()
        A[out] = turn(A[out])
        prob.run.ap = design.with_design(A, prob.obs.weight)
    return rw, Je, Jp, design


def _by_point(prob: BundleProblem, X: F64) -> F64:
    """Sums per point unknown (p_var, k) of rows ``X`` (n_var, k) in the tracks' ray order."""
    return np.asarray(prob.reduced.tracks.by_point @ X)


@dataclass
class PointNewton:
    """The Newton corrections of a step's active points and what their search needs.

    Attributes
    ----------
    active : ndarray of int, shape (a,)
        The point unknowns with a ray beyond the loss's scale (the others' reweighted
        model is their true one, for Huber exactly).
    rays : ndarray of int, shape (m,)
        Their rays (positions in the tracks' ray order), point by point.
    obs_rays : ndarray of int, shape (m,)
        The same rays as rows of the problem's observations.
    starts : ndarray of int, shape (a,)
        The first of each active point's rays in ``rays``.
    dp : ndarray, shape (a, 3)
        The Newton corrections, m (0 for a point whose model is singular).
    first : ndarray, shape (a,)
        The fraction of ``dp`` at which a ray of the point first reaches the loss's scale
        from beyond it (linearised; 1 where no ray does).
    owner : ndarray of int, shape (m,)
        The active point (index into ``active``) of each ray.
    r : ndarray, shape (m, 2)
        The rays' misclosures (1/σ-weighted) after the images' correction, linearised.
    up : ndarray, shape (m, 2)
        The rays' 1/σ-weighted change by ``dp`` of their point, linearised (J dp).
    rr, rup, upup : ndarray, shape (m,)
        Per ray r·r, r·up and up·up (the linearised ‖r − α up‖² of any fraction α).
    """

    active: I64
    rays: I64
    obs_rays: I64
    starts: I64
    dp: F64
    first: F64
    owner: I64
    r: F64
    up: F64
    rr: F64
    rup: F64
    upup: F64

    def sums(self, x: F64) -> F64:
        """Sums per active point of per-ray values ``x`` (m, …)."""
        return np.add.reduceat(x, self.starts, axis=0)

    def fractions(self) -> F64:
        """(c, a): the fractions of ``dp`` tried per point — up to the first breakpoint
        (also beyond ``dp``), and :data:`FRACTIONS`."""
        f = np.empty((len(FRACTIONS) + 1, self.first.size))
        f[0] = self.first
        f[1:] = np.asarray(FRACTIONS)[:, None]
        return f


def point_newton(
    prob: BundleProblem,
    loss: RobustLoss,
    base_weight: F64,
    st: BundleState,
    lin: tuple,
    dc: F64,
    da: F64,
    lam: float,
) -> PointNewton | None:
    """The Newton corrections of the points with a ray beyond the loss's scale, given the
    images' correction ``dc`` (m, 6) and the additional parameters' ``da`` (see the
    module docstring); None when no point has such a ray.

    The model: each point's rays' Σρ at the new image parameters with the misclosures
    linearised, r − J δ (r = the misclosure at ``st`` less the images' share of the
    step), to second order in δ with the Gauss-Newton curvature ρ′ + 2sρ″ along r and ρ′
    across it, at r.

    ``lin``: (rw, Je, Jp, scale) at ``st`` — misclosures weighted by 1/σ·√ρ′, the
    unweighted Jacobians, √ρ′ per ray; ``base_weight`` (n, 2): 1/σ of the rays (1/mm);
    ``lam``: the step's damping (λ times the diagonal of the reweighted point blocks is
    added, as in the joint step).
    """
    rw, Je, Jp, scale = lin
    tg, pts = prob.reduced.tracks, prob.points
    bsc = loss.scale * loss.scale
    beyond = np.einsum("ij,ij->i", rw, rw) > bsc * scale * scale  # s > a² (s = ‖rw‖²/ρ′)
    col = prob.obs.column[beyond]  # the point unknown of each such ray (−1: none)
    hit = np.zeros(pts.unknown.size, dtype=bool)
    hit[col[col >= 0]] = True
    active = np.flatnonzero(hit)
    if not active.size:
        return None
    bp = tg.by_point  # its rows list each point's rays (columns: the tracks' ray order)
    counts = np.diff(bp.indptr)
    rays = bp.indices[np.repeat(hit, counts)]
    n_rays = counts[active]
    starts = np.zeros(active.size, dtype=np.intp)
    np.cumsum(n_rays[:-1], out=starts[1:])
    obs_rays = rays if tg.in_order else tg.rays[rays]
    w = base_weight.take(obs_rays, axis=0)
    J = Jp.take(obs_rays, axis=0)
    J *= w[:, :, None]  # (m, 2, 3), weighted by 1/σ
    # the misclosures (1/σ) after the images' correction, linearised: r − u
    u = np.einsum("nij,nj->ni", Je.take(obs_rays, axis=0), dc.take(tg.ray_image[rays], axis=0))
    if prob.q:
        u += (prob.ap.A_csr @ da[: prob.q]).reshape(-1, 2)[obs_rays]
    u *= w
    r = rw.take(obs_rays, axis=0)
    r /= scale.take(obs_rays)[:, None]
    r -= u
    r0, r1 = r[:, 0], r[:, 1]
    s = r0 * r0 + r1 * r1
    rho1, along = loss.newton_terms(s)
    norm = np.sqrt(s)
    rhat = r / np.where(norm > 0, norm, np.inf)[:, None]
    # per ray at the linearised misclosure r: the gradient Jᵀρ′r, the reweighted block
    # ρ′JᵀJ and the part the true model lacks ρ′k (Jᵀr̂)(Jᵀr̂)ᵀ (upper triangles, _UPPER),
    # k = 1 − (ρ′ + 2sρ″)/ρ′ the share of ρ′ the true model lacks along the misclosure
    t = r * rho1[:, None]
    J0, J1 = J[:, 0, :], J[:, 1, :]
    q = J0 * rhat[:, :1] + J1 * rhat[:, 1:]
    a, b = _UPPER
    rows = np.empty((r.shape[0], 15))
    rows[:, :3] = J0 * t[:, :1] + J1 * t[:, 1:]
    rows[:, 3:9] = (J0[:, a] * J0[:, b] + J1[:, a] * J1[:, b]) * rho1[:, None]
    rows[:, 9:] = q[:, a] * q[:, b] * (rho1 * (1.0 - along))[:, None]
    sums = np.add.reduceat(rows, starts, axis=0)
    pw = pts.prior_w[active]
    g = sums[:, :3] + pw * (pts.prior_obs[active] - st.xyz[pts.unknown[active]])
    # N = (1 + floor)·M − Q + λ diag(M), M = the reweighted block + the prior: upper triangle
    M = sums[:, 3:9]
    M[:, _DIAG] += pw
    N = (1.0 + NEWTON_FLOOR) * M - sums[:, 9:]
    N[:, _DIAG] += lam * M[:, _DIAG]
    dp, det = _solve3(N, g)
    # a point whose model is singular (rays without weight, a point at infinity) stays
    tr = N[:, 0] + N[:, 3] + N[:, 5]
    bad = ~(np.abs(det) > 1e-12 * np.maximum(tr, 1e-300) ** 3)
    if bad.any():
        dp[bad] = 0.0
    # the first breakpoint along dp: a ray beyond the scale reaches it (linearised:
    # ‖r − α J dp‖² = a², the smaller root where r·J dp > 0)
    owner = np.repeat(np.arange(active.size), n_rays)
    do = dp.take(owner, axis=0)[:, None, :]
    up = J[:, :, 0] * do[:, :, 0] + J[:, :, 1] * do[:, :, 1] + J[:, :, 2] * do[:, :, 2]
    u0, u1 = up[:, 0], up[:, 1]
    A2 = u0 * u0 + u1 * u1
    B = r0 * u0 + r1 * u1
    C = s - bsc
    disc = B * B - A2 * C
    ok = (C > 0) & (B > 0) & (disc >= 0) & (A2 > 0)
    alpha = np.full(r.shape[0], np.inf)
    alpha[ok] = (B[ok] - np.sqrt(disc[ok])) / A2[ok]
    first = np.minimum.reduceat(alpha, starts)
    first = np.where(np.isfinite(first), first, 1.0)
    return PointNewton(active, rays, obs_rays, starts, dp, first, owner, r, up, s, B, A2)


def point_search(
    prob: BundleProblem,
    loss: RobustLoss,
    base_weight: F64,
    st: BundleState,
    dc: F64,
    da: F64,
    dp: F64,
    newton: PointNewton,
    images: tuple[F64, F64] | None = None,
) -> tuple[F64, int, float]:
    """Per point the correction with the lowest Σρ of its rays (and prior) at the new
    image parameters: ``dp`` (the joint step's) or, for an active point, the candidate of
    ``newton`` that its linearised rays rank first (:meth:`PointNewton.fractions`) —
    the choice between the two made by their true misclosures; returns (corrections
    (p_var, 3) m, number of points not at ``dp``, the decrease of Σρ (+ the points'
    priors' vᵀPv) against the joint step's correction, ≥ 0). Sets the problem's ray
    weights to ``base_weight`` (1/σ). ``images``: (X0, angles) of the step's new image
    parameters, st.X0 + dc[:, :3] and st.angles + dc[:, 3:] (formed here without); a
    pinhole's table of them is left in ``prob.run.image_table`` for the evaluation of
    the iterate made of these arrays."""
    pts = prob.points
    act, owner = newton.active, newton.owner
    pw = pts.prior_w[act]
    # points with a prior: its vᵀPv joins their Σρ
    held = np.flatnonzero((pw[:, 0] != 0) | (pw[:, 1] != 0) | (pw[:, 2] != 0))
    f = newton.fractions()  # (c, a)
    # the linearised rays' Σρ of each point at each fraction of dp: ‖r − f·J dp‖²
    fo = f[:, owner]  # (c, m)
    s = newton.rr - 2.0 * fo * newton.rup + fo * fo * newton.upup
    lin = np.add.reduceat(loss.rho(np.maximum(s, 0.0)), newton.starts, axis=1)
    if held.size:
        x0p = pts.prior_obs[act[held]] - st.xyz[pts.unknown[act[held]]]
        pwh = pw[held]
        v = x0p[None] - f[:, held, None] * newton.dp[held][None]
        lin[:, held] += _sum3(pwh * v * v)
    lin[~np.isfinite(lin)] = np.inf
    best = f[np.argmin(lin, axis=0), np.arange(act.size)]
    cand = (dp[act], best[:, None] * newton.dp)  # the joint step's and the ranked one
    prob.obs.weight[...] = base_weight
    # the true misclosures of the active points' rays at both corrections, in one pass
    rays = newton.obs_rays
    xyz = st.xyz.take(prob.obs.point[rays], axis=0)
    both = np.concatenate((rays, rays))
    at = np.empty((2 * rays.size, 3))
    np.add(xyz, cand[0].take(owner, axis=0), out=at[: rays.size])
    np.add(xyz, cand[1].take(owner, axis=0), out=at[rays.size :])
    X0, angles = (st.X0 + dc[:, :3], st.angles + dc[:, 3:]) if images is None else images
    rw = ray_misclosures(prob, X0, angles, st.ap + da, both, at, keep=True)
    rho = loss.rho(rw[:, 0] * rw[:, 0] + rw[:, 1] * rw[:, 1])
    true = np.add.reduceat(rho.reshape(2, -1), newton.starts, axis=1)  # (2, a)
    for k, d in enumerate(cand) if held.size else ():
        vv = x0p - d[held]
        true[k, held] += _sum3(pwh * vv * vv)
    better = true[1] < true[0]  # ties and NaN: the joint step's own
    out = dp.copy()
    out[act[better]] = cand[1][better]
    gain = float(np.sum(true[0][better] - true[1][better]))
    return out, int(np.count_nonzero(better)), gain


def ray_misclosures(
    prob: BundleProblem,
    X0: F64,
    angles: F64,
    ap: F64,
    obs_rays: I64,
    xyz: F64,
    keep: bool = False,
) -> F64:
    """Misclosures (k, 2) weighted by the problem's ray weights of the observations
    ``obs_rays`` (k,) with their points at ``xyz`` (k, 3) m, given the images' ``X0`` (m),
    ``angles`` (rad) and the additional parameters ``ap``: the rows ``obs_rays`` of
    :meth:`BundleProblem.residuals` at that state, evaluated for these rays only (an
    observation may appear more than once, with other points). Not for auxiliary data.
    ``keep``: a pinhole's per-image table of ``X0``, ``angles`` is kept for the
    evaluation of an iterate made of these arrays (``prob.run.image_table``)."""
    obs = prob.obs
    img = obs.image[obs_rays]
    seq = prob.block.sequence
    if prob.ap.lens is not None:
        nrm = normalised_block(X0, angles, img, xyz, seq, False)[0]
        f = prob.ap.lens.evaluate(ap, prob.ap.group[img], nrm, obs.xy[obs_rays], False)[0]
    else:
        io = prob.interior
        proj = RayProjection(X0, angles, io.c, io.x0, io.y0, img, xyz, seq)
        if keep:
            prob.run.image_table = (X0, angles, proj.table)
        f = proj.xy
        if prob.q:
            f = f + (prob.ap.A_csr @ ap).reshape(-1, 2)[obs_rays]
    return (obs.xy[obs_rays] - f) * obs.weight[obs_rays]
