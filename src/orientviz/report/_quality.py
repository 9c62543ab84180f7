"""Sections of the report on quality: largest normalised residuals, high correlations,
warnings on geometry.

A mixin of the report builder (:mod:`orientviz.report._sections`); it uses the
builder's ``p``, ``s``, ``adj``, ``block``, ``used``, ``largest``, ``correlation``,
``warn``, ``plot`` and ``coverage_below()``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..block import CHECK, CONTROL
from ..errors import parameter_words
from ..plausibility import is_aerial
from ..units import RHO
from ._document import (
    FEW_POINTS,
    MAX_ROWS,
    NEAR_SINGULAR,
    POOR_COVERAGE,
    R_LOW,
    SMALL_ANGLE_GON,
    Section,
    Table,
    fmt,
    fmt_g,
)
from ._stats import (
    condition_number,
    conditioned_below,
    correlation_matrix,
    intersection_angles,
    split_label,
)


#: How many items a warning names (with their values), the rest as "…".
NAMED = 6


class QualitySections:
    """``residuals``, ``correlations`` and ``warnings`` sections and the geometry checks."""

    # .................................................................. residuals
    def residuals(self) -> Section:
        adj, s = self.adj, self.s
        w = adj.normalized_residuals
        k = self.largest
        img_q = s.observation_quantity == "image"
        um = img_q and s.units.image != "px"  # image residuals in µm; a pixel file's in px
        vu = "µm" if um else s.unit_name(s.observation_quantity)
        vf = 1000.0 if um else s.factor(s.observation_quantity)
        vd = 2 if img_q else 4  # decimals of v and σ
        blk = self.block
        block_obs = (
            blk is not None and s.kind == "block" and adj.obs_slices.get("image") is not None
        )
        rows, marked, recs = [], [], []
        idx = adj.largest_residuals(k)
        for i in idx:
            i = int(i)
            lab = s.label(i)
            if block_obs and i < 2 * blk.n_observations:
                o = i // 2
                im, pt, comp = (
                    blk.images.ids[blk.observations.image[o]],
                    blk.points.ids[blk.observations.point[o]],
                    "xy"[i % 2],
                )
            else:
                im, pt, comp = split_label(lab)
                if not im and len(s.image_ids) == 1 and s.kind != "similarity":
                    im = s.image_ids[0]
            ri = float(adj.redundancy_numbers[i]) if adj.redundancy_numbers is not None else np.nan
            wi = float(w[i]) if w is not None else np.nan
            flag = bool(np.isfinite(wi) and abs(wi) > s.critical)
            rec = {
                "index": i,
                "label": lab,
                "image": im,
                "point": pt,
                "component": comp,
                "v": float(adj.residuals[i]) * vf,
                "sigma": float(adj.sigma_obs[i]) * vf,
                "r": ri,
                "w": wi,
                "flagged": flag,
            }
            recs.append(rec)
            rows.append(
                [
                    str(i),
                    lab,
                    im or "—",
                    pt or "—",
                    comp,
                    fmt(rec["v"], vd),
                    fmt(rec["sigma"], vd),
                    fmt(ri, 3) if not ri < 1e-3 else fmt_g(ri, 2),
                    fmt(wi, 2),
                    "> crit" if flag else "",
                ]
            )
            marked.append(flag)
        n_flag = int(adj.flagged(s.critical).size)
        items = [
            ("critical value of |w|", f"{s.critical:g} (Baarda's w-test)"),
            ("observations above it", str(n_flag)),
        ]
        if w is None:
            items.append(
                ("normalised residuals", "not available (no redundancy numbers); ranked by |v|")
            )
        t = Table(
            ["obs", "label", "image", "point", "coord", f"v [{vu}]", f"σ [{vu}]", "r_i", "w", ""],
            rows,
            title=f"the {len(rows)} largest normalised residuals",
            align="rlllcrrrrl",
            marked=marked,
        )
        v: dict[str, Any] = {
            "largest": recs,
            "n_flagged": n_flag,
            "critical": s.critical,
            "unit": vu,
        }
        if n_flag:
            self.warn.append(
                f"{n_flag} observation(s) with |w| > {s.critical:g}: possible gross "
                f"errors (largest: {recs[0]['label']}, w = {recs[0]['w']:.2f})"
            )
        sec = Section(
            "residuals", "Largest normalised residuals", items=items, tables=[t], values=v
        )
        sec.text = [
            "w_i = v_i / (σ_i √r_i): the residual divided by its own standard deviation "
            "(Baarda's data snooping, a-priori σ0 = 1); 'obs' is the position in the "
            "observation vector."
        ]
        if w is not None:
            ww = w[self.used & np.isfinite(w)]
            if ww.size:
                sec.figures = ["w_histogram"]
                self.plot["w_histogram"] = {"w": ww, "critical": s.critical}
        return sec

    # .................................................................. correlations
    def correlations(self) -> Section:
        thr = self.correlation
        pairs, scope, near = self._correlation_checks(with_pairs=True)
        self._near_singular_warnings(near)
        rows = [  # in the user's words: "image s00_003 (Y0)", not "s00_003.Y0"
            [parameter_words([a]), parameter_words([b]), f"{r:+.4f}"]
            for a, b, r in pairs[:MAX_ROWS]
        ]
        t = Table(
            ["parameter", "parameter", "ρ"],
            rows,
            align="llr",
            title=f"pairs with |ρ| > {thr:g}",
            note=(f"{len(pairs) - MAX_ROWS} more not shown" if len(pairs) > MAX_ROWS else ""),
        )
        items = [
            ("threshold", f"|ρ| > {thr:g}"),
            ("scope", scope),
            ("pairs above the threshold", str(len(pairs))),
        ]
        sec = Section(
            "correlations",
            "High correlations",
            items=items,
            tables=[t] if rows else [],
            values={"pairs": pairs, "threshold": thr},
        )
        if any(
            {a.split(".")[-1], b.split(".")[-1]} in ({"X0", "phi"}, {"Y0", "omega"})
            for a, b, _ in pairs
        ):
            sec.text = [
                "X0–φ and Y0–ω are strongly correlated in every near-vertical image: "
                "a shift of the projection centre and a tilt move the image almost "
                "alike. This is expected and no defect."
            ]
        return sec

    def _correlation_checks(
        self, with_pairs: bool
    ) -> tuple[list[tuple[str, str, float]], str, list[tuple[str, float]]]:
        """The pairs of parameters with ``|ρ|`` above the threshold (sorted by ``|ρ|``;
        none unless ``with_pairs``), the scope of the check and the near-singular
        correlation matrices (what, condition number)."""
        adj, thr = self.adj, self.correlation
        pairs: list[tuple[str, str, float]] = []
        scope = ""
        near: list[tuple[str, float]] = []
        free = np.isfinite(adj.std()) & (adj.std() > 0)
        if adj.cofactor is not None:
            scope = "all pairs of parameters"
            idx = np.flatnonzero(free)
            if idx.size:
                C = correlation_matrix(adj.cofactor[np.ix_(idx, idx)])
                if with_pairs:
                    i, j = np.triu_indices_from(C, k=1)
                    sel = np.abs(C[i, j]) > thr
                    pairs = sorted(
                        (
                            (adj.names[idx[a]], adj.names[idx[b]], float(C[a, b]))
                            for a, b in zip(i[sel], j[sel])
                        ),
                        key=lambda t: -abs(t[2]),
                    )
                cond = condition_number(C)
                if cond > NEAR_SINGULAR:
                    near.append(("all parameters", cond))
        else:
            scope = (
                "pairs within one image's or one point's parameters (the full cofactor "
                "matrix is not formed for blocks)"
            )
            for bname, Q in adj.cofactor_groups.items():
                if bname not in adj.groups or Q.ndim != 3:
                    continue
                names = adj.names[adj.groups[bname]]
                nb = Q.shape[1]
                fb = free[adj.groups[bname]].reshape(-1, nb)
                # parameters without a σ (fixed points) get unit variance and no correlation
                d = np.sqrt(np.clip(np.einsum("kii->ki", Q), 0.0, None))
                d = np.where(fb & (d > 0), d, 1.0)
                C = np.where(
                    fb[:, :, None] & fb[:, None, :], Q / (d[:, :, None] * d[:, None, :]), 0.0
                )
                C[:, np.arange(nb), np.arange(nb)] = 1.0
                if with_pairs:
                    i, j = np.triu_indices(nb, k=1)
                    kk, pp = np.nonzero(np.abs(C[:, i, j]) > thr)
                    first = [names[a] for a in (kk * nb + i[pp]).tolist()]
                    second = [names[b] for b in (kk * nb + j[pp]).tolist()]
                    pairs.extend(zip(first, second, C[kk, i[pp], j[pp]].tolist()))
                active = np.flatnonzero(fb.sum(axis=1) >= 2)
                if nb == 3 and active.size:  # the eigenvalues only where they may exceed it
                    active = active[~conditioned_below(C[active], NEAR_SINGULAR)]
                if active.size:
                    with np.errstate(all="ignore"):
                        ev = np.linalg.eigvalsh(C[active])
                    cond = np.where(
                        ev[:, 0] > 0, ev[:, -1] / np.where(ev[:, 0] > 0, ev[:, 0], 1.0), np.inf
                    )
                    for k in active[np.flatnonzero(~(cond <= NEAR_SINGULAR))]:
                        near.append(
                            (
                                names[k * nb].rpartition(".")[0],
                                float(cond[np.searchsorted(active, k)]),
                            )
                        )
            pairs.sort(key=lambda t: -abs(t[2]))
        return pairs, scope, near

    def _near_singular_warnings(self, near: list[tuple[str, float]]) -> None:
        for what, cond in near[:10]:
            self.warn.append(
                f"near-singular: the correlation matrix of {what} has condition "
                f"number {cond:.3g} (> {NEAR_SINGULAR:.0e}); parameters nearly "
                "undetermined"
            )

    # .................................................................. warnings
    def warnings(self) -> Section:
        given = [n[len("warning: ") :] for n in self.s.notes if n.startswith("warning: ")]
        msgs = list(dict.fromkeys(given + self.warn))
        sec = Section("warnings", "Warnings on geometry and quality", values={"messages": msgs})
        sec.items = [("warnings", str(len(msgs)) if msgs else "none")]
        small = f"{SMALL_ANGLE_GON:g} gon"
        if self.block is not None and not is_aerial(self.block, self.s.units.length):
            small = f"{SMALL_ANGLE_GON * 0.9:g} deg"  # 10 gon
        sec.text = [
            f"Checked: convergence, global test, |w| above the critical value, redundancy "
            f"numbers below {R_LOW:g}, tie/check points with fewer than 3 rays, intersection "
            f"angles below {small}, images with fewer than {FEW_POINTS} points or "
            f"points covering less than {POOR_COVERAGE:.0%} of the format, near-singular "
            f"correlation matrices (condition number above {NEAR_SINGULAR:.0e})."
        ]
        return sec

    # .................................................................. geometry
    def geometry_warnings(self) -> None:
        blk, s = self.block, self.s
        if blk is None:
            return
        rays = blk.rays_per_point()
        roles = blk.points.role
        if s.kind != "resection":
            weak = np.flatnonzero((roles != CONTROL) & (rays < 3))
            if weak.size:
                self.warn.append(
                    f"{weak.size} tie/check point(s) with fewer than 3 rays: no "
                    "gross-error check along the ray (" + self._names(blk.points.ids, weak) + ")"
                )
            X0 = blk.images.X0
            if s.image_ids and len(s.image_ids) == blk.n_images:
                X0 = np.where(np.isfinite(s.X0), s.X0, X0)
            xyz = blk.points.xyz
            if len(s.point_ids) == blk.n_points:
                xyz = np.where(np.isfinite(s.xyz), s.xyz, xyz)
            ang = intersection_angles(blk, X0, xyz) * RHO["gon"]
            small = np.flatnonzero(np.isfinite(ang) & (ang < SMALL_ANGLE_GON))
            self.plot.setdefault("geometry", {})["angles_gon"] = ang
            if small.size:
                # aerial: the photogrammetrist's gon and "height"; else the file's angle
                # unit and the depth along the rays (a reconstruction's axes point anywhere)
                aerial = is_aerial(blk, s.units.length)
                au = "deg" if not aerial and s.units.angle == "deg" else "gon"
                f = RHO[au] / RHO["gon"]
                self.warn.append(
                    f"{small.size} point(s) with intersection angle below "
                    f"{SMALL_ANGLE_GON * f:.3g} {au}: "
                    + ("weak height (" if aerial else "weak depth along the rays (")
                    + self._names(blk.points.ids, small, ang * f, au)
                    + ")"
                )
        if s.image_ids and len(s.image_ids) == blk.n_images:
            npts = blk.points_per_image()
            few = np.flatnonzero(npts < FEW_POINTS)
            if few.size:
                self.warn.append(
                    f"{few.size} image(s) measured in fewer than {FEW_POINTS} "
                    "points (" + self._names(blk.images.ids, few, npts, "points") + ")"
                )
            measured = npts >= 3
            below, cov = self.coverage_below(POOR_COVERAGE, first=NAMED, among=measured)
            poor = np.flatnonzero(below & measured)
            if poor.size:
                self.warn.append(
                    f"{poor.size} image(s) whose points cover less than "
                    f"{POOR_COVERAGE:.0%} of the format: poorly determined "
                    "orientation (" + self._names(blk.images.ids, poor, cov * 100, "%") + ")"
                )
        std = self.adj.std()
        bad = ~np.isfinite(std)
        if s.kind == "block" and "points" in self.adj.groups:
            pb = self.adj.groups["points"]
            nb = bad[pb].reshape(-1, 3)
            if nb.shape[0] == roles.size:  # the bundle: all points (models: tie points only)
                nb[roles == CHECK] = False  # check points are not unknowns
                bad[pb] = nb.reshape(-1)
        if np.any(bad) and s.method == "bundle":
            names = [self.adj.names[i] for i in np.flatnonzero(bad)[:5]]
            self.warn.append(
                f"{int(bad.sum())} parameter(s) without a computed σ ({', '.join(names)})"
            )

    @staticmethod
    def _names(ids, idx, val=None, unit="", k: int = NAMED) -> str:
        parts = [ids[i] + (f" {val[i]:.3g} {unit}" if val is not None else "") for i in idx[:k]]
        return ", ".join(parts) + (", …" if len(idx) > k else "")
