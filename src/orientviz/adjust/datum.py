"""The datum of a free network: inner constraints and the S-transformation.

A network of points observed only among themselves (distances, angles, image rays)
fixes its *shape* but not where it lies: the normal matrix N = AᵀPA is singular, with
A G = 0 for the columns of G that move the whole network without changing any
observation — shifts, rotations (and a scale, if nothing measures length). The datum is
a choice of d = rank defect conditions on the unknowns. Writing E for a diagonal 0/1
selection of the *datum points*,

    Gᵀ E Δx = 0           (partial inner constraints; E = I: inner constraints)

and solving the bordered system [[N, E G], [Gᵀ E, 0]] gives the solution of least
Σ Δx² over the datum points (:func:`datum_solve`); with E = I its cofactor matrix is the
pseudo-inverse N⁺ (the least trace of all datums). One datum goes into another by the
**S-transformation** (Baarda)

    S = I − G (Gᵀ E G)⁻¹ Gᵀ E,    x_B = S x_A,   Q_B = S Q_A Sᵀ,

(:func:`s_transformation`) without a new adjustment. Quantities that do not depend on
the datum (distances, angles, the residuals, σ̂0) are *estimable*; coordinates and their
ellipses are not.

Units: whatever the coordinates are in (m); G's rotation and scale columns are formed
from coordinates centred on the datum points and scaled to unit length.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

F64 = NDArray[np.float64]


def helmert_basis(points: ArrayLike, *, scale: bool = False) -> F64:
    """Null-space basis G of a free network of 2-D or 3-D points (unknowns x1, y1, x2, …).

    Parameters
    ----------
    points : array_like, shape (p, 2) or (p, 3)
        Approximate coordinates, m.
    scale : bool
        Add the scale column (networks without any length observation).

    Returns
    -------
    ndarray, shape (p·dim, d)
        Columns: the shifts, the rotation(s) (2-D: about the vertical; 3-D: about X, Y,
        Z), optionally the scale; each of unit length. d = 3 (2-D) or 6 (3-D), +1 with scale.
    """
    X = np.asarray(points, dtype=float)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise InputError(f"expected points of shape (p, 2) or (p, 3), got {X.shape}")
    p, dim = X.shape
    Xc = X - X.mean(axis=0)
    cols = []
    for k in range(dim):
        t = np.zeros((p, dim))
        t[:, k] = 1.0
        cols.append(t)
    if dim == 2:
        cols.append(np.column_stack([-Xc[:, 1], Xc[:, 0]]))
    else:
        for k in range(3):  # rotation about axis k: ω × X
            e = np.zeros(3)
            e[k] = 1.0
            cols.append(np.cross(e, Xc))
    if scale:
        cols.append(Xc.copy())
    G = np.column_stack([c.reshape(-1) for c in cols])
    return G / np.linalg.norm(G, axis=0)


def _selection(u: int, dim: int, datum_points: ArrayLike | None) -> F64:
    if datum_points is None:
        return np.ones(u)
    e = np.zeros(u // dim)
    e[np.asarray(datum_points, dtype=int)] = 1.0
    return np.repeat(e, dim)


def datum_solve(N: ArrayLike, b: ArrayLike, G: ArrayLike, *, datum_points: ArrayLike | None = None,
                dim: int = 2) -> tuple[F64, F64]:  # fmt: skip
    """Solve singular normal equations N Δx = b in the datum of (partial) inner constraints.

    Parameters
    ----------
    N : array_like, shape (u, u)
        Normal matrix with rank defect d, N G = 0.
    b : array_like, shape (u,)
        Right-hand side AᵀP(l − f(x0)).
    G : array_like, shape (u, d)
        Null-space basis (:func:`helmert_basis`).
    datum_points : array_like of int, optional
        Indices of the points that define the datum (default: all: inner constraints).
    dim : int
        Coordinates per point (2 or 3).

    Returns
    -------
    dx : ndarray, shape (u,)
    Q : ndarray, shape (u, u)
        Cofactor matrix of the unknowns in this datum.
    """
    N = np.asarray(N, dtype=float)
    G = np.asarray(G, dtype=float)
    u, d = G.shape
    EG = G * _selection(u, dim, datum_points)[:, None]
    if np.linalg.matrix_rank(EG) < d:
        raise InputError(f"the datum points do not fix the {d} datum parameters (too few points)")
    # the border is scaled to N's size (the multipliers take up the factor; Q is unchanged)
    EG = EG * np.sqrt(max(float(np.trace(N)) / u, 1e-300))
    M = np.block([[N, EG], [EG.T, np.zeros((d, d))]])
    Minv = np.linalg.inv(M)
    Q = Minv[:u, :u]
    Q = 0.5 * (Q + Q.T)
    return Q @ np.asarray(b, dtype=float), Q


def s_transformation(G: ArrayLike, *, datum_points: ArrayLike | None = None, dim: int = 2) -> F64:
    """The S-matrix S = I − G (Gᵀ E G)⁻¹ Gᵀ E into the datum of ``datum_points``.

    Apply it as ``x_B = S @ x_A`` and ``Q_B = S @ Q_A @ S.T`` (any datum A of the same network).
    """
    G = np.asarray(G, dtype=float)
    u, d = G.shape
    e = _selection(u, dim, datum_points)
    GtE = G.T * e[None, :]
    M = GtE @ G
    if np.linalg.matrix_rank(M) < d:
        raise InputError(f"the datum points do not fix the {d} datum parameters (too few points)")
    return np.eye(u) - G @ np.linalg.solve(M, GtE)
