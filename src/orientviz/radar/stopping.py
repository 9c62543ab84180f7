"""A stopping rule reconstructed from Geier's (1973) Fig. 8 — not a rule the paper states.

The paper does not describe when its iteration stopped. This rule was reconstructed by
matching the printed calibration and exterior-orientation numbers of Fig. 8
(docs/geier_conventions.md §6); it is therefore *fitted*, and ``orientviz reproduce
geier`` labels the rows it was fitted on so. The rule: after each solution of the
linearised system, compare the mean error of unit weight of the *linearised* problem, m0 = sqrt(vᵀv / r) with v = A·Δx − (l − f), with that of
the previous iteration:

1. if m0 changed by less than ``rel`` (0.1 %) of itself, the correction is applied and
   the iteration ends (converged);
2. if m0 grew, the correction is *not* applied and the iteration ends with the previous
   estimate (the new step made the fit no better);
3. otherwise the correction is applied and the next iteration follows.

Rule 2 is what leaves the calibration of the concave cylinders (Fig. 8, columns 8 and
10) at the state after the first Gauss-Newton step. The rule is an option
(``stopping="geier"``) of the radar tasks; orientviz's default iterates to convergence.

This module uses the engine only for the final precision (covariance, redundancy
numbers) at the adopted estimate; the result is an
:class:`~orientviz.adjust.result.Adjustment` with the rule's own two fields
(:class:`GeierRun`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..adjust import Adjustment, Iteration, gauss_newton
from ..adjust.rank import raise_if_singular

F64 = NDArray[np.float64]

#: Relative change of the linearised m0 below which the iteration counts as converged.
GEIER_RELATIVE_M0: float = 1e-3


@dataclass
class GeierRun(Adjustment):
    """An adjustment stopped by the rule reconstructed from Fig. 8.

    Attributes
    ----------
    m0_linearized : float
        The linearised m0 of the last system solved (the value the paper prints), in the
        observations' unit for σ = 1.
    rule : str
        Which branch of the rule ended the iteration, in words.
    """

    m0_linearized: float = float("nan")
    rule: str = ""


def geier_iterate(
    equations: Callable[[F64], tuple[F64, F64]],
    u0: F64,
    l: F64,
    sigma: float | F64 = 1.0,
    *,
    names: list[str],
    rel: float = GEIER_RELATIVE_M0,
    max_iter: int = 30,
    context: str = "",
    **engine,
) -> GeierRun:
    """Gauss-Newton with the stopping rule reconstructed from Fig. 8 (module docstring).

    Parameters
    ----------
    equations : callable
        ``equations(u) -> (f, J)`` as for :func:`~orientviz.adjust.gauss_newton`.
    u0 : ndarray
        Start values.
    l : ndarray
        Observations.
    sigma : float or ndarray
        A-priori σ of the observations.
    names : list of str
        Parameter names.
    rel : float
        Relative change of the linearised m0 that counts as converged.
    max_iter : int
        Maximum number of linear solutions.
    context : str
        Prefix for error messages.
    **engine
        Passed to the engine for the final precision (e.g. ``obs_labels``).

    Returns
    -------
    GeierRun
        At the adopted estimate. ``history`` holds one record per *applied* step;
        ``m0_linearized`` is the linearised m0 of the last system solved (the value the
        paper prints), ``rule`` says which branch ended the iteration.
    """
    u = np.asarray(u0, float).copy()
    l = np.asarray(l, float)
    s = np.broadcast_to(np.asarray(sigma, float), l.shape)
    p = 1.0 / s**2
    dof = l.size - u.size
    m0_old = np.inf
    f, J = equations(u)
    r = l - f
    history = [Iteration(0, u.copy(), None, _m0(r, p, dof), float(r @ (p * r)))]
    rule, m0_lin = f"reached the maximum of {max_iter} iterations", float("nan")
    converged = False
    for k in range(1, max_iter + 1):
        N = (J.T * p) @ J
        if k == 1:
            raise_if_singular(N, names, context)
        dx = np.linalg.solve(N, (J.T * p) @ r)
        v = J @ dx - r
        m0_lin = _m0(v, p, dof)
        if abs(m0_lin - m0_old) < rel * m0_lin:
            u = u + dx
            rule, converged = f"m0 changed by less than {rel:g} of itself in iteration {k}", True
        elif m0_lin > m0_old:
            rule = f"m0 grew in iteration {k}: its correction was not applied"
            converged = True
        else:
            u = u + dx
        if converged:
            if u is not history[-1].x:
                f, J = equations(u)
                r = l - f
            if "not applied" not in rule:
                history.append(Iteration(k, u.copy(), dx, _m0(r, p, dof), float(r @ (p * r))))
            break
        f, J = equations(u)
        r = l - f
        history.append(Iteration(k, u.copy(), dx, _m0(r, p, dof), float(r @ (p * r))))
        m0_old = m0_lin
    res = gauss_newton(equations, u, l, sigma, names=names, max_iter=0, context=context, **engine)
    res.history = history
    res.converged = converged
    res.reason = f"stopping rule reconstructed from Geier's Fig. 8: {rule}"
    return res.extend(GeierRun, m0_linearized=m0_lin, rule=rule)


def _m0(v: F64, p: F64, dof: int) -> float:
    return float(np.sqrt(v @ (p * v) / dof)) if dof > 0 else float("nan")
