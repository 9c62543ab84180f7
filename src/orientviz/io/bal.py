"""BAL files ("Bundle Adjustment in the Large", Agarwal et al.): read, write, import.

The text format::

    <n_cameras> <n_points> <n_observations>
    <camera> <point> <x> <y>                 × n_observations   (pixels)
    <r1> <r2> <r3> <t1> <t2> <t3> <f> <k1> <k2>   × n_cameras (one number per line)
    <X> <Y> <Z>                              × n_points      (one number per line)

Camera model (as written by the peer bench's ``make_block.py``): ``P = R_bal·X + t``
with R_bal from the angle-axis vector r (Rodrigues), ``p = −P / P_z``,
``x_px = f · (1 + k1·|p|² + k2·|p|⁴) · p`` — origin at the image centre, y up, the
camera looking along −z. This *is* the photogrammetric camera of
:mod:`orientviz.camera`, so no axis flip is needed:

* R (image → object) = R_balᵀ; ω, φ, κ follow from R in the block's sequence
  (default ``"opk"``: R = R_ω R_φ R_κ),
* X0 = −R_balᵀ t (m, or whatever length unit the file uses),
* c = f · pixel size (mm), image coordinates x_mm = x_px · pixel size.

A BAL file carries no pixel size; the default 0.010 mm (10 µm) is the bench's. Radial
distortion (k1, k2 ≠ 0) is removed from the observations at import (iteratively,
normalised coordinates), so the block holds distortion-free coordinates. BAL has no
control points: an imported block is a free network (7 datum parameters) until control
is added.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..errors import InputError
from ..rotation import matrix_from_opk, matrix_from_rotvec, opk_from_matrix, rotvec_from_matrix

F64 = NDArray[np.float64]
#: Pixel size (mm) assumed when none is given: 10 µm, as in the peer bench.
DEFAULT_PIXEL_MM: float = 0.010
#: Image coordinates beyond ± this many pixels are refused (no sensor is that large).
MAX_PIXELS: float = 1e7
#: Camera parameters and coordinates beyond ± this are refused (not adjustable in doubles).
MAX_VALUE: float = 1e15


class _Tokens:
    """All whitespace-separated fields of a BAL file, with the 1-based line of each.

    One reader for every section (observations, cameras, points): it hands out the next
    fields as numbers and names the line of the first bad one.
    """

    def __init__(self, lines: list[str], source: str) -> None:
        fields = [ln.split() for ln in lines]
        self.source = source
        self.n_lines = len(lines)
        self.words = [w for f in fields for w in f]
        self.line = np.repeat(np.arange(1, len(lines) + 1), [len(f) for f in fields])
        self.pos = 0

    def fail(self, message: str, k: int | None = None) -> InputError:
        """An InputError at the line of field ``k`` (default: the last line of the file)."""
        no = int(self.line[k]) if k is not None and k < self.line.size else self.n_lines
        return InputError(message, self.source, f"line {max(no, 1)}")

    def first_bad(self, bad: NDArray[np.bool_], start: int, stride: int, message) -> None:
        """Raise at the first True of ``bad``; item i sits at field ``start + stride·i``."""
        hit = np.flatnonzero(bad)
        if hit.size:
            i = int(hit[0])
            raise self.fail(message(i), start + stride * i)

    def take(self, count: int, what: str) -> F64:
        """The next ``count`` fields as finite floats."""
        first = self.pos
        if first + count > len(self.words):
            raise self.fail(
                f"expected {count} numbers for {what}, the file ends after "
                f"{len(self.words) - first}"
            )
        out = self.words[first : first + count]
        self.pos += count
        try:
            arr = np.array(out, dtype=float)
        except ValueError:
            bad = np.array([not _is_float(t) for t in out])
            self.first_bad(bad, first, 1, lambda i: f"expected a number in {what}, got {out[i]!r}")
            raise  # pragma: no cover - numpy and float() disagree
        self.first_bad(
            ~np.isfinite(arr), first, 1,
            lambda i: f"expected a finite number in {what}, got {out[i]!r}",
        )  # fmt: skip
        return arr


def _is_float(t: str) -> bool:
    try:
        float(t)
    except ValueError:
        return False
    return True


def _parse(lines: list[str], source: str) -> tuple[F64, F64, F64]:
    """Check and split a BAL file: observations (n, 4), camera parameters (m, 9), xyz (p, 3)."""
    tok = _Tokens(lines, source)
    head = lines[0].split() if lines else []
    try:
        nc, npt, nobs = (int(v) for v in head)
    except ValueError:
        raise InputError(
            f"expected a header '<cameras> <points> <observations>', got {' '.join(head)!r}",
            source,
            "line 1",
        ) from None
    if min(nc, npt, nobs) < 0:
        raise InputError("expected non-negative counts in the header", source, "line 1")
    if max(nc, npt, nobs) > 10**9:
        raise InputError("expected counts below 10^9 in the header", source, "line 1")
    tok.pos = 3
    if len(lines) < 1 + nobs:
        raise tok.fail(f"expected {nobs} observation lines, the file ends at line {len(lines)}")
    counts = np.array([len(ln.split()) for ln in lines[1 : 1 + nobs]], dtype=np.int64)
    wrong = np.flatnonzero(counts != 4)
    if wrong.size:
        k = int(wrong[0])
        raise InputError(
            f"expected 4 values '<camera> <point> <x> <y>', got {counts[k]}",
            source,
            f"line {k + 2}",
        )
    obs = tok.take(4 * nobs, "the observations").reshape(nobs, 4)
    for col, name, n in ((0, "camera", nc), (1, "point", npt)):
        idx = obs[:, col]
        tok.first_bad(
            (idx != np.round(idx)) | (idx < 0) | (idx >= n), 3 + col, 4,
            lambda i, name=name, n=n, col=col: (
                f"expected a {name} index in [0, {n}), got {tok.words[3 + 4 * i + col]}"
            ),
        )  # fmt: skip
    tok.first_bad(
        np.any(np.abs(obs[:, 2:4]) > MAX_PIXELS, axis=1), 5, 4,
        lambda i: f"image coordinate beyond ±{MAX_PIXELS:g} px: not a pixel position",
    )  # fmt: skip
    first_cam = tok.pos
    cams = tok.take(9 * nc, "the camera parameters").reshape(nc, 9)
    pts = tok.take(3 * npt, "the points").reshape(npt, 3)
    tok.first_bad(
        np.any(np.abs(cams) > MAX_VALUE, axis=1), first_cam, 9,
        lambda i: f"camera {i}: a parameter beyond ±{MAX_VALUE:g}",
    )  # fmt: skip
    tok.first_bad(
        np.any(np.abs(pts) > MAX_VALUE, axis=1), first_cam + 9 * nc, 3,
        lambda i: f"point {i}: a coordinate beyond ±{MAX_VALUE:g}",
    )  # fmt: skip
    if tok.pos < len(tok.words):
        raise tok.fail(
            f"expected {tok.pos} numbers for the counts {nc} {npt} {nobs} of the header, "
            f"the file has {len(tok.words) - tok.pos} more",
            tok.pos,
        )
    tok.first_bad(
        ~(cams[:, 6] > 0), first_cam + 6, 9,
        lambda i: f"expected a focal length f > 0 px, got {tok.words[first_cam + 9 * i + 6]} "
        f"(camera {i})",
    )  # fmt: skip
    return obs, cams, pts


def read_bal(
    path: str | os.PathLike[str],
    *,
    pixel_size_mm: float = DEFAULT_PIXEL_MM,
    sigma_px: float = 1.0,
    sequence: str = "opk",
) -> Block:
    """Read a BAL file into a :class:`~orientviz.block.Block` (all points tie points).

    Parameters
    ----------
    path : path-like
        The BAL text file.
    pixel_size_mm : float
        Size of one pixel in mm (default 0.010 mm).
    sigma_px : float
        A-priori σ of the image coordinates in pixels (default 1 px).
    sequence : {"opk", "pok"}
        Rotation sequence of the block's angles.

    Returns
    -------
    Block
        One camera per distinct f (c = f · pixel size, mm), image coordinates in mm,
        X0 and points in the file's length unit (m for the bench), angles in rad.

    Raises
    ------
    InputError
        Naming the file and line of a broken header, observation or parameter.
    """
    source = str(path)
    if not (np.isfinite(pixel_size_mm) and pixel_size_mm > 0):
        raise InputError(f"expected a pixel size > 0 mm, got {pixel_size_mm}", source)
    if not (np.isfinite(sigma_px) and sigma_px > 0):
        raise InputError(f"expected an image σ > 0 px, got {sigma_px}", source)
    from .safeio import read_input_text

    lines = read_input_text(path, "a BAL text file").splitlines()
    obs, cams, pts = _parse(lines, source)
    npt = pts.shape[0]
    ci, pi = obs[:, 0], obs[:, 1]
    f = cams[:, 6]
    Rb = matrix_from_rotvec(cams[:, :3])
    R = np.swapaxes(Rb, 1, 2)
    X0 = -np.einsum("nij,nj->ni", R, cams[:, 3:6])
    om, ph, ka = opk_from_matrix(R, sequence)
    # one camera per distinct principal distance
    fu, cam_of = np.unique(f, return_inverse=True)
    ci = ci.astype(np.int64)
    xy = obs[:, 2:4]
    k1, k2 = cams[ci, 7], cams[ci, 8]
    if np.any(k1 != 0) or np.any(k2 != 0):
        xy = _undistort(xy / f[ci][:, None], k1, k2) * f[ci][:, None]
    return Block.from_arrays(
        camera_c=fu * pixel_size_mm,
        image_camera=cam_of,
        X0=X0,
        angles=np.column_stack([om, ph, ka]),
        xyz=pts.reshape(npt, 3),
        obs_image=ci,
        obs_point=pi.astype(np.int64),
        obs_xy=xy * pixel_size_mm,
        obs_sigma=sigma_px * pixel_size_mm,
        sequence=sequence,
        meta={"source": source, "format": "BAL", "pixel_size_mm": pixel_size_mm},
    )


def _undistort(pd: F64, k1: F64, k2: F64, iterations: int = 20) -> F64:
    """Invert p_d = (1 + k1 r² + k2 r⁴) p for normalised coordinates (fixed point)."""
    p = pd.copy()
    for _ in range(iterations):
        r2 = np.sum(p**2, axis=1)
        p = pd / (1.0 + k1 * r2 + k2 * r2**2)[:, None]
    return p


def write_bal(
    block: Block, path: str | os.PathLike[str], *, pixel_size_mm: float = DEFAULT_PIXEL_MM
) -> Path:
    """Write a block as a BAL file (k1 = k2 = 0; principal points must be 0).

    Inverse of :func:`read_bal`: image coordinates mm → px, R_bal = Rᵀ as angle-axis,
    t = −R_bal X0, f = c / pixel size.
    """
    cam = block.images.camera
    if np.any(block.cameras.x0 != 0) or np.any(block.cameras.y0 != 0):
        raise InputError("BAL has no principal point: expected x0 = y0 = 0 for every camera")
    a = block.images.angles
    R = matrix_from_opk(a[:, 0], a[:, 1], a[:, 2], block.sequence)
    Rb = np.swapaxes(R, 1, 2)
    t = -np.einsum("nij,nj->ni", Rb, block.images.X0)
    f = block.cameras.c[cam] / pixel_size_mm
    params = np.column_stack([rotvec_from_matrix(Rb), t, f, np.zeros((len(f), 2))])
    obs = block.observations
    xy = obs.xy / pixel_size_mm
    from .safeio import write_atomic

    text = "".join(
        [
            f"{block.n_images} {block.n_points} {block.n_observations}\n",
            *(
                f"{c} {p} {x:.9f} {y:.9f}\n"
                for c, p, x, y in zip(
                    obs.image.tolist(), obs.point.tolist(), xy[:, 0].tolist(), xy[:, 1].tolist()
                )
            ),
            *(f"{v:.17g}\n" for v in params.ravel().tolist()),
            *(f"{v:.17g}\n" for v in block.points.xyz.ravel().tolist()),
        ]
    )
    return write_atomic(path, text)


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz import-bal FILE -o OUT.json [--control CSV]``: BAL file → problem file."""
    from .importing import import_to_problem

    return import_to_problem(
        args,
        lambda px, sig: read_bal(args.file, pixel_size_mm=px, sigma_px=sig),
        Path(args.file).stem,
        default_pixel_mm=DEFAULT_PIXEL_MM,
    )
