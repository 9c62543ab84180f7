"""Kovarik's pre-orientation formulas with round constants.

How wrong they get as the rotations grow: :func:`orientviz.orientation.plotter.preorientation_error`
(it drives the simulated plotter).

For wide-angle photographs (c = 152.7 mm, 23 × 23 cm) and a constant model base of
220.7 machine mm, Kovarik (1968) gives, with by and z in machine mm and the angles in
centesimal minutes (c):

    Δω = −4000 (by_o + by_u − 2 by_m) / (z_o + z_u − 1.25 z_m)       (one profile)
    Δφ = 20 (by3 − by5 − by4 + by6) + 0.005 Δω (z3 − z5 − z4 + z6)
    Δbz = −0.7 (by4 − by6) − (z4 − z6) / 6000 · Δω

4000 ≈ ρ^c / K and 1.25 ≈ 2 / K with K = 1.59 (an ordinate of 117 mm); 20 ≈ ρ^c/(2 b k),
0.005 ≈ K/(2 b k) (strictly 0.0048), 0.7 ≈ 1/(2k) and 6000 ≈ 2 k ρ^c / K with k = 110/152.7.
The formulas are written in Kovarik's senses (his z is the negative model ordinate and
his bz and κ count the other way round from orientviz's, see
:data:`orientviz.orientation.relative.KOVARIK_SIGNS`). The base is left alone
(Δby = Δbz of the constant base); by and κ are then cleared at points 2 and 1 as the
operator does ("auskanten"), which is the exact linear expression at those points.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..units import RHO_C
from .relative import kovarik_to_orientviz
from .schemes import Scheme, get_scheme

F64 = NDArray[np.float64]

#: The round constants as printed.
ROUND = {"omega": 4000.0, "omega_m": 1.25, "phi": 20.0, "phi_w": 0.005, "bz": 0.7, "bz_w": 6000.0}


def round_formulas(by: ArrayLike, z: ArrayLike, profile: tuple[int, int, int] = (4, 6, 2)) -> F64:
    """Δω, Δφ (centesimal minutes) and Δbz (mm) by Kovarik's round-constant formulas.

    Parameters
    ----------
    by, z : array_like, shape (≥ 6,)
        by readings (relative to the current by) and z (negative model ordinate) at
        the points numbered 1, 2, … of Gruber's / Kovarik's scheme, machine mm.
    profile : (int, int, int)
        Point numbers (upper, lower, middle) of the profile used for Δω.

    Returns
    -------
    ndarray, shape (3,)
        Δω [c], Δφ [c], Δbz [mm] in Kovarik's senses.
    """
    p = np.asarray(by, dtype=float).reshape(-1)
    zz = np.asarray(z, dtype=float).reshape(-1)
    if p.size < 6 or zz.size != p.size:
        raise InputError(f"expected by and z at ≥ 6 scheme points, got {p.size} and {zz.size}")
    o, u, m = (i - 1 for i in profile)
    d_omega = (
        -ROUND["omega"] * (p[o] + p[u] - 2 * p[m]) / (zz[o] + zz[u] - ROUND["omega_m"] * zz[m])
    )
    d_phi = ROUND["phi"] * (p[2] - p[4] - p[3] + p[5]) + ROUND["phi_w"] * d_omega * (
        zz[2] - zz[4] - zz[3] + zz[5]
    )
    d_bz = -ROUND["bz"] * (p[3] - p[5]) - (zz[3] - zz[5]) / ROUND["bz_w"] * d_omega
    return np.array([d_omega, d_phi, d_bz])


def preorientation_corrections(by: ArrayLike, z: ArrayLike, scheme: Scheme | str, b: float) -> F64:
    """All five corrections of a pre-orientation pass (orientviz senses, mm and rad).

    Δω, Δφ, Δbz from :func:`round_formulas`; then by is cleared at point 2 and κ at
    point 1 (linear expressions given the other corrections).

    Returns
    -------
    ndarray, shape (5,)
        dby, dbz (mm), dω, dφ, dκ (rad).
    """
    sch = get_scheme(scheme)
    if not set("123456") <= set(sch.labels):
        raise InputError(f"the pre-orientation formulas need Gruber's points 1-6, not {sch.name}")
    idx = [sch.index(str(n)) for n in range(1, 7)]
    p = np.asarray(by, dtype=float)[idx]
    zz = np.asarray(z, dtype=float)[idx]
    w_c, f_c, dbz = round_formulas(p, zz)
    dw = w_c / RHO_C
    # Kovarik's equation at point 2 (x = b, y = 0): p2 = dby − z2 dω
    dby = p[1] + zz[1] * dw
    # at point 1 (x = 0, y = 0): p1 = dby − z1 dω + b dκ
    dk = (p[0] - dby + zz[0] * dw) / b
    return kovarik_to_orientviz([dby, dbz, dw, f_c / RHO_C, dk])
