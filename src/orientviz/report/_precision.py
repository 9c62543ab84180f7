"""Sections of the report on precision: per image, per point, check points.

A mixin of the report builder (:mod:`orientviz.report._sections`); it uses the
builder's ``p`` (problem), ``s`` (solution), ``adj``, ``block``, ``used``, ``worst``,
``warn`` and ``plot``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..block import CHECK
from ._document import MAX_ROWS, Section, Table, angle_unit, decimals, fmt, length_unit
from ._stats import F64, image_slice


class PrecisionSections:
    """``images``, ``points`` and ``check`` sections."""

    # .................................................................. images
    def images(self) -> Section | None:
        s = self.s
        if not s.image_ids:
            return None
        m = len(s.image_ids)
        sX = np.asarray(s.X0_sigma, float)
        sA = np.asarray(s.angles_sigma, float)
        lu, lf = length_unit(sX, self.s.units.length)
        au, af = angle_unit(s.units.angle)
        L, A = s.factor("length"), s.factor("angle")
        blk = self.block
        npts = np.full(m, -1)
        cov = np.full(m, np.nan)
        if blk is not None and len(blk.images) == m:
            npts = blk.points_per_image()
            cov = self.coverage()
        v = {
            "ids": list(s.image_ids),
            "sigma_X0": sX * lf,
            "sigma_angles": sA * af,
            "length_unit": lu,
            "angle_unit": au,
            "points": npts,
            "coverage": cov,
        }
        stats = []
        for j, nm in enumerate(("σX0", "σY0", "σZ0")):
            stats.append([nm, lu, *self._stat(sX[:, j] * lf, decimals(lu))])
        for j, nm in enumerate(("σω", "σφ", "σκ")):
            stats.append([nm, au, *self._stat(sA[:, j] * af, decimals(au))])
        t_stat = Table(
            ["", "unit", "mean", "r.m.s.", "max", "image of max"],
            stats,
            title="precision of the exterior orientation",
            align="llrrrl",
        )
        for row, col in zip(stats, range(6)):
            arr = (sX * lf if col < 3 else sA * af)[:, col % 3]
            row[-1] = s.image_ids[int(np.nanargmax(arr))] if np.any(np.isfinite(arr)) else "—"
        rank = np.argsort(-np.nan_to_num(np.linalg.norm(sX, axis=1), nan=-1.0))
        shown = rank[:MAX_ROWS] if m > MAX_ROWS else np.arange(m)
        rows = []
        dl = 3 if s.units.length in ("m", "model") else 1
        for k in shown:
            X = s.X0[k] * L
            a = s.angles[k] * A
            rows.append(
                [
                    s.image_ids[k],
                    *(fmt(x, dl) for x in X),
                    *(fmt(x, decimals(lu)) for x in sX[k] * lf),
                    *(fmt(x, 5) for x in a),
                    *(fmt(x, decimals(au)) for x in sA[k] * af),
                    str(npts[k]) if npts[k] >= 0 else "—",
                    f"{100 * cov[k]:.0f} %" if np.isfinite(cov[k]) else "—",
                ]
            )
        t = Table(
            [
                "image",
                f"X0 [{s.units.length_name}]",
                f"Y0 [{s.units.length_name}]",
                f"Z0 [{s.units.length_name}]",
                f"σX0 [{lu}]",
                f"σY0 [{lu}]",
                f"σZ0 [{lu}]",
                f"ω [{s.units.angle}]",
                f"φ [{s.units.angle}]",
                f"κ [{s.units.angle}]",
                f"σω [{au}]",
                f"σφ [{au}]",
                f"σκ [{au}]",
                "points",
                "coverage",
            ],
            rows,
            title="exterior orientation (adjusted) and its precision",
            note=(f"the {len(shown)} least precise of {m} images" if m > MAX_ROWS else ""),
        )
        sec = Section("images", "Per-image precision", tables=[t_stat, t], values=v)
        sec.text = [
            f"σ of positions in {lu}, of angles in {au} (a posteriori, scaled with "
            f"σ0 a posteriori); rotation sequence {s.sequence}. 'coverage' is the area of the "
            "convex hull of the image's measured points over the image format."
        ]
        if m >= 2 and np.any(np.isfinite(sX)):
            sec.figures = ["image_sigma"]
            self.plot["image_sigma"] = v
        return sec

    @staticmethod
    def _stat(a: F64, d: int) -> list[str]:
        a = a[np.isfinite(a)]
        if a.size == 0:
            return ["—", "—", "—", "—"]
        return [
            fmt(float(np.mean(a)), d),
            fmt(float(np.sqrt(np.mean(a**2))), d),
            fmt(float(np.max(a)), d),
            "",
        ]

    # .................................................................. points
    def points(self) -> Section | None:
        s = self.s
        if not s.point_ids:
            return None
        sxyz = np.asarray(s.xyz_sigma, float)
        roles = np.array(s.point_roles + [""] * (len(s.point_ids) - len(s.point_roles)))
        est = np.all(np.isfinite(sxyz), axis=1) & np.any(sxyz > 0, axis=1)
        if not est.any():
            return None
        lu, lf = length_unit(sxyz[est], self.s.units.length)
        d = decimals(lu)
        v: dict[str, Any] = {
            "ids": list(s.point_ids),
            "roles": list(roles),
            "sigma": sxyz * lf,
            "unit": lu,
            "estimated": est,
        }
        rows = []
        groups = [(r, est & (roles == r)) for r in dict.fromkeys(roles[est])]
        groups.append(("all", est))
        summary: dict[str, Any] = {}
        for name, sel in groups:
            if not sel.any() or (name == "all" and len(groups) == 2):
                continue
            a = sxyz[sel] * lf
            rms = np.sqrt(np.mean(a**2, axis=0))
            mx = np.max(a, axis=0)
            summary[name] = {"n": int(sel.sum()), "rms": rms, "max": mx}
            rows.append(
                [name, str(int(sel.sum())), *(fmt(x, d) for x in rms), *(fmt(x, d) for x in mx)]
            )
        v["summary"] = summary
        t1 = Table(
            [
                "points",
                "n",
                f"r.m.s. σX [{lu}]",
                f"r.m.s. σY [{lu}]",
                f"r.m.s. σZ [{lu}]",
                f"max σX [{lu}]",
                f"max σY [{lu}]",
                f"max σZ [{lu}]",
            ],
            rows,
            title="summary of the point precision (estimated points)",
        )
        total = np.where(est, np.sqrt(np.nansum(sxyz**2, axis=1)), -1.0)
        worst = np.argsort(-total)[: min(self.worst, int(est.sum()))]
        rays = self.block.rays_per_point() if self.block is not None else None
        L = s.factor("length")
        rows2 = []
        for k in worst:
            rows2.append(
                [
                    s.point_ids[k],
                    roles[k],
                    *(fmt(x, 3) for x in s.xyz[k] * L),
                    *(fmt(x, d) for x in sxyz[k] * lf),
                    str(rays[k]) if rays is not None and k < len(rays) else "—",
                ]
            )
        t2 = Table(
            [
                "point",
                "role",
                f"X [{s.units.length_name}]",
                f"Y [{s.units.length_name}]",
                f"Z [{s.units.length_name}]",
                f"σX [{lu}]",
                f"σY [{lu}]",
                f"σZ [{lu}]",
                "rays",
            ],
            rows2,
            title=f"the {len(worst)} least precise points",
            align="llrrrrrrr",
        )
        if rays is None or len(rays) != len(s.point_ids):  # no rays to count (similarity)
            t2.columns.pop()
            t2.align = t2.align[:-1]
            for row in t2.rows:
                row.pop()
        v["worst"] = [s.point_ids[k] for k in worst]
        sec = Section("points", "Per-point precision", tables=[t1, t2], values=v)
        sec.text = [
            f"a-posteriori σ in {lu}; control points held fixed have σ = 0 and are not "
            "counted; all coordinates: orientviz solve FILE --json"
        ]
        if self.block is not None and np.any(np.isfinite(s.xyz[est])):
            sec.figures = ["point_precision"]
            self.plot["point_precision"] = {
                "xy": s.xyz[est, :2],
                "sigma": sxyz[est] * lf,
                "unit": lu,
            }
        return sec

    # .................................................................. check points
    def check(self) -> Section | None:
        blk, s = self.block, self.s
        if blk is None:
            return None
        chk = np.flatnonzero(
            (blk.points.role == CHECK) & np.any(np.isfinite(blk.points.xyz_known), axis=1)
        )
        if chk.size == 0:
            return None
        pos = {k: i for i, k in enumerate(s.point_ids)}
        ids = [blk.points.ids[i] for i in chk]
        have = np.array([i in pos for i in ids])
        est = np.full((chk.size, 3), np.nan)
        est[have] = s.xyz[[pos[i] for i, h in zip(ids, have) if h]]
        dm = est - blk.points.xyz_known[chk]
        n = np.sum(np.isfinite(dm), axis=0)
        with np.errstate(invalid="ignore"):
            rms = np.sqrt(np.nansum(dm**2, axis=0) / np.maximum(n, 1))
            mean = np.nansum(dm, axis=0) / np.maximum(n, 1)
            mx = np.nanmax(np.abs(np.where(np.isfinite(dm), dm, -np.inf)), axis=0)
        rms = np.where(n > 0, rms, np.nan)
        mean = np.where(n > 0, mean, np.nan)
        mx = np.where(n > 0, mx, np.nan)
        lu, lf = length_unit(np.abs(dm), self.s.units.length)
        d = decimals(lu)
        v: dict[str, Any] = {
            "ids": ids,
            "difference_m": dm,
            "rms_m": rms,
            "mean_m": mean,
            "max_abs_m": mx,
            "n": n,
            "unit": lu,
        }
        items = [
            (
                "check points",
                f"{chk.size} ({int(np.sum(np.all(np.isfinite(dm), axis=1)))} "
                "with estimated coordinates)",
            )
        ]
        rows = [
            ["μ (r.m.s.)", *(fmt(x * lf, d) for x in rms)],
            ["mean", *(fmt(x * lf, d) for x in mean)],
            ["max abs", *(fmt(x * lf, d) for x in mx)],
            ["n", *(str(int(x)) for x in n)],
        ]
        t1 = Table(
            ["", f"X [{lu}]", f"Y [{lu}]", f"Z [{lu}]"],
            rows,
            title="differences estimated − given at the check points",
        )
        tables = [t1]
        scale = self._image_scale()
        s0i = self._sigma0_image_mm()
        if scale is not None and s0i is not None and s0i > 0:
            ratio = rms / scale * 1000.0 / s0i  # m in the object → mm in the image
            v.update(image_scale=scale, mu_over_sigma0=ratio)
            items.append(("image scale 1 : m_b", f"1 : {scale:,.0f}".replace(",", " ")))
            items.append(
                (
                    "μ/σ0 in image scale (μ / m_b / σ0 in the image)",
                    ", ".join(f"{a} {fmt(x, 2)}" for a, x in zip("XYZ", ratio)),
                )
            )
            items.append(
                (
                    "μ in the image (μ / m_b)",
                    ", ".join(f"{a} {fmt(x / scale * 1e6, 2)} µm" for a, x in zip("XYZ", rms)),
                )
            )
            items.append(("σ0 a posteriori in the image", f"{fmt(s0i * 1000, 2)} µm"))
        order = np.argsort(-np.nan_to_num(np.linalg.norm(dm, axis=1), nan=-1.0))
        rows2 = [
            [
                ids[k],
                *(fmt(x * lf, d) for x in dm[k]),
                fmt(float(np.linalg.norm(dm[k, :2])) * lf, d),
            ]
            for k in order[:MAX_ROWS]
        ]
        tables.append(
            Table(
                ["point", f"ΔX [{lu}]", f"ΔY [{lu}]", f"ΔZ [{lu}]", f"ΔXY [{lu}]"],
                rows2,
                title="check points, largest difference first",
            )
        )
        sec = Section("check", "Check-point statistics", items=items, tables=tables, values=v)
        sec.text = [
            "Check points take no part in the adjustment: they are intersected from the "
            "adjusted orientations and compared with their given coordinates."
        ]
        self.plot["check"] = {"xy": blk.points.xyz_known[chk, :2], "d": dm}
        return sec

    def _image_scale(self) -> float | None:
        blk, s = self.block, self.s
        if blk is None or not s.image_ids or len(blk.cameras) == 0:
            return None
        Z0 = np.asarray(s.X0, float)[:, 2]
        zg = np.nanmean(np.asarray(s.xyz, float)[:, 2]) if len(s.point_ids) else np.nan
        c = float(np.mean(blk.cameras.c)) / 1000.0
        h = float(np.nanmean(Z0) - zg)
        if not np.isfinite(h) or h <= 0 or c <= 0:
            return None
        return h / c

    def _sigma0_image_mm(self) -> float | None:
        adj = self.adj
        sl = image_slice(adj, self.s)
        img = np.zeros(adj.n_observations, bool)
        img[sl] = True
        img &= self.used
        if not img.any() or self.s.observation_quantity != "image":
            return None
        return float(adj.sigma0) * float(np.median(adj.sigma_obs[img]))
