"""Kind ``similarity``: a 3D similarity (7 p.) or rigid (6 p.) transformation.

The classic use is the absolute orientation of a relatively oriented model (Leeb 1968):
``X = T + m · R(ω, φ, κ) · x`` turns ``source`` points x (model coordinates) into the
``target`` frame X (object coordinates); R in the file's rotation sequence. Points are
matched by id. Target coordinates may be null (planimetric- or height-only control);
source points without a target counterpart are transformed and reported.

Each point set may state its own length unit (``"length": "mm"`` for plotter model
coordinates); the translation is reported in ``units.length``, the scale is a pure
number relating metres to metres. A target σ that is not given is 1 length unit of the
target set (equal weights: σ̂0 is then the r.m.s. residual in that unit). Source σ
(optional, all or none) makes the model coordinates observations too.

Solver: :func:`orientviz.orientation.absolute.similarity_transform`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...adjust.result import W_CRITICAL
from ...errors import InputError
from ...orientation.absolute import similarity_model, similarity_transform
from ..problem import LENGTH_UNITS, Problem, Units
from ..registry import Kind, register_kind
from ..solution import Parameter, Solution
from ..tables import REQUIRED, json_numbers, read_table, write_table

F64 = NDArray[np.float64]
FIELDS = {"id": REQUIRED, "X": REQUIRED, "Y": REQUIRED, "Z": REQUIRED, "sigma": None}


@dataclass
class PointSet:
    """Points of one frame: ids, coordinates (n, 3) m (NaN = not given), σ (n, 3) m (NaN = none)."""

    ids: list[str]
    xyz: F64
    sigma: F64
    frame: str = ""
    length: str | None = None  # unit override of this set in the file


@dataclass
class SimilarityData:
    """The two point sets of a similarity problem, in m."""

    source: PointSet
    target: PointSet
    sequence: str = "opk"
    meta: dict[str, Any] = field(default_factory=dict)


def _read_set(doc: dict[str, Any], key: str, units: Units, source: str):
    node = doc[key]
    unit = node.get("length", units.length)
    scale = LENGTH_UNITS[unit]
    t = read_table(node, f"{key}.points", FIELDS, source)
    t.index("id", f"{key} point")
    xyz = np.column_stack([t.floats("X", scale), t.floats("Y", scale), t.floats("Z", scale)])
    sig = t.vectors("sigma", 3, scale)
    zero = np.argwhere(sig <= 0)
    if zero.size:
        raise t.fail(
            int(zero[0][0]), "sigma", "expected σ > 0 (to hold a coordinate fixed use a small σ)"
        )
    ps = PointSet(t.strings("id"), xyz.reshape(-1, 3), sig, str(node.get("frame", "")),
                  node.get("length"))  # fmt: skip
    return ps, t


def load(doc: dict[str, Any], units: Units, source: str) -> SimilarityData:
    """Read a ``similarity`` document (coordinates in m)."""
    src, ts = _read_set(doc, "source", units, source)
    tgt, tt = _read_set(doc, "target", units, source)
    bad = np.argwhere(~np.isfinite(src.xyz))
    if bad.size:
        i, k = int(bad[0][0]), int(bad[0][1])
        raise ts.fail(i, "XYZ"[k], "source coordinates must all be given")
    has_sig = np.isfinite(src.sigma).all(axis=1)
    if has_sig.any() and not has_sig.all():
        i = int(np.flatnonzero(~has_sig)[0])
        raise ts.fail(i, "sigma", "give σ for all source points or for none")
    src_idx = {k: i for i, k in enumerate(src.ids)}
    for j, ident in enumerate(tgt.ids):
        if ident not in src_idx:
            raise tt.fail(j, "id", f"unknown point id {ident!r}: not among the source points")
    empty = np.flatnonzero(np.all(np.isnan(tgt.xyz), axis=1))
    if empty.size:
        raise tt.fail(int(empty[0]), "X", "target point has no coordinates (all null)")
    return SimilarityData(src, tgt, doc["sequence"])


def _write_set(ps: PointSet, units: Units, columnar: bool) -> dict[str, Any]:
    scale = LENGTH_UNITS[ps.length or units.length]
    sig_cells: list[Any] = []
    for s in ps.sigma:
        if np.all(np.isnan(s)):
            sig_cells.append(None)
        else:
            vals = json_numbers(s / scale)
            sig_cells.append(vals[0] if len(set(vals)) == 1 else vals)
    cols = {
        "id": list(ps.ids),
        "X": json_numbers(ps.xyz[:, 0] / scale),
        "Y": json_numbers(ps.xyz[:, 1] / scale),
        "Z": json_numbers(ps.xyz[:, 2] / scale),
        "sigma": sig_cells,
    }
    out: dict[str, Any] = {}
    if ps.frame:
        out["frame"] = ps.frame
    if ps.length:
        out["length"] = ps.length
    table = write_table(cols, columnar)
    if not columnar:  # X, Y, Z are required keys: keep null for a coordinate not given
        for row, x, y, z in zip(table, cols["X"], cols["Y"], cols["Z"]):
            row.update({"X": x, "Y": y, "Z": z})
            row.update({k: row.pop(k) for k in ("sigma",) if k in row})
    else:
        table.update({"X": cols["X"], "Y": cols["Y"], "Z": cols["Z"]})
    out["points"] = table
    return out


def dump(data: SimilarityData, units: Units, columnar: bool) -> dict[str, Any]:
    return {
        "source": _write_set(data.source, units, columnar),
        "target": _write_set(data.target, units, columnar),
    }


def _propagate(adj, J: F64, n: int, with_points: bool) -> F64:
    """σ (n, 3) of transformed points from the parameter covariance (and model points)."""
    C = adj.covariance()
    if not with_points:
        Cp = C[:7, :7]
        return np.sqrt(np.clip(np.einsum("nik,kl,nil->ni", J, Cp, J), 0.0, None))
    R_blk = adj.transform.scale * adj.transform.R
    Jf = np.concatenate([J, np.broadcast_to(R_blk, (n, 3, 3))], axis=2)  # (n, 3, 10)
    idx = np.concatenate(
        [np.broadcast_to(np.arange(7), (n, 7)), 7 + 3 * np.arange(n)[:, None] + np.arange(3)],
        axis=1,
    )
    Cs = C[idx[:, :, None], idx[:, None, :]]
    return np.sqrt(np.clip(np.einsum("nik,nkl,nil->ni", Jf, Cs, Jf), 0.0, None))


def solve(problem: Problem, method: str | None) -> Solution:
    """Estimate the transformation and transform every source point."""
    data: SimilarityData = problem.data
    src, tgt = data.source, data.target
    n = len(src.ids)
    pos = {k: i for i, k in enumerate(src.ids)}
    target = np.full((n, 3), np.nan)
    sigma_t = np.full((n, 3), np.nan)
    tscale = LENGTH_UNITS[tgt.length or problem.units.length]
    for j, ident in enumerate(tgt.ids):
        i = pos[ident]
        target[i] = tgt.xyz[j]
        sigma_t[i] = np.where(np.isnan(tgt.sigma[j]), tscale, tgt.sigma[j])
    sigma_t = np.where(np.isnan(target), np.nan, sigma_t)
    with_points = bool(np.all(np.isfinite(src.sigma)))
    rigid = not bool(problem.options.get("scale", True))
    adj = similarity_transform(
        src.xyz, target, sigma_target=sigma_t, sigma_source=src.sigma if with_points else None,
        rigid=rigid, sequence=data.sequence, point_ids=list(src.ids),
        max_iter=int(problem.options.get("max_iter", 30)),
    )  # fmt: skip
    std = adj.std()
    names = ("tx", "ty", "tz", "omega", "phi", "kappa", "scale")
    qty = ("length",) * 3 + ("angle",) * 3 + ("1",)
    params = [
        Parameter(nm, float(adj.x[k]), float(std[k]), q)
        for k, (nm, q) in enumerate(zip(names, qty))
    ]
    pts = src.xyz if not with_points else adj.x[7:].reshape(n, 3)
    _, J = similarity_model(adj.x[:7], pts, data.sequence)
    if rigid:
        J = J.copy()
        J[:, :, 6] = 0.0
    used = np.any(np.isfinite(target), axis=1)
    notes = [
        f"X_target = T + m · R(ω, φ, κ) · x_source, sequence {data.sequence}; "
        f"{int(used.sum())} of {n} points with target coordinates; "
        + ("rigid (m = 1)" if rigid else "7 parameters")
    ]
    if np.any(np.isnan(tgt.sigma) & np.isfinite(tgt.xyz)):
        notes.append(f"target σ not given: 1 {tgt.length or problem.units.length} (equal weights)")
    if src.length:
        notes.append(f"source coordinates given in {src.length}, converted to m: m relates m to m")
    return Solution(
        kind="similarity",
        method="similarity" if not rigid else "rigid",
        adjustment=adj,
        units=problem.units,
        sequence=data.sequence,
        point_ids=list(src.ids),
        xyz=adj.transformed,
        xyz_sigma=_propagate(adj, J, n, with_points),
        point_roles=["control" if u else "transformed" for u in used],
        parameters=params,
        observation_quantity="length",
        critical=float(problem.options.get("critical", W_CRITICAL)),
        notes=notes,
    )


def similarity_problem(source_ids, source_xyz, target_ids, target_xyz, **kw) -> SimilarityData:
    """Build :class:`SimilarityData` from arrays (m); ``kw``: ``target_sigma``, ``source_sigma``, frames."""
    s = np.asarray(source_xyz, float).reshape(-1, 3)
    t = np.asarray(target_xyz, float).reshape(-1, 3)
    ss = np.broadcast_to(np.asarray(kw.get("source_sigma", np.nan), float), s.shape).copy()
    ts = np.broadcast_to(np.asarray(kw.get("target_sigma", np.nan), float), t.shape).copy()
    if len(source_ids) != s.shape[0] or len(target_ids) != t.shape[0]:
        raise InputError("similarity_problem: one id per point expected")
    return SimilarityData(
        PointSet([str(i) for i in source_ids], s, ss, kw.get("source_frame", "model"), kw.get("source_length")),
        PointSet([str(i) for i in target_ids], t, ts, kw.get("target_frame", "object"), kw.get("target_length")),
        kw.get("sequence", "opk"),
    )  # fmt: skip


KIND = register_kind(
    Kind(
        name="similarity",
        schema="similarity.json",
        load=load,
        dump=dump,
        solve=solve,
        description="3D similarity / rigid transformation (absolute orientation of a model)",
        methods=("similarity",),
    )
)
