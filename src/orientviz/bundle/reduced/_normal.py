"""The bundle's normal equations, with the points eliminated (Schur complement).

Per image a 6 × 6 block U, per point unknown a 3 × 3 block V, per ray the coupling
W = J_eᵀ P J_p (6 × 3). Eliminating the points gives the reduced camera system

    S dc = r,   S = U − Σ W V⁻¹ Wᵀ,   r = b_c − Σ W V⁻¹ b_p,

stored by :class:`NormalEquations` as the blocks of S inside its band (the structure is
:class:`orientviz.bundle.reduced.ReducedStructure`) with what the back-substitution of
the points and the precision need. Self-calibration parameters and auxiliary
offsets/drifts border S (:class:`APBorder`, :class:`AuxBorder`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


@dataclass
class APBorder:
    """The border of the additional parameters a (q unknowns), points eliminated.

    Attributes
    ----------
    E_border : BorderE
        E (6m, q) by blocks (:class:`orientviz.bundle.problem._ap_normal.BorderE`).
    F0, F : ndarray, shape (q, q)
        The parameters' block, undamped and damped (diagonal × (1 + λ)).
    ba : ndarray, shape (q,)
        Right-hand side.
    H : ndarray, shape (pairs, k, 3)
        Σ Aᵀ P J_p per (point, group) pair (back-substitution, precision).
    reused : bool
        E and F0 were taken over from the last iteration.
    """

    E_border: object
    F0: F64
    F: F64
    ba: F64
    H: F64
    reused: bool = False
    _E: F64 | None = field(default=None, repr=False)

    @property
    def E(self) -> F64:
        """E as a dense (6m, q) array, formed on first access."""
        if self._E is None:
            self._E = self.E_border.dense()
        return self._E


@dataclass
class AuxBorder:
    """The border of the auxiliary offsets/drifts g (na unknowns), points eliminated.

    Attributes
    ----------
    E : ndarray, shape (6m, na)
        Coupling with the images.
    F : ndarray, shape (na, na)
        Their own block (damped).
    b : ndarray, shape (na,)
        Right-hand side.
    Pg : ndarray, shape (p_var, 3, na)
        Coupling with the points (back-substitution).
    diag : ndarray, shape (na,)
        Undamped diagonal of F.
    Fag : ndarray, shape (q, na) or None
        Coupling with the additional parameters (when they are estimated).
    """

    E: F64
    F: F64
    b: F64
    Pg: F64
    diag: F64
    Fag: F64 | None = None


@dataclass
class NormalEquations:
    """The normal equations of one bundle iteration, points eliminated.

    Attributes
    ----------
    blocks : ndarray or None
        6 × 6 blocks of the reduced camera system S inside its band (None when only the
        rest was formed, for a chord step: :meth:`BundleProblem.chord_normal`).
    rhs : ndarray, shape (6m,)
        Reduced right-hand side r.
    Vinv : ndarray, shape (p_var, 3, 3)
        Inverse point blocks V⁻¹ (damped).
    Wr, Tr : ndarray, shape (n_var, 6, 3)
        W = J_eᵀ P J_p and T = W V⁻¹ of the rays of point unknowns in the order of
        ``rays`` (the track-length order of :mod:`orientviz.bundle.reduced._tracks`).
    rays : ndarray of int, shape (n_var,)
        Observation index of each row of ``Wr``, ``Tr``.
    n_obs : int
        Number of observations (rows of :attr:`W`, :attr:`T`).
    bp : ndarray, shape (p_var, 3)
        Right-hand sides of the points.
    diagU, diagV : ndarray, shapes (m, 6), (p_var, 3)
        Undamped diagonals (the stopping rule's conditional σ = 1/√N_ii).
    diagF : ndarray, shape (q + na,)
        Undamped diagonal of the border (additional parameters, then auxiliary).
    ap : APBorder or None
        The additional parameters' border (None without them or while they are held).
    aux : AuxBorder or None
        The auxiliary offsets' border.
    Fs, Fs_aux : ndarray or None
        The border's Schur complement F − Eᵀ S⁻¹ E when it was formed exactly.
    S : ndarray, shape (6m, 6m), or None
        S as a dense matrix (lower triangle) when it was formed densely
        (:func:`orientviz.bundle.reduced._schur.dense_schur`); the factorisation consumes it.
    ext : object or None
        The system in blocks of an image's exterior and camera unknowns when the cameras
        are per image (:class:`orientviz.bundle.problem._camera_blocks.CameraBlocks`);
        then ``blocks``, ``rhs``, ``Wr``, ``Tr`` are its exterior parts.
    held : HeldDepths or None
        Points held along their weak directions in this step: their block V is
        numerically singular (:func:`~orientviz.bundle.reduced.inv3_held`; ``Vinv`` holds
        V⁺ for them). None: every V inverted.
    """

    blocks: F64 | None
    rhs: F64
    Vinv: F64
    Wr: F64
    Tr: F64
    rays: NDArray[np.int64]
    n_obs: int
    bp: F64
    diagU: F64
    diagV: F64
    diagF: F64 = field(default_factory=lambda: np.zeros(0))
    ap: APBorder | None = None
    aux: AuxBorder | None = None
    Fs: F64 | None = None
    Fs_aux: F64 | None = None
    S: F64 | None = field(default=None, repr=False)
    ext: object | None = field(default=None, repr=False)
    held: object | None = field(default=None, repr=False)
    _W: F64 | None = field(default=None, repr=False)
    _T: F64 | None = field(default=None, repr=False)

    def _by_observation(self, A: F64) -> F64:
        """``A`` (per ray of a point unknown, ``rays`` order) per observation, zero for
        fixed points: ``A`` itself when those rays are all the observations in their own
        order (read only)."""
        r = self.rays
        if r.size == self.n_obs and (r.size == 0 or (r[0] == 0 and r[-1] == r.size - 1)):
            if np.array_equal(r, np.arange(r.size)):
                return A
        out = np.zeros((self.n_obs,) + A.shape[1:])
        out[self.rays] = A
        return out

    @property
    def W(self) -> F64:
        """W = J_eᵀ P J_p per observation (n, 6, 3), zero for fixed points (formed on
        first access)."""
        if self._W is None:
            self._W = self._by_observation(self.Wr)
        return self._W

    @property
    def T(self) -> F64:
        """T = W V⁻¹ per observation (n, 6, 3), zero for fixed points (formed on first
        access)."""
        if self._T is None:
            self._T = self._by_observation(self.Tr)
        return self._T
