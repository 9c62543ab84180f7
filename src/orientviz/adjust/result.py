"""The result of every adjustment in orientviz: :class:`Adjustment`.

Sign convention: residuals are corrections to the observations,
``v = f(x̂) − l`` so that ``l + v = f(x̂)``; σ0 is the a-posteriori standard deviation
of unit weight, ``σ̂0 = sqrt(vᵀPv / r)`` with redundancy ``r = n − u``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
A = TypeVar("A", bound="Adjustment")

#: Default critical value of the normalised residual (Baarda's w-test, α0 = 0.1 %, two-sided).
W_CRITICAL: float = 3.29


@dataclass
class Iteration:
    """One Gauss-Newton/Levenberg-Marquardt step, kept so that it can be replayed.

    Attributes
    ----------
    index : int
        0 for the state before the first step, then 1, 2, …
    x : ndarray
        Parameters *after* this step (flat, same order as ``Adjustment.names``).
    dx : ndarray or None
        The correction applied in this step (None for index 0).
    sigma0 : float
        σ̂0 at ``x`` (a-posteriori, unit weight).
    cost : float
        vᵀPv at ``x``.
    damping : float
        Levenberg-Marquardt λ used for the step (0 for pure Gauss-Newton).
    max_correction : float
        max abs(dx_i) / σ_i, the correction in units of the parameter's standard deviation.
    """

    index: int
    x: F64
    dx: F64 | None
    sigma0: float
    cost: float
    damping: float = 0.0
    max_correction: float = float("nan")


@dataclass
class Adjustment:
    """Estimated parameters with their quality; the common result of all solvers.

    Attributes
    ----------
    x : ndarray, shape (u,)
        Estimated parameters (internal units: m, mm, rad).
    names : sequence of str
        Parameter names, e.g. ``"img3.omega"`` (a list; a bundle's is a
        :class:`~orientviz.bundle.problem.ParameterNames`, formed when first read).
    groups : dict of str to slice
        Named groups of parameters (``"exterior"``, ``"points"``, …) as slices of ``x``.
    sigma0 : float
        σ̂0 (a-posteriori, unit weight; NaN if the redundancy is 0).
    redundancy : int
        n − u (observations, pseudo-observations included, minus unknowns).
    residuals : ndarray, shape (n,)
        v = f(x̂) − l in the observations' units.
    sigma_obs : ndarray, shape (n,)
        A-priori σ of the observations (weights 1/σ²).
    redundancy_numbers : ndarray, shape (n,) or None
        r_i = (Q_vv P)_ii, summing to the redundancy.
    normalized_residuals : ndarray, shape (n,) or None
        w_i = v_i / (σ_i √r_i) (Baarda, a-priori σ0 = 1).
    cofactor : ndarray, shape (u, u) or None
        Q_xx = N⁻¹ for small problems; ``cofactor_groups`` for large ones.
    cofactor_groups : dict
        Diagonal blocks of Q_xx by block name for large problems: a stack of shape
        (k, b, b), e.g. ``"exterior"`` (m, 6, 6) per image and ``"points"`` (p, 3, 3)
        per point, or a square matrix (u_block, u_block).
    converged : bool
        Whether the stopping rule was met.
    reason : str
        Why the iteration stopped, in words.
    history : list of Iteration
        Index 0 is the start; one record per step.
    obs_labels : list of str or None
        A label per observation for reports (e.g. ``"img3/pt12/x"``).
    obs_slices : dict of str to slice
        Named ranges of the observations (e.g. ``"image"``: the image coordinates,
        ``"control"``: pseudo-observations of control points); empty if one kind.
    redundancy_xy : ndarray, shape (n/2,) or None
        For observations that come in (x, y) pairs 2i, 2i+1: the off-diagonal of
        P½ Q_vv P½ per pair (the 2-D tests of :mod:`orientviz.adjust.snooping`).

    A task's own results are typed fields of a subclass (``RelativeResult``,
    ``ResectionResult``, ``BlockAdjustment``, …), built with :meth:`extend`.
    """

    x: F64
    names: Sequence[str]
    sigma0: float
    redundancy: int
    residuals: F64
    sigma_obs: F64
    converged: bool
    reason: str
    history: list[Iteration] = field(default_factory=list)
    groups: dict[str, slice] = field(default_factory=dict)
    redundancy_numbers: F64 | None = None
    normalized_residuals: F64 | None = None
    cofactor: F64 | None = None
    cofactor_groups: dict[str, F64] = field(default_factory=dict)
    obs_labels: list[str] | None = None
    obs_slices: dict[str, slice] = field(default_factory=dict)
    redundancy_xy: F64 | None = None

    def extend(self, cls: type[A], **fields: Any) -> A:
        """This result as ``cls`` (an :class:`Adjustment` with typed fields of its own).

        The fields of ``cls`` that this result has are shared, not copied (``x``,
        ``residuals``, …); ``fields`` set (or override) the others.
        """
        wanted = {f.name for f in dataclasses.fields(cls)}
        own = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name in wanted}
        return cls(**{**own, **fields})

    # ------------------------------------------------------------------ access
    @property
    def iterations(self) -> int:
        """Number of steps taken."""
        return max(len(self.history) - 1, 0)

    @property
    def n_observations(self) -> int:
        return int(self.residuals.shape[0])

    @property
    def n_unknowns(self) -> int:
        return int(self.x.shape[0])

    def index(self, name: str) -> int:
        """Position of parameter ``name`` in ``x``."""
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"unknown parameter {name!r}") from None

    def __getitem__(self, key: str) -> Any:
        """A parameter by name, or a block of parameters by block name."""
        if key in self.groups:
            return self.x[self.groups[key]]
        return self.x[self.index(key)]

    @property
    def params(self) -> dict[str, F64]:
        """Blocks of estimates by name (the whole ``x`` under ``"x"`` if no blocks)."""
        if not self.groups:
            return {"x": self.x}
        return {k: self.x[s] for k, s in self.groups.items()}

    def _sigma0_for_covariance(self, a_posteriori: bool) -> float:
        if a_posteriori and self.redundancy > 0 and np.isfinite(self.sigma0):
            return float(self.sigma0)
        return 1.0

    def covariance(self, a_posteriori: bool = True) -> F64:
        """Covariance σ0² Q_xx of the parameters (dense; small problems only).

        Parameters
        ----------
        a_posteriori : bool, default True
            Scale with σ̂0² (True) or the a-priori σ0² = 1 (False).
        """
        if self.cofactor is None:
            raise ValueError(
                "no dense cofactor matrix was computed for this problem; use cofactor_groups"
            )
        return self._sigma0_for_covariance(a_posteriori) ** 2 * self.cofactor

    def std(self, a_posteriori: bool = True) -> F64:
        """Standard deviations of all parameters (internal units), NaN where not computed."""
        s0 = self._sigma0_for_covariance(a_posteriori)
        if self.cofactor is not None:
            return s0 * np.sqrt(np.clip(np.diag(self.cofactor), 0.0, None))
        out = np.full(self.n_unknowns, np.nan)
        for name, Q in self.cofactor_groups.items():
            if name in self.groups:
                # a square matrix for the whole block, or a stack (k, b, b) of diagonal blocks
                d = np.diag(Q) if Q.ndim == 2 else np.einsum("nii->ni", Q).reshape(-1)
                out[self.groups[name]] = s0 * np.sqrt(np.clip(d, 0.0, None))
        return out

    def correlations(self) -> F64:
        """Correlation matrix ρ_ij = Q_ij / sqrt(Q_ii Q_jj) (dense)."""
        if self.cofactor is None:
            raise ValueError("no dense cofactor matrix was computed for this problem")
        d = np.sqrt(np.clip(np.diag(self.cofactor), 1e-300, None))
        return self.cofactor / np.outer(d, d)

    def high_correlations(self, threshold: float = 0.9) -> list[tuple[str, str, float]]:
        """Pairs of parameters with abs(ρ) ≥ threshold, strongest first."""
        if self.cofactor is None:
            return []
        C = self.correlations()
        i, j = np.triu_indices_from(C, k=1)
        sel = np.abs(C[i, j]) >= threshold
        pairs = sorted(zip(i[sel], j[sel], C[i, j][sel]), key=lambda t: -abs(t[2]))
        return [(self.names[a], self.names[b], float(r)) for a, b, r in pairs]

    def flagged(self, critical: float = W_CRITICAL) -> NDArray[np.int64]:
        """Observations whose absolute normalised residual exceeds ``critical``, largest first."""
        if self.normalized_residuals is None:
            return np.zeros(0, dtype=np.int64)
        w = np.abs(np.nan_to_num(self.normalized_residuals, nan=0.0))
        idx = np.flatnonzero(w > critical)
        return idx[np.argsort(-w[idx])]

    def largest_residuals(self, k: int = 10) -> NDArray[np.int64]:
        """Indices of the k largest absolute normalised (or raw, if none) residuals."""
        w = self.normalized_residuals if self.normalized_residuals is not None else self.residuals
        w = np.abs(np.nan_to_num(w, nan=0.0))
        return np.argsort(-w)[:k]

    def summary(self) -> str:
        """A few lines: σ0, redundancy, iterations, convergence."""
        return (
            f"sigma0 = {self.sigma0:.4g} (a-posteriori, unit weight), redundancy {self.redundancy}, "
            f"{self.iterations} iterations, {'converged' if self.converged else 'NOT converged'}: "
            f"{self.reason}"
        )
