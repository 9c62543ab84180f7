"""The datum options of a block: ``--fix`` / ``options.fix`` and ``--free`` / ``options.free``.

Without them the datum comes from the control points (and observed orientations). With

* ``fix``: a list of ``"ID"`` or ``"ID:PART,PART"`` — the named images' orientations
  (parts X0 Y0 Z0 omega phi kappa; all six by default) or points' coordinates (X Y Z)
  are held at their given values. An image is held by a pseudo-observation of its
  approximation with σ = ``FIX_SIGMA_M`` / ``FIX_SIGMA_RAD`` (it shows as ``ID/X0_obs`` …
  among the residuals), a point becomes a control point with σ = 0 in those
  coordinates. Fixing one image's six parameters and one coordinate of a second image's
  centre is the classic datum of a block without control.
* ``free``: a free network. Control and check points become tie points (their given
  coordinates are only approximations) and the datum is the minimum: of the pair of
  images whose number of shared points times base length is largest, the first image's
  orientation and the largest base component to the second image, held at their
  approximate values (a long base holds the scale firmly: a pair that shares many
  points but stands almost at one place would hang the scale on a few centimetres, and
  Gauss-Newton then creeps). The optimum does not depend on the datum; estimates and σ
  refer to it.

Units: m, rad (the block's).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..block import CONTROL, TIE, Block
from ..errors import InputError

#: σ of the pseudo-observations that hold a fixed image's centre (m) and attitude (rad).
FIX_SIGMA_M: float = 1e-6
FIX_SIGMA_RAD: float = 1e-9
IMAGE_PARTS = ("X0", "Y0", "Z0", "omega", "phi", "kappa")
POINT_PARTS = ("X", "Y", "Z")


def parse_fix(specs, source: str | None = None) -> list[tuple[str, tuple[str, ...]]]:
    """``["img1", "img2:X0", "p7:Z"]`` → [(id, parts or ())] (InputError if malformed)."""
    if isinstance(specs, str):
        specs = [specs]
    out = []
    for spec in specs or []:
        if not isinstance(spec, str) or not spec.strip():
            raise InputError(
                f"fix: expected an id or 'ID:PART,PART', got {spec!r}", source, "options.fix"
            )
        ident, _, parts = spec.rpartition(":") if ":" in spec else (spec, "", "")
        names = tuple(p.strip() for p in parts.split(",") if p.strip())
        bad = [p for p in names if p not in IMAGE_PARTS + POINT_PARTS]
        if bad:
            raise InputError(
                f"fix {spec!r}: unknown part(s) {', '.join(bad)}; images have "
                f"{' '.join(IMAGE_PARTS)}, points {' '.join(POINT_PARTS)}",
                source,
                "options.fix",
            )
        out.append((ident.strip(), names))
    return out


def apply_fix(block: Block, specs: list[tuple[str, tuple[str, ...]]]) -> Block:
    """A copy of ``block`` with the named images/points held at their given values."""
    if not specs:
        return block
    out = block.copy()
    images = {k: i for i, k in enumerate(block.images.ids)}
    points = {k: i for i, k in enumerate(block.points.ids)}
    src = block.meta.get("source")
    for ident, parts in specs:
        img_parts = [p for p in parts if p in IMAGE_PARTS]
        pt_parts = [p for p in parts if p in POINT_PARTS]
        if ident in images and not pt_parts:
            i = images[ident]
            for p in img_parts or IMAGE_PARTS:
                k = IMAGE_PARTS.index(p)
                if k < 3:
                    out.images.X0_obs[i, k] = block.images.X0[i, k]
                    out.images.X0_sigma[i, k] = FIX_SIGMA_M
                else:
                    out.images.angles_obs[i, k - 3] = block.images.angles[i, k - 3]
                    out.images.angles_sigma[i, k - 3] = FIX_SIGMA_RAD
            if not np.all(np.isfinite(block.images.X0[i])) or not np.all(
                np.isfinite(block.images.angles[i])
            ):
                raise InputError(
                    f"fix: image {ident!r} has no given orientation to hold", src, "options.fix"
                )
        elif ident in points and not img_parts:
            i = points[ident]
            cols = [POINT_PARTS.index(p) for p in (pt_parts or POINT_PARTS)]
            given = (
                block.points.xyz_known[i]
                if block.points.role[i] == CONTROL
                else block.points.xyz[i]
            )
            if not np.all(np.isfinite(given[cols])):
                raise InputError(
                    f"fix: point {ident!r} has no given coordinate(s) {' '.join(POINT_PARTS[c] for c in cols)}",
                    src,
                    "options.fix",
                )
            known = (
                out.points.xyz_known[i] if block.points.role[i] == CONTROL else np.full(3, np.nan)
            )
            sigma = out.points.sigma[i] if block.points.role[i] == CONTROL else np.full(3, np.nan)
            known = known.copy()
            sigma = np.array(sigma, dtype=float).copy()
            known[cols] = given[cols]
            sigma[cols] = 0.0
            out.points.role[i] = CONTROL
            out.points.xyz_known[i] = known
            out.points.sigma[i] = sigma
        else:
            what = "image or point" if not parts else ("image" if img_parts else "point")
            raise InputError(f"fix: no {what} {ident!r} in the block", src, "options.fix")
    return out


def free_network(block: Block) -> tuple[Block, str]:
    """Control and check points as tie points (given coordinates as approximations).

    Points seen in one image only (control points may be) cannot be intersected in a free
    network: they are left out (in memory only); the note names them.
    """
    out = block.copy()
    pts = out.points
    given = ~np.isfinite(pts.xyz).all(axis=1) & np.isfinite(pts.xyz_known).all(axis=1)
    pts.xyz[given] = pts.xyz_known[given]
    pts.role[:] = TIE
    pts.xyz_known[:] = np.nan
    pts.sigma[:] = np.nan
    keep = block.rays_per_point() >= 2
    if keep.all():
        return out, ""
    dropped = [block.points.ids[i] for i in np.flatnonzero(~keep)]
    new = -np.ones(block.n_points, np.int64)
    new[keep] = np.arange(int(keep.sum()))
    o = out.observations
    rays = keep[o.point]
    out.points = type(pts)([pts.ids[i] for i in np.flatnonzero(keep)], pts.xyz[keep],
                           pts.role[keep], pts.xyz_known[keep], pts.sigma[keep])  # fmt: skip
    out.observations = type(o)(o.image[rays], new[o.point[rays]], o.xy[rays], o.sigma[rays])
    more = f" and {len(dropped) - 8} more" if len(dropped) > 8 else ""
    return out, (
        f"free network: {len(dropped)} point(s) seen in one image only left out: "
        f"{', '.join(dropped[:8])}{more}"
    )


def minimum_datum(block: Block) -> tuple[Block, str]:
    """Hold 7 parameters at their approximations: of the image pair whose shared points
    times base length (m) is largest, the first image (6) and the largest base component
    to the second image (1); with no base at all (every centre at one place), the pair
    sharing the most points. Returns the block and a note."""
    obs = block.observations
    m, p = block.n_images, block.n_points
    M = sp.csr_matrix((np.ones(obs.image.size), (obs.image, obs.point)), shape=(m, p))
    M.data[:] = 1.0
    common = (M @ M.T).tocoo()
    off = common.row != common.col
    if not off.any():
        raise InputError(
            "a free network needs two images that share points", block.meta.get("source")
        )
    X0 = block.images.X0
    length = np.linalg.norm(X0[common.col] - X0[common.row], axis=1)
    score = np.where(off, common.data * np.nan_to_num(length), -1.0)
    if not score.max() > 0:
        score = np.where(off, common.data, -1.0)
    best = int(np.argmax(score))
    a, b = int(common.row[best]), int(common.col[best])
    base = X0[b] - X0[a]
    c = int(np.argmax(np.abs(base)))
    ida, idb = block.images.ids[a], block.images.ids[b]
    out = apply_fix(block, [(ida, ()), (idb, (IMAGE_PARTS[c],))])
    note = (
        f"free network: control and check points are tie points; datum by minimum constraints — "
        f"image {ida} (all six) and {IMAGE_PARTS[c]} of image {idb} held at their approximate "
        "values; σ of points and images refer to this datum"
    )
    return out, note
