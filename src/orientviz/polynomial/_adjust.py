"""Polynomial strip and block adjustment (Ackermann 1974, Table 1, method 1).

1. **Strip formation** (:func:`form_strips`): the models of a strip
   (:func:`~.model_formation.form_models`, dependent pairs formed by least squares on
   the image coordinates in this package — the same five elements by, bz, ω, φ, κ as
   :func:`orientviz.orientation.relative.relative_orientation`) are chained: model j+1
   takes over the orientation of its left image from model j (successive relative
   orientation, rotations multiply) and its origin from their common projection centre;
   its scale is transferred from the common points (least squares on the vectors from the
   common projection centre). The strip frame is the frame of the strip's first model.
2. Each strip is brought near the object frame by one 3D similarity to the block's
   approximate point coordinates (closed form, :func:`orientviz.orientation.absolute.
   similarity_closed_form`).
3. **Polynomial block adjustment** (:func:`polynomial_adjust`): per strip j a conformal
   polynomial of degree d in planimetry and a polynomial in height correct the strip
   coordinates (x, y, z) (in m, reduced to the strip centre, u = x/L, v = y/L with
   L = 1000 m)::

       X + iY = x + iy + L · Σ_k (a_kj + i b_kj) (u + iv)^k,   k = 0 … d_xy
       Z      = z + L · (Σ_k c_kj u^k + v · Σ_k e_kj u^k),      k = 0 … d_z (e: … d_z − 1)

   The corrections of all strips and the coordinates of the tie points are estimated
   together from the strip coordinates of all points (shared points tie neighbouring
   strips) and the control; planimetry and height are two linear adjustments. Expanding
   the complex product gives Table 1's rows a0 + a1 x − b1 y + a2 x² − 2 b2 x y + …
   (Table 1 drops the y² terms of the second degree, which are small in a long strip).

It is an interpolation method: the polynomials model the smooth accumulated errors of
strip formation, not their causes; Ackermann (§21) finds it equivalent to the rigorous
methods for single strips with minimal control, clearly worse for blocks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, Block, BlockAdjustment, check_points_of
from ..errors import InputError, NotDeterminableError
from ..orientation.absolute import similarity_closed_form
from ..rotation import matrix_from_opk
from ..stereo_models import ModelSet, form_models, solve_rows

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
#: Length unit of the polynomial variables u, v (m).
L_M: float = 1000.0
#: A part is called weakly determined when the largest σ of its corrections at the strips'
#: points exceeds this many σ of a strip coordinate (the polynomials extrapolate).
WEAK_FACTOR: float = 100.0


@dataclass
class PolynomialResult(BlockAdjustment):
    """The result of :func:`polynomial_adjust` (``exterior`` is None: no image orientation).

    Attributes
    ----------
    strips : list of Strip
        The strips that were adjusted.
    degree_xy, degree_z : int
        Degrees of the planimetric and height polynomials.
    sigma0_xy, sigma0_z : float
        σ̂0 of the planimetric and height adjustments.
    sigma_strip : tuple of float
        A-priori σ of strip coordinates (planimetry, height), m.
    point_index : ndarray of int
        Block index of each point unknown (the ``"points"`` block of x).
    sigma_correction : dict of str to tuple of float
        ``"planimetry"`` and ``"height"`` → (median, largest) a-priori σ of the polynomial
        corrections at the strips' own points, m (from the cofactors of the strip
        coefficients, the tie points eliminated). Far above σ of a strip coordinate
        (:attr:`sigma_strip`) means the control and the ties barely determine the
        polynomials there: the corrections extrapolate.
    weak : list of str
        One sentence per part whose largest σ of the correction exceeds
        :data:`WEAK_FACTOR` times σ of a strip coordinate (empty when none does).
    """

    strips: list = field(default_factory=list)
    degree_xy: int = 0
    degree_z: int = 0
    sigma0_xy: float = math.nan
    sigma0_z: float = math.nan
    sigma_strip: tuple[float, float] = (math.nan, math.nan)
    point_index: I64 | None = None
    sigma_correction: dict = field(default_factory=dict)
    weak: list = field(default_factory=list)


@dataclass
class Strip:
    """A strip formed from its models.

    Attributes
    ----------
    index : int
        Strip number (``images.strip``).
    images : ndarray of int
        Images in flight order.
    point : ndarray of int, shape (k,)
        Block points of the strip.
    xyz : ndarray, shape (k, 3)
        Their strip coordinates (m), mean over the models of the strip.
    centres : ndarray, shape (len(images), 3)
        Strip coordinates of the projection centres.
    scale : ndarray, shape (n_models,)
        Transferred scale of each model (1 for the first).
    """

    index: int
    images: I64
    point: I64
    xyz: F64
    centres: F64
    scale: F64


def _chain(ms: ModelSet, mods: I64, block: Block) -> Strip:
    """Chain the models ``mods`` (flight order) of one strip."""
    R, T, lam = np.eye(3), np.zeros(3), 1.0
    pts_all, xyz_all, scales = [], [], []
    centres = [np.zeros(3)]
    prev_pts, prev_xyz = None, None
    for n, jm in enumerate(mods):
        rows = ms.point_model == jm
        p, m = ms.point[rows], ms.xyz[rows]
        if n > 0:
            jp = mods[n - 1]
            R = R @ matrix_from_opk(*ms.elements[jp, 2:])
            T = centres[-1]
            common, ia, ib = np.intersect1d(prev_pts, p, return_indices=True)
            if common.size == 0:
                raise NotDeterminableError(
                    f"strip {int(ms.strip[jm])} breaks between models {ms.ids[jp]} and "
                    f"{ms.ids[jm]}: no common points for the scale transfer",
                    parameters=[ms.ids[jm]],
                )
            a = prev_xyz[ia] - T
            b = m[ib] @ R.T
            lam = float(np.sum(a * b) / np.sum(b * b))
        xyz = lam * m @ R.T + T
        centres.append(lam * R @ ms.centres[jm, 1] + T)
        pts_all.append(p)
        xyz_all.append(xyz)
        scales.append(lam)
        prev_pts, prev_xyz = p, xyz
    p = np.concatenate(pts_all)
    x = np.concatenate(xyz_all)
    up, inv = np.unique(p, return_inverse=True)
    cnt = np.bincount(inv).astype(float)
    mean = np.column_stack([np.bincount(inv, x[:, c]) / cnt for c in range(3)])
    images = np.concatenate([[ms.models[mods[0], 0]], ms.models[mods, 1]])
    return Strip(int(ms.strip[mods[0]]), images, up, mean, np.array(centres), np.array(scales))


def form_strips(block: Block, models: ModelSet | None = None) -> list[Strip]:
    """Strip formation by successive relative orientation and scale transfer.

    Parameters
    ----------
    block : Block
        Observations and approximate orientations, ``images.strip`` set.
    models : ModelSet, optional
        Models already formed (default: :func:`form_models`).

    Returns
    -------
    list of Strip
    """
    ms = models if models is not None else form_models(block)
    strips = []
    for s in np.unique(ms.strip):
        mods = np.flatnonzero(ms.strip == s)
        mods = mods[np.argsort(ms.models[mods, 0], kind="stable")]
        strips.append(_chain(ms, mods, block))
    return strips


def _term_words(part: str, degree: int) -> list[str]:
    """What each coefficient of a strip's polynomial does, in words (for messages).

    Planimetry: a0, b0, a1, b1, … of Σ (a_k + i b_k)(u + iv)^k; height: c0 … c_d,
    e0 … e_{d−1} of Σ c_k u^k + v Σ e_k u^k (the module docstring's formulas).
    """
    if part == "planimetry":
        words = ["shift X", "shift Y", "scale", "rotation"]
        for k in range(2, degree + 1):
            words += [f"planimetric term of degree {k} (a{k})", f"planimetric term of degree {k} (b{k})"]  # fmt: skip
        return words[: 2 * (degree + 1)]
    words = ["height shift", "tilt along the strip"][: degree + 1]
    words += [f"height bending of degree {k} along the strip (c{k})" for k in range(2, degree + 1)]
    words += ["tilt across the strip", *(f"twist of degree {k} (e{k})" for k in range(1, degree))][:degree]  # fmt: skip
    return words


def _planimetric_terms(u: F64, v: F64, d: int) -> tuple[F64, F64]:
    """Rows of X and Y for the coefficients (a0, b0, a1, b1, …) of Σ (a_k + i b_k) w^k."""
    w = u + 1j * v
    pw = np.stack([w**k for k in range(d + 1)], axis=1)
    p, q = pw.real, pw.imag
    JX = np.empty((u.size, 2 * (d + 1)))
    JY = np.empty_like(JX)
    JX[:, 0::2], JX[:, 1::2] = p, -q
    JY[:, 0::2], JY[:, 1::2] = q, p
    return JX * L_M, JY * L_M


def _height_terms(u: F64, v: F64, d: int) -> F64:
    cols = [u**k for k in range(d + 1)] + [v * u**k for k in range(d)]
    return np.column_stack(cols) * L_M


def polynomial_adjust(
    block: Block,
    *,
    degree_xy: int = 2,
    degree_z: int = 2,
    strips: list[Strip] | None = None,
    sigma_strip: tuple[float, float] | None = None,
    iterations: int = 3,
) -> PolynomialResult:
    """Polynomial block adjustment of the strips of a block (see the module docstring).

    Parameters
    ----------
    block : Block
        Observations, approximate orientations and points, control (fixed; σ ignored).
    degree_xy, degree_z : int
        Degrees of the conformal planimetric and of the height polynomials (0 … 4).
    strips : list of Strip, optional
        Strips already formed (default :func:`form_strips`).
    sigma_strip : tuple of float, optional
        σ of strip coordinates (planimetry, height) in m; default σ_image · m_B and
        √2 · H/B times that (as for independent models).
    iterations : int
        Passes: the first brings the strips near the object frame by a similarity to the
        block's approximate points, later ones by a similarity to the adjusted points of
        the previous pass (this removes the second-order effect of the tilts on
        planimetry, which the separate planimetric and height polynomials ignore).

    Returns
    -------
    Adjustment
        ``x``: planimetric coefficients (a0, b0, a1, b1, …) of every strip, then the
        height coefficients (c0 … c_d, e0 … e_{d−1}), then X, Y, Z of the tie points;
        residuals v = polynomial(strip coordinates) − X (m). A :class:`PolynomialResult`:
        ``points`` (p, 3): adjusted coordinates of all block points (check points from
        their strip coordinates; NaN if in no strip); ``check_points``, ``strips``,
        ``sigma0_xy``, ``sigma0_z``.

    Raises
    ------
    InputError
        For degrees outside 0 … 4, or no strip of at least two images.
    NotDeterminableError
        For a strip that breaks apart or polynomials not determined by control and ties.
    """
    for name, d in (("degree_xy", degree_xy), ("degree_z", degree_z)):
        if not 0 <= int(d) <= 4:
            raise InputError(f"{name}: expected a polynomial degree 0 … 4, got {d}")
    if strips is None:
        strip = block.images.strip
        if not np.any(np.bincount(strip[strip >= 0], minlength=1) >= 2):
            raise InputError(
                "the polynomial method needs strips: give the images a strip number "
                "(images[].strip), at least two images in a strip (consecutive images form "
                "its models)"
            )
        ms = form_models(block)
        strips = form_strips(block, ms)
        base = float(np.median(ms.centres[:, 1, 0]))
    else:
        base = float(np.median(np.linalg.norm(np.diff(strips[0].centres, axis=0), axis=1)))
    target = block.points.xyz
    for _ in range(max(1, int(iterations))):
        out = _adjust_once(block, strips, target, degree_xy, degree_z, sigma_strip, base)
        target = np.where(np.isnan(out.points), block.points.xyz, out.points)
    return out


def _adjust_once(block, strips, target, degree_xy, degree_z, sigma_strip, base) -> PolynomialResult:
    pts = block.points
    # strip → near the object frame (closed-form similarity to the target coordinates)
    rows_s, rows_p, rows_x = [], [], []
    for k, st in enumerate(strips):
        tr = similarity_closed_form(st.xyz, target[st.point])
        rows_s.append(np.full(st.point.size, k))
        rows_p.append(st.point)
        rows_x.append(tr.apply(st.xyz))
    j, pt, x = np.concatenate(rows_s), np.concatenate(rows_p), np.concatenate(rows_x)
    ns = len(strips)
    cen = np.column_stack([np.bincount(j, x[:, c]) / np.bincount(j) for c in range(2)])
    u, v = (x[:, 0] - cen[j, 0]) / L_M, (x[:, 1] - cen[j, 1]) / L_M
    used = pts.role[pt] != CHECK
    ctrl = (pts.role == CONTROL)[:, None] & ~np.isnan(pts.xyz_known)
    if sigma_strip is None:
        H = float(np.median(block.images.X0[:, 2]) - np.median(pts.xyz[:, 2]))
        s_xy = (
            float(np.median(block.observations.sigma))
            / 1000.0
            * H
            / (np.median(block.cameras.c) / 1000.0)
        )
        sigma_strip = (s_xy, math.sqrt(2.0) * H / base * s_xy)
    s_xy, s_z = sigma_strip
    tie = np.unique(pt[used])
    X = np.zeros((block.n_points, 3))
    cnt = np.bincount(pt[used], minlength=block.n_points).astype(float)
    for c in range(3):
        X[:, c] = np.bincount(pt[used], x[used, c], minlength=block.n_points) / np.maximum(cnt, 1)
    X = np.where(ctrl, np.nan_to_num(pts.xyz_known), X)
    results = {}
    sigma_corr: dict[str, tuple[float, float]] = {}
    weak: list[str] = []
    for part, coords in (("planimetry", (0, 1)), ("height", (2,))):
        free = np.zeros((block.n_points, len(coords)), bool)
        free[tie] = ~ctrl[tie][:, list(coords)]
        sc = np.full(free.shape, -1, np.int64)
        sc[free] = np.arange(int(free.sum()))
        uj, pj, jj, xj = u[used], pt[used], j[used], x[used]
        if part == "planimetry":
            JX, JY = _planimetric_terms(uj, v[used], degree_xy)
            J = np.stack([JX, JY], axis=1).reshape(-1, JX.shape[1])
            r = (xj[:, :2] - X[pj, :2]).ravel()
            rows, rs, w = np.repeat(jj, 2), sc[pj].ravel(), np.full(r.size, 1 / s_xy**2)
        else:
            J = _height_terms(uj, v[used], degree_z)
            r = xj[:, 2] - X[pj, 2]
            rows, rs, w = jj, sc[pj, 0], np.full(r.size, 1 / s_z**2)
        npar = J.shape[1]
        terms = _term_words(part, degree_xy if part == "planimetry" else degree_z)
        names = [f"strip{strips[k].index}.{part}.{t}" for k in range(ns) for t in terms]
        try:
            sol = solve_rows(
                rows, J, rs, w, r, ns, int(free.sum()), names=names, context=f"polynomial {part}"
            )
        except NotDeterminableError as exc:
            degree = "degree_xy" if part == "planimetry" else "degree_z"
            raise NotDeterminableError(
                f"{exc} — the control points and the tie points shared with other strips do "
                f"not determine the {part} polynomial of these strips: give more control there "
                f"or a lower {degree}",
                parameters=exc.parameters,
                defect=exc.defect,
            ) from None
        sig = _correction_sigma(sol.factor, J, rows, ns, npar)
        s_row = s_xy if part == "planimetry" else s_z
        sigma_corr[part] = (float(np.median(sig)), float(sig.max()))
        if sig.max() > WEAK_FACTOR * s_row:
            degree = "degree_xy" if part == "planimetry" else "degree_z"
            weak.append(
                f"the {part} polynomials are barely determined by the control and the ties: "
                f"σ of their correction reaches {sig.max():.3g} m ({sig.max() / s_row:.0f}× a "
                f"strip coordinate's σ); give more control there or a lower {degree}"
            )
        for i, c in enumerate(coords):
            has = sc[:, i] >= 0
            X[has, c] += sol.dX[sc[has, i]]
        res_rows = (
            r
            + np.sum(J * sol.dtheta[rows], axis=1)
            - np.where(rs >= 0, sol.dX[np.maximum(rs, 0)], 0.0)
        )
        results[part] = (sol.dtheta, res_rows, w, npar, names, int(free.sum()))
    # adjusted coordinates of all points (check points from their corrected strip coordinates)
    th_xy, th_z = results["planimetry"][0], results["height"][0]
    JX, JY = _planimetric_terms(u, v, degree_xy)
    corr = np.column_stack([
        x[:, 0] + np.sum(JX * th_xy[j], axis=1),
        x[:, 1] + np.sum(JY * th_xy[j], axis=1),
        x[:, 2] + np.sum(_height_terms(u, v, degree_z) * th_z[j], axis=1),
    ])  # fmt: skip
    xyz = np.full((block.n_points, 3), np.nan)
    allc = np.bincount(pt, minlength=block.n_points).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        for c in range(3):
            xyz[:, c] = np.bincount(pt, corr[:, c], minlength=block.n_points) / allc
    xyz[tie] = X[tie]
    resid = np.concatenate([results["planimetry"][1], results["height"][1]])
    wts = np.concatenate([results["planimetry"][2], results["height"][2]])
    n_unknown = sum(ns * results[k][3] + results[k][5] for k in results)
    dof = resid.size - n_unknown
    s0 = math.sqrt(float(np.sum(wts * resid**2)) / dof) if dof > 0 else float("nan")
    s0_part = {
        k: math.sqrt(float(np.sum(results[k][2] * results[k][1] ** 2)) / max(results[k][1].size - ns * results[k][3] - results[k][5], 1))
        for k in results
    }  # fmt: skip
    n1, n2 = ns * results["planimetry"][3], ns * results["height"][3]
    xvec = np.concatenate([th_xy.ravel(), th_z.ravel(), X[tie].ravel()])
    names = (
        results["planimetry"][4]
        + results["height"][4]
        + [f"{pts.ids[i]}.{c}" for i in tie for c in "XYZ"]
    )
    return PolynomialResult(
        x=xvec, names=names, sigma0=s0, redundancy=int(dof), residuals=resid,
        sigma_obs=1.0 / np.sqrt(wts), converged=True,
        reason="; ".join(["linear adjustments (one step each)", *weak]),
        history=[], groups={"planimetry": slice(0, n1), "height": slice(n1, n1 + n2), "points": slice(n1 + n2, xvec.size)},
        points=xyz, check_points=check_points_of(block, xyz), strips=strips, degree_xy=degree_xy,
        degree_z=degree_z, sigma0_xy=s0_part["planimetry"], sigma0_z=s0_part["height"],
        sigma_strip=(s_xy, s_z), point_index=tie, adjusted=(int(resid.size), int(n_unknown)),
        sigma_correction=sigma_corr, weak=weak,
    )  # fmt: skip


def _correction_sigma(factor, J: F64, rows: I64, ns: int, npar: int) -> F64:
    """σ (m) of the polynomial correction ``J_i · θ_j`` of each row, from Q_θθ of the strips.

    Q_θθ is the inverse of the reduced normal matrix (tie points eliminated), so the
    values include the uncertainty the tie points carry; weights 1/σ² make them metres.
    """
    Q = factor.solve(np.eye(ns * npar)).reshape(ns, npar, ns, npar)
    Qd = Q[np.arange(ns), :, np.arange(ns), :]  # (ns, npar, npar) per-strip blocks
    var = np.einsum("na,nab,nb->n", J, Qd[rows], J)
    return np.sqrt(np.maximum(var, 0.0))
