"""The camera model of :mod:`._lens` evaluated on a block's rays, with only the terms that act.

:func:`orientviz.bundle.model.evaluate_lens` writes the model out in full: every ray
carries all ten parameters and all ten derivatives are formed. In a bundle most of them
are idle — a BAL camera has f, k1, k2 and nothing else, a COLMAP ``SIMPLE_RADIAL``
camera f, k and a held principal point — and only the estimated parameters' derivatives
are needed. :func:`lens_rays` evaluates the same formulas (see :mod:`._lens` for them)

* per group of parameters (one value per group, a scalar where all groups agree),
* without the terms of parameters that are zero and not estimated (a term with a zero
  coefficient adds nothing; ``as`` = ``sk`` = 0 leave the affinity the identity),
* with the derivatives of the estimated parameters only, already in scaled units,
* with the operations in the same order (the same roundings).

Its results equal :func:`evaluate_lens`'s (``tests/bundle/test_lens_rays.py``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
Value = F64 | float | None  # per ray, one for all rays, or idle (zero, not estimated)

__all__ = ["lens_rays"]


def _per_ray(col: F64, ray_group: I64) -> F64 | float:
    """A group parameter per ray: a float when every group has the same value."""
    if np.all(col == col[0]):
        return float(col[0])
    return np.take(col, ray_group)


def _sum(*terms: Value) -> Value:
    """The sum of the terms that are not None (None when all are)."""
    out = None
    for t in terms:
        if t is not None:
            out = t if out is None else out + t
    return out


def _mul(a: Value, b: Value) -> Value:
    """a · b, None when either is idle."""
    return None if a is None or b is None else a * b


def lens_rays(
    kind: str,
    theta: F64,
    ray_group: I64,
    nrm: F64,
    m: F64,
    est: I64,
    scale: F64,
    jac: bool = True,
) -> tuple[F64, F64 | None, F64 | None]:
    """Predicted observations, ∂f/∂n and the design of the estimated parameters.

    Parameters
    ----------
    kind : {"backward", "forward"}
    theta : ndarray, shape (G, 10)
        Physical parameters of each group, in the model's order (:mod:`._lens`).
    ray_group : ndarray of int, shape (n,)
        Group of each ray.
    nrm : ndarray, shape (n, 2)
        Normalised image points −(u, v)/w.
    m : ndarray, shape (n, 2)
        Measured image points, mm.
    est : ndarray of int, shape (k,)
        Positions of the estimated parameters among the ten.
    scale : ndarray, shape (G, k)
        Physical units per scaled unit of the estimated parameters.
    jac : bool
        Also return the derivatives.

    Returns
    -------
    f : ndarray, shape (n, 2)
        Predicted observation, mm (``v = f − m``).
    M : ndarray, shape (n, 2, 2) or None
        ∂f/∂n (mm).
    D : ndarray, shape (n, 2, k) or None
        ∂f/∂(scaled parameters), mm per scaled unit.
    """
    estimated = set(int(j) for j in est)
    nonzero = np.any(theta != 0.0, axis=0).tolist()
    same = np.all(theta == theta[:1], axis=0).tolist()  # one value in every group
    par = []  # per ray (:func:`_per_ray`, from two tests of the whole table)
    for j in range(10):
        if not (j in estimated or nonzero[j]):
            par.append(None)  # idle: zero in every group and not estimated
        else:
            par.append(float(theta[0, j]) if same[j] else np.take(theta[:, j], ray_group))
    c, x0, y0, a, s = par[:5]
    K1, K2, K3 = par[5:8]
    # Brown's P1 (the r² + 2x² term of x) and P2: OpenCV's p2 and p1 in the forward model
    P1, P2 = (par[8], par[9]) if kind == "backward" else (par[9], par[8])
    n = nrm.shape[0]
    # the operations in evaluate_lens's order (the same roundings: the same numbers)
    one_a = 1.0 + a if a is not None else None
    if kind == "backward":
        x = m[:, 0] - x0 if x0 is not None else m[:, 0].copy()
        y = m[:, 1] - y0 if y0 is not None else m[:, 1].copy()
        zx = _sum(x if one_a is None else one_a * x, _mul(s, y))
        zy = y
    else:
        zx, zy = nrm[:, 0].copy(), nrm[:, 1].copy()
    r2 = zx * zx + zy * zy
    rad = _sum(_mul(K1, r2), _mul(_mul(K2, r2), r2), _mul(_mul(_mul(K3, r2), r2), r2))
    # (an estimated parameter is never idle: the terms its derivative needs are formed)
    ux = r2 + 2.0 * zx * zx if P1 is not None else None
    uy = r2 + 2.0 * zy * zy if P2 is not None else None
    dx = _sum(zx, _mul(zx, rad), _mul(P1, ux), _mul(_mul(_mul(2.0, P2), zx), zy))
    dy = _sum(zy, _mul(zy, rad), _mul(P2, uy), _mul(_mul(_mul(2.0, P1), zx), zy))
    f = np.empty((n, 2))
    if kind == "backward":
        f[:, 0] = m[:, 0] + c * nrm[:, 0] - dx
        f[:, 1] = m[:, 1] + c * nrm[:, 1] - dy
    else:
        ax = _sum(dx if one_a is None else one_a * dx, _mul(s, dy))  # [[1 + as, sk], [0, 1]] d
        f[:, 0] = _sum(x0, c * ax)
        f[:, 1] = _sum(y0, c * dy)
    if not jac:
        return f, None, None
    # ∂d/∂z: a11, a12, a21, a22 with g = 2 (K1 + 2 K2 r² + 3 K3 r⁴)
    g = _sum(K1, _mul(_mul(2.0, K2), r2), _mul(_mul(_mul(3.0, K3), r2), r2))
    g = _mul(2.0, g)
    s1 = 1.0 if rad is None else 1.0 + rad
    gx = _mul(g, zx)
    gxy = _mul(gx, zy)
    a11 = _sum(s1, _mul(gx, zx), _mul(_mul(6.0, P1), zx), _mul(_mul(2.0, P2), zy))
    a12 = _sum(gxy, _mul(_mul(2.0, P1), zy), _mul(_mul(2.0, P2), zx))
    a21 = _sum(gxy, _mul(_mul(2.0, P2), zx), _mul(_mul(2.0, P1), zy))
    a22 = _sum(s1, _mul(_mul(g, zy), zy), _mul(_mul(6.0, P2), zy), _mul(_mul(2.0, P1), zx))
    a12 = 0.0 if a12 is None else a12
    a21 = 0.0 if a21 is None else a21
    k = est.size
    M = np.zeros((n, 2, 2))
    D = np.empty((n, 2, k))
    if kind == "backward":
        M[:, 0, 0] = c
        M[:, 1, 1] = c
        cols = {  # ∂f/∂θ = −∂x̄/∂θ (see evaluate_lens)
            0: lambda: (nrm[:, 0], nrm[:, 1]),
            1: lambda: (
                a11 if one_a is None else a11 * one_a,
                a21 if one_a is None else a21 * one_a,
            ),
            2: lambda: (_sum(_mul(a11, s), a12), _sum(_mul(a21, s), a22)),
            3: lambda: (-(a11 * x), -(a21 * x)),
            4: lambda: (-(a11 * y), -(a21 * y)),
            5: lambda: (-(zx * r2), -(zy * r2)),
            6: lambda: (-(zx * r2 * r2), -(zy * r2 * r2)),
            7: lambda: (-(zx * r2**3), -(zy * r2**3)),
            8: lambda: (-ux, -(2.0 * zx * zy)),
            9: lambda: (-(2.0 * zx * zy), -uy),
        }
    else:
        ca = c if one_a is None else c * one_a  # c [[1 + as, sk], [0, 1]]
        cs = _mul(c, s)

        def cA(vx: F64, vy: F64) -> tuple[F64, F64]:
            return _sum(ca * vx, _mul(cs, vy)), c * vy

        M[:, 0, 0], M[:, 1, 0] = cA(a11, a21)
        M[:, 0, 1], M[:, 1, 1] = cA(a12, a22)
        cols = {
            0: lambda: (ax, dy),
            1: lambda: (1.0, 0.0),
            2: lambda: (0.0, 1.0),
            3: lambda: (c * dx, 0.0),
            4: lambda: (c * dy, 0.0),
            5: lambda: cA(zx * r2, zy * r2),
            6: lambda: cA(zx * r2 * r2, zy * r2 * r2),
            7: lambda: cA(zx * r2**3, zy * r2**3),
            8: lambda: cA(2.0 * zx * zy, uy),  # OpenCV's p1: Brown's P2
            9: lambda: cA(ux, 2.0 * zx * zy),  # OpenCV's p2: Brown's P1
        }
    for i, j in enumerate(est.tolist()):
        dfx, dfy = cols[j]()
        sc = _per_ray(scale[:, i], ray_group)
        np.multiply(dfx, sc, out=D[:, 0, i])
        np.multiply(dfy, sc, out=D[:, 1, i])
    return f, M, D
