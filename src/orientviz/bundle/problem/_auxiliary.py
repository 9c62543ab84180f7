"""Auxiliary data as joint observations: rows, weights and extra unknowns per strip.

Each auxiliary observation observes one coordinate of one entity of the block — a
projection centre (GNSS: X0, Y0, Z0; statoscope: Z0) or a ground point (APR: terrain Z)
— affected per strip by an offset and optionally a linear drift with the position along
the strip, t ∈ [0, 1] ::

    l + v = X_e[c] + o_s[c] + t · d_s[c]            (m)

The offsets o and drifts d are extra unknowns of the adjustment ("globals"), shared by
all observations of a strip; with ``offsets=False`` the data are absolute and enter
without them (e.g. GNSS that fixes the datum). The rows are linear: ∂v/∂X_e[c] = 1,
∂v/∂o = 1, ∂v/∂d = t. Both :func:`orientviz.stereo_models.independent_models` (on the
scalar point/centre unknowns) and :func:`orientviz.bundle.bundle_adjust` (on the
exterior-orientation and point unknowns) assemble them into their normal equations.

Statoscope: the instrument reads flying heights relative to an isobaric surface that is
unknown and drifts; what it delivers reliably are *height differences* between
consecutive exposure stations. Here it enters as readings with an unknown offset per
strip: that offset drops out of every difference, so the readings carry exactly the
information of the consecutive differences (and, unlike formed differences, they stay
uncorrelated); a drift per strip of the readings is a constant per strip of the
differences.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ...block import AuxiliaryEstimates
from ...errors import InputError
from ..reduced import AuxBorder, NormalEquations, factor_reduced
from . import _auxiliary_border as _ab

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
KINDS = ("gnss", "statoscope", "apr")
#: What each kind observes: "image" (projection centre) or "point".
TARGET = {"gnss": "image", "statoscope": "image", "apr": "point"}


@dataclass
class AuxRows:
    """All auxiliary observation rows of a block, one row per observed coordinate.

    Attributes
    ----------
    kind : list of str
        Kind of each row.
    target : ndarray of int, shape (n,)
        Observed image (gnss, statoscope) or block point (apr).
    on_image : ndarray of bool, shape (n,)
        True where the target is an image (projection centre).
    coord : ndarray of int, shape (n,)
        Observed coordinate 0 X, 1 Y, 2 Z.
    l : ndarray, shape (n,)
        Observed values (m).
    w : ndarray, shape (n,)
        Weights 1/σ² (1/m²).
    gcol : ndarray of int, shape (n, 2)
        Columns of the offset and drift unknowns in the global vector (−1: none).
    gcoef : ndarray, shape (n, 2)
        Their coefficients (1 for the offset, t for the drift).
    names : list of str
        Names of the global unknowns (``"gnss.offset_Z@s1"``).
    labels : list of str
        One label per row (``"gnss:s00_003.Z"``).
    """

    kind: list[str]
    target: I64
    on_image: NDArray[np.bool_]
    coord: I64
    l: F64
    w: F64
    gcol: I64
    gcoef: F64
    names: list[str] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)

    @property
    def n(self) -> int:
        """Number of rows."""
        return int(self.l.size)

    @property
    def n_global(self) -> int:
        """Number of offset/drift unknowns."""
        return len(self.names)

    def residuals(self, values: F64, g: F64) -> F64:
        """v = X_e[c] + o + t·d − l (m) for observed-coordinate ``values`` (n,) and globals g."""
        gv = np.where(self.gcol >= 0, g[np.maximum(self.gcol, 0)], 0.0) if g.size else 0.0
        return values + np.sum(self.gcoef * gv, axis=1) - self.l

    def jacobian_global(self) -> F64:
        """∂v/∂g, dense (n, n_global)."""
        J = np.zeros((self.n, self.n_global))
        for k in range(2):
            ok = self.gcol[:, k] >= 0
            J[np.flatnonzero(ok), self.gcol[ok, k]] += self.gcoef[ok, k]
        return J

    def split_globals(self, g: F64) -> dict:
        """Offsets (and drifts) per kind: ``{kind: array (strips, dims, 1 or 2)}``."""
        out: dict = {}
        for kind in dict.fromkeys(self.kind):
            pos = [i for i, nm in enumerate(self.names) if nm.startswith(kind + ".")]
            if not pos:
                continue
            dims = 3 if kind == "gnss" else 1
            npar = 2 if any(".drift_" in self.names[i] for i in pos) else 1
            out[kind] = g[pos].reshape(-1, npar, dims).transpose(0, 2, 1)
        return out


def auxiliary_rows(aux, block, *, image_ids: list[str] | None = None) -> AuxRows:
    """Rows of a list of :class:`orientviz.block.Auxiliary` data sets.

    Parameters
    ----------
    aux : list of Auxiliary
        At most one per kind; ``values`` (k, 3) for gnss, (k,) otherwise.
    block : Block
        The block (ids for labels, number of strips).

    Raises
    ------
    InputError
        For unknown or repeated kinds, indices out of range, non-positive σ.
    """
    kinds = [getattr(a, "kind", None) for a in aux]
    if any(k not in KINDS for k in kinds) or len(set(kinds)) != len(kinds):
        raise InputError(f"auxiliary: expected at most one each of {', '.join(KINDS)}, got {kinds}")
    if "gnss" in kinds and "statoscope" in kinds:
        raise InputError("auxiliary: gnss and statoscope both observe Z0; give one of them")
    ids_img = image_ids or list(block.images.ids)
    parts = dict(kind=[], target=[], on=[], coord=[], l=[], w=[], gcol=[], gcoef=[], labels=[])
    names: list[str] = []
    for a in aux:
        idx = np.asarray(a.index, np.int64)
        limit = block.n_images if TARGET[a.kind] == "image" else block.n_points
        if idx.size and (idx.min() < 0 or idx.max() >= limit):
            raise InputError(f"auxiliary {a.kind}: index out of range 0 … {limit - 1}")
        if not float(a.sigma) > 0:
            raise InputError(f"auxiliary {a.kind}: expected σ > 0 m, got {a.sigma}")
        dims = (0, 1, 2) if a.kind == "gnss" else (2,)
        vals = np.asarray(a.values, float).reshape(idx.size, len(dims))
        strip = np.asarray(a.strip, np.int64)
        t = np.asarray(a.time, float)
        n_s = int(strip.max()) + 1 if strip.size else 0
        npar = (2 if a.drift else 1) if a.offsets else 0
        base = len(names)
        for s in range(n_s):
            for p in range(npar):
                for c in dims:
                    names.append(f"{a.kind}.{('offset', 'drift')[p]}_{'XYZ'[c]}@s{s}")
        for d, c in enumerate(dims):
            k = idx.size
            gcol = np.full((k, 2), -1, np.int64)
            gcoef = np.zeros((k, 2))
            for p in range(npar):
                gcol[:, p] = base + (strip * npar + p) * len(dims) + d
                gcoef[:, p] = 1.0 if p == 0 else t
            parts["kind"] += [a.kind] * k
            parts["target"].append(idx)
            parts["on"].append(np.full(k, TARGET[a.kind] == "image"))
            parts["coord"].append(np.full(k, c, np.int64))
            parts["l"].append(vals[:, d])
            parts["w"].append(np.full(k, 1.0 / float(a.sigma) ** 2))
            parts["gcol"].append(gcol)
            parts["gcoef"].append(gcoef)
            ids = ids_img if TARGET[a.kind] == "image" else block.points.ids
            parts["labels"] += [f"{a.kind}:{ids[i]}.{'XYZ'[c]}" for i in idx]

    def cat(key, shape, dtype):
        return np.concatenate(parts[key]) if parts[key] else np.zeros(shape, dtype)

    return AuxRows(
        kind=parts["kind"], target=cat("target", 0, np.int64), on_image=cat("on", 0, bool),
        coord=cat("coord", 0, np.int64), l=cat("l", 0, float), w=cat("w", 0, float),
        gcol=cat("gcol", (0, 2), np.int64), gcoef=cat("gcoef", (0, 2), float), names=names,
        labels=parts["labels"],
    )  # fmt: skip


# --------------------------------------------------------------------------- bundle hook
class BundleAuxiliary:
    """The hook of :func:`orientviz.bundle.bundle_adjust` for auxiliary observations.

    Rows on projection centres add to the 6 × 6 image blocks of the normal matrix, rows
    on points to the 3 × 3 point blocks (before the points are eliminated), and the
    offsets/drifts border the reduced camera system together with the self-calibration
    parameters, if any (after them; :mod:`orientviz.bundle.problem._auxiliary_border`). All
    methods take the bundle's current state arrays.
    """

    def __init__(self, rows: AuxRows, pt_col: I64):
        self.rows = rows
        self.img = rows.on_image
        pc = np.where(~rows.on_image, pt_col[np.where(rows.on_image, 0, rows.target)], -1)
        if np.any(~rows.on_image & (pc < 0)):
            bad = rows.target[~rows.on_image & (pc < 0)][:5].tolist()
            raise InputError(
                f"auxiliary apr: points {bad} are not unknowns of the bundle (fixed or unused)"
            )
        self.pcol = pc
        self.Jg = rows.jacobian_global()

    @property
    def n_global(self) -> int:
        return self.rows.n_global

    def residuals(self, X0: F64, xyz: F64, g: F64) -> F64:
        """v (n,) in m at the current projection centres (m, 3), points (p, 3), globals."""
        r = self.rows
        vals = np.where(r.on_image, X0[r.target * r.on_image, r.coord], 0.0)
        vals = np.where(r.on_image, vals, xyz[r.target * ~r.on_image, r.coord])
        return r.residuals(vals, g)

    def cost(self, X0: F64, xyz: F64, g: F64) -> float:
        v = self.residuals(X0, xyz, g)
        return float(np.sum(self.rows.w * v**2))

    def add_images(self, U: F64, bc: F64, X0: F64, xyz: F64, g: F64) -> None:
        """Add the centre rows to the image blocks U (m, 6, 6) and right sides bc (m, 6)."""
        r, s = self.rows, self.img
        v = self.residuals(X0, xyz, g)
        np.add.at(U, (r.target[s], r.coord[s], r.coord[s]), r.w[s])
        np.add.at(bc, (r.target[s], r.coord[s]), -r.w[s] * v[s])

    def add_points(self, V: F64, bp: F64, X0: F64, xyz: F64, g: F64) -> None:
        """Add the point rows to the point blocks V (p_var, 3, 3) and bp (p_var, 3)."""
        r, s = self.rows, ~self.img
        v = self.residuals(X0, xyz, g)
        np.add.at(V, (self.pcol[s], r.coord[s], r.coord[s]), r.w[s])
        np.add.at(bp, (self.pcol[s], r.coord[s]), -r.w[s] * v[s])

    def global_blocks(self, m: int, n_pts: int, X0: F64, xyz: F64, g: F64):
        """Coupling of the globals: with images E (6m, q), with points P (p_var·3, q),
        their own block F (q, q) and right side b (q,)."""
        r = self.rows
        wJ = self.Jg * r.w[:, None]
        E = np.zeros((6 * m, self.n_global))
        P = np.zeros((3 * n_pts, self.n_global))
        s = self.img
        np.add.at(E, 6 * r.target[s] + r.coord[s], wJ[s])
        np.add.at(P, 3 * self.pcol[~s] + r.coord[~s], wJ[~s])
        F = self.Jg.T @ wJ
        b = -(wJ.T @ self.residuals(X0, xyz, g))
        return E, P, F, b

    def reduce(
        self, prob, X0: F64, xyz: F64, g: F64, ne: NormalEquations, lam: float = 0.0
    ) -> AuxBorder:
        """The globals' part of the point-reduced normal equations.

        Returns ``E`` (6m, na) camera coupling, ``F`` (na, na), ``b`` (na,), ``Pg``
        (p_var, 3, na) point coupling (for the back substitution) and ``diag`` (undamped
        diagonal of F).
        """
        S = prob.reduced
        n_pts = prob.points.unknown.size
        E, P, F, b = self.global_blocks(prob.m, n_pts, X0, xyz, g)
        Pg = P.reshape(n_pts, 3, -1)
        Vinv, T = ne.Vinv, ne.T
        pts = np.unique(self.pcol[~self.img])
        if pts.size:
            VP = Vinv[pts] @ Pg[pts]  # (k, 3, na)
            F -= np.einsum("kia,kib->ab", Pg[pts], VP)
            b -= np.einsum("kia,ki->a", VP, ne.bp[pts])
            vo = S.pt_obs
            o = vo[np.isin(prob.obs.column[vo], pts)]
            # Σ over the rays of each image by one sparse product (np.add.at is slow here)
            per_ray = -(T[o] @ Pg[prob.obs.column[o]]).reshape(o.size, -1)
            by_image = sp.csr_matrix(
                (np.ones(o.size), (prob.obs.image[o], np.arange(o.size))), shape=(prob.m, o.size)
            )
            E.reshape(prob.m, -1)[:] += by_image @ per_ray
        diag = np.diag(F).copy()
        if lam > 0:
            F[np.diag_indices_from(F)] *= 1.0 + lam
        return AuxBorder(E=E, F=F, b=b, Pg=Pg, diag=diag)

    def normal(self, prob, st, ne: NormalEquations, lam: float = 0.0) -> None:
        """Put the globals' bordered block into the bundle's normal equations ``ne``.

        Stored as ``ne.aux`` (see :meth:`reduce`; with additional parameters also
        their coupling ``"Fag"`` (q, na), :mod:`orientviz.bundle.problem._auxiliary_border`);
        ``ne.diagF`` is extended by the globals' diagonal (the stopping rule reads
        the corrections (da, dg) in one vector).
        """
        a = self.reduce(prob, st.X0, st.xyz, st.g, ne, lam)
        if prob.q and not prob.run.border.hold:
            a.Fag = _ab.ap_aux_coupling(prob, ne, a.Pg)
        ne.aux = a
        ne.diagF = np.concatenate([ne.diagF, a.diag])

    def solve(self, prob, fac, ne: NormalEquations):
        """Corrections (dc (m, 6), dp (p_var, 3), (da, dg) (q + na,), fac) of the
        bordered system; the additional parameters' corrections da come first (zero
        while they are held).

        Raises
        ------
        NotDeterminableError
            If the offsets/drifts (with the additional parameters) are not determinable
            (naming them).
        """
        dc, da, dg = _ab.solve_joint(prob, fac, ne)
        if not da.size:
            da = np.zeros(prob.q)
        dc, dp, da, fac = prob.back_substitute(ne, dc, da, fac)
        dp -= np.einsum("nij,nj->ni", ne.Vinv, ne.aux.Pg @ dg)
        return dc, dp, np.concatenate([da, dg]), fac

    def border(self, prob, ne: NormalEquations) -> tuple[F64, F64]:
        """The joint border of the point-reduced system: E (6m, q + na), F (q + na, q + na)."""
        return _ab.border(prob, ne)[:2]

    def point_border(self, prob, ne: NormalEquations, hb: F64) -> None:
        """Fill g's columns ``hb[:, q:]`` (p_var, na, 3) of the points' border term."""
        hb[:, prob.q :] = _ab.point_border(ne)

    def precision(self, res, Qcc: F64, Qpp: F64, Qcb: F64, Qbp: F64, Qbb: F64) -> None:
        """Redundancy numbers of the rows (``res.auxiliary.redundancy``, appended to the
        result's by :func:`finish_bundle`) and ``cofactor_groups["auxiliary"]``.

        Cofactor blocks as in :func:`orientviz.bundle.problem._auxiliary_border.auxiliary_redundancy`.
        """
        na = self.n_global
        r = _ab.auxiliary_redundancy(self, Qcc, Qpp, Qcb, Qbp, Qbb)
        res.auxiliary = AuxiliaryEstimates({}, {}, np.zeros(0), [], redundancy=r)
        res.cofactor_groups["auxiliary"] = Qbb[Qbb.shape[0] - na :, Qbb.shape[0] - na :]


def finish_bundle(res, prob, st, rw, Je, Jp) -> None:
    """Add the auxiliary estimates, their σ and residuals to a bundle result.

    The auxiliary rows are appended to the result's observations (after the
    pseudo-observations; ``obs_slices["auxiliary"]``, m): ``residuals``,
    ``sigma_obs`` and — when the precision was computed — ``redundancy_numbers`` and
    ``normalized_residuals``. ``cofactor_groups["auxiliary"]`` is the cofactor matrix of
    the offsets/drifts (m², marginal: with the orientations, points and additional
    parameters adjusted together).
    """
    aux = prob.aux
    Qg = res.cofactor_groups.get("auxiliary")
    if Qg is None:  # no precision run: the border of the solution alone
        ne = prob.normal(st, rw, Je, Jp)
        fac = factor_reduced(prob.reduced, ne.blocks, [str(i) for i in range(6 * prob.m)])
        aux.solve(prob, fac, ne)
        Qg = np.linalg.inv(ne.Fs_aux)[prob.q :, prob.q :]
        res.cofactor_groups["auxiliary"] = Qg
    s0 = res.sigma0 if np.isfinite(res.sigma0) else 1.0
    v = aux.residuals(st.X0, st.xyz, st.g)
    r = res.auxiliary.redundancy if res.auxiliary is not None else None
    res.auxiliary = AuxiliaryEstimates(
        aux.rows.split_globals(st.g),
        aux.rows.split_globals(s0 * np.sqrt(np.diag(Qg))),
        v,
        aux.rows.labels,
        list(aux.rows.names),
        r,
    )
    # the rows as observations of the result, after the pseudo-observations
    n0 = res.residuals.size
    sig = 1.0 / np.sqrt(aux.rows.w)
    res.obs_slices["auxiliary"] = slice(n0, n0 + v.size)
    res.residuals = np.concatenate([res.residuals, v])
    res.sigma_obs = np.concatenate([res.sigma_obs, sig])
    if r is not None and res.redundancy_numbers is not None:
        res.redundancy_numbers = np.concatenate([res.redundancy_numbers, r])
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(r > 1e-10, v / (sig * np.sqrt(r)), np.nan)
        res.normalized_residuals = np.concatenate([res.normalized_residuals, w])
        res.redundancy_check = float(np.nansum(res.redundancy_numbers))
