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

A BAL file carries no pixel size; the default 0.010 mm (10 µm) is the bench's. f, k1
and k2 become each camera's forward lens model (:mod:`orientviz.bundle.model._lens`),
refined per camera as a BAL problem defines it or held (``lens="fixed"``); the
observations stay the file's distorted pixels. BAL has no principal point: a block
written back measures its observations from its cameras' principal points. BAL has no
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
from .colmap_scan import parse_numbers, tokenize
from .datasets import resolve_name
from .importing import import_to_problem
from .problem import load_problem
from .safeio import decode_text, read_input_bytes, read_input_text, write_atomic

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
    fields as numbers and names the line of the first bad one. ``values``: every field
    already read as a number (a plain file, :func:`_plain_fields`), else each section's
    fields are read when taken.
    """

    def __init__(
        self, text: str, counts: NDArray[np.int64], source: str, values: F64 | None = None
    ) -> None:
        self.source = source
        self.text = text
        self.counts = counts  # fields per line
        self.n_lines = counts.size
        self.values = values
        self.n_words = int(counts.sum())
        self._words: list[str] | None = None
        self.pos = 0

    @property
    def words(self) -> list[str]:
        """The fields of every line, in order (split on first use)."""
        if self._words is None:
            self._words = self.text.split()
        return self._words

    def fail(self, message: str, k: int | None = None) -> InputError:
        """An InputError at the line of field ``k`` (default: the last line of the file)."""
        if k is not None and k < self.n_words:  # the line of each field (only to fail)
            line = np.repeat(np.arange(1, self.n_lines + 1), self.counts)
            no = int(line[k])
        else:
            no = self.n_lines
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
        if first + count > self.n_words:
            raise self.fail(
                f"expected {count} numbers for {what}, the file ends after {self.n_words - first}"
            )
        self.pos += count
        if self.values is not None:
            arr = self.values[first : first + count]
        else:
            out = self.words[first : first + count]
            try:
                arr = np.array(out, dtype=float)
            except ValueError:
                bad = np.array([not _is_float(t) for t in out])
                self.first_bad(
                    bad, first, 1, lambda i: f"expected a number in {what}, got {out[i]!r}"
                )
                raise  # pragma: no cover - numpy and float() disagree
        self.first_bad(
            ~np.isfinite(arr), first, 1,
            lambda i: f"expected a finite number in {what}, got {self.words[first + i]!r}",
        )  # fmt: skip
        return arr


def _is_float(t: str) -> bool:
    try:
        float(t)
    except ValueError:
        return False
    return True


def _plain_fields(text: str) -> tuple[NDArray[np.int64], F64 | None] | None:
    """The number of fields on each line of ``text`` (its lines as ``str.splitlines``
    gives them) and every field as a number, in one pass over its bytes
    (:func:`~orientviz.io.colmap_scan.parse_numbers`, correctly rounded as ``float``
    reads them; None for the numbers when a field is not one).

    None unless the text is ASCII with only spaces, tabs, ``\\n`` and ``\\r\\n``
    between its fields.
    """
    if not text.isascii():
        return None
    u = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    sep = u <= 32
    ctrl = u[sep]
    ctrl = ctrl[ctrl != 32]
    if ctrl.size and not np.all((ctrl == 9) | (ctrl == 10) | (ctrl == 13)):
        return None
    cr = np.flatnonzero(u == 13)
    if cr.size and (cr[-1] + 1 == u.size or np.any(u[cr + 1] != 10)):
        return None  # a lone CR breaks a line for splitlines
    if u.size and u[-1] != 10:  # tokenize reads complete lines
        u = np.append(u, np.uint8(10))
    tok = tokenize(u)
    counts = np.bincount(tok.line, minlength=tok.n_lines).astype(np.int64)
    values, bad = parse_numbers(u, tok.start, tok.end)
    return counts, (None if bad.size else values)


def _parse(text: str, source: str) -> tuple[F64, F64, F64]:
    """Check and split a BAL file: observations (n, 4), camera parameters (m, 9), xyz (p, 3)."""
    plain = _plain_fields(text)
    if plain is None:  # other line breaks or blanks: line by line
        counts = np.array([len(ln.split()) for ln in text.splitlines()], dtype=np.int64)
        tok = _Tokens(text, counts, source)
    else:
        counts, values = plain
        tok = _Tokens(text, counts, source, values)
    head = text.split(None, int(counts[0]))[: counts[0]] if counts.size else []
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
    if counts.size < 1 + nobs:
        raise tok.fail(f"expected {nobs} observation lines, the file ends at line {counts.size}")
    counts = counts[1 : 1 + nobs]
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
    if tok.pos < tok.n_words:
        raise tok.fail(
            f"expected {tok.pos} numbers for the counts {nc} {npt} {nobs} of the header, "
            f"the file has {tok.n_words - tok.pos} more",
            tok.pos,
        )
    tok.first_bad(
        ~(cams[:, 6] > 0), first_cam + 6, 9,
        lambda i: f"expected a focal length f > 0 px, got {tok.words[first_cam + 9 * i + 6]} "
        f"(camera {i})",
    )  # fmt: skip
    return obs, cams, pts


def read_bal_arrays(path: str | os.PathLike[str]) -> tuple[F64, F64, F64]:
    """The three tables of a BAL file (plain or ``*.bz2``) as they stand, BAL's units.

    Returns
    -------
    (obs, cams, pts)
        ``obs`` (n, 4): camera index, point index, x, y (px, BAL's signs); ``cams``
        (m, 9): angle-axis rotation (rad), translation, f (px), k1, k2; ``pts`` (p, 3).
    """
    return _parse(_read_text(path), str(path))


#: What :func:`read_bal` does with each camera's f, k1, k2.
LENS_MODES = ("refine", "fixed")
#: The lens terms of a BAL camera in orientviz's forward model (f is the model's c).
BAL_TERMS = ("c", "k1", "k2")


def read_bal(
    path: str | os.PathLike[str],
    *,
    pixel_size_mm: float = DEFAULT_PIXEL_MM,
    sigma_px: float = 1.0,
    sequence: str = "opk",
    lens: str = "refine",
) -> Block:
    """Read a BAL file into a :class:`~orientviz.block.Block` (all points tie points).

    Each BAL camera becomes its own camera with the forward lens model of
    :mod:`orientviz.bundle.model._lens` (the distortion of the ideal point, as BAL defines it):
    c = f · pixel size (mm), x0 = y0 = 0, k1 and k2 as in the file. The observations are
    the file's pixels (distorted) in mm, so the residuals are BAL's reprojection errors.

    Parameters
    ----------
    path : path-like
        The BAL text file.
    pixel_size_mm : float
        Size of one pixel in mm (default 0.010 mm); it only scales the image units.
    sigma_px : float
        A-priori σ of the image coordinates in pixels (default 1 px).
    sequence : {"opk", "pok"}
        Rotation sequence of the block's angles.
    lens : {"refine", "fixed"}
        ``"refine"`` (default, as a BAL problem is defined): f, k1, k2 of every camera
        are free in the bundle (``cameras[].free = ["c", "k1", "k2"]``); ``"fixed"``:
        they are held at the file's values (only the poses and points are adjusted).

    Returns
    -------
    Block
        One camera per BAL camera (ids ``cam0``, ``cam1``, …) with its lens spec in
        ``cameras.model`` (what ``orientviz solve`` and ``bundle_adjust(block)`` estimate;
        :func:`orientviz.bundle.block_camera_options`),
        image coordinates in mm (y up, origin at the image centre), X0 and points in the
        file's length unit, angles in rad.

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
    if lens not in LENS_MODES:
        raise InputError(f"lens: expected one of {', '.join(LENS_MODES)}, got {lens!r}", source)
    obs, cams, pts = _parse(_read_text(path), source)
    nc, npt = cams.shape[0], pts.shape[0]
    ci, pi = obs[:, 0].astype(np.int64), obs[:, 1].astype(np.int64)
    Rb = matrix_from_rotvec(cams[:, :3])
    R = np.swapaxes(Rb, 1, 2)
    X0 = -np.einsum("nij,nj->ni", R, cams[:, 3:6])
    om, ph, ka = opk_from_matrix(R, sequence)
    xy = obs[:, 2:4] * pixel_size_mm
    # BAL has no image size: the format is the extent of all observations about the centre
    half = 2.0 * float(np.max(np.abs(xy))) if xy.size else 1.0
    free = list(BAL_TERMS) if lens == "refine" else []
    models = [
        {"model": "forward", "free": free, "sigma": {},
         "values": {"k1": float(k1), "k2": float(k2)}, "r0": None}
        for k1, k2 in cams[:, 7:9].tolist()
    ]  # fmt: skip
    block = Block.from_arrays(
        camera_c=cams[:, 6] * pixel_size_mm,
        camera_ids=[f"cam{i}" for i in range(nc)],
        camera_format_mm=(half, half),
        image_camera=np.arange(nc),
        image_ids=[f"img{i}" for i in range(nc)],
        X0=X0,
        angles=np.column_stack([om, ph, ka]),
        xyz=pts.reshape(npt, 3),
        obs_image=ci,
        obs_point=pi,
        obs_xy=xy,
        obs_sigma=sigma_px * pixel_size_mm,
        sequence=sequence,
        meta={"source": source, "format": "BAL", "pixel_size_mm": pixel_size_mm,
              "lens": lens},
    )  # fmt: skip
    block.cameras.model = models
    return block


#: A compressed BAL file (``*.bz2``, as the BAL collection publishes them) may expand to
#: at most this many bytes.
MAX_BZ2_BYTES: int = 1 << 31
#: The BAL problem shipped with orientviz (``orientviz import-bal ladybug``).
SHIPPED = {"ladybug": "problem-49-7776-pre.txt.bz2"}


def shipped_bal(name: str = "ladybug") -> Path:
    """Path of a BAL problem shipped in ``orientviz/datasets/bal`` (see its MANIFEST.json:
    Agarwal et al.'s Ladybug problem-49-7776, bz2-compressed)."""
    from importlib import resources

    if name not in SHIPPED:
        raise InputError(f"no shipped BAL problem {name!r} (shipped: {', '.join(SHIPPED)})")
    return Path(str(resources.files("orientviz.datasets").joinpath("bal", SHIPPED[name])))


def _read_text(path: str | os.PathLike[str]) -> str:
    """The text of a BAL file, plain or bz2-compressed (``*.bz2``)."""
    if not str(path).endswith(".bz2"):
        return read_input_text(path, "a BAL text file")
    import bz2

    raw = read_input_bytes(path, "a bz2-compressed BAL file")
    unzip = bz2.BZ2Decompressor()
    try:
        data = unzip.decompress(raw, max_length=MAX_BZ2_BYTES)
    except (OSError, ValueError) as exc:
        raise InputError(f"not a bz2 file: {exc}", str(path)) from None
    if not unzip.eof:
        raise InputError(
            f"the bz2 data expand beyond {MAX_BZ2_BYTES} bytes or are truncated", str(path)
        )
    return decode_text(data, str(path), "a BAL text file")


def bal_cameras(block: Block, pixel_size_mm: float) -> F64:
    """The nine BAL parameters (r, t, f, k1, k2) per image of ``block``, shape (m, 9).

    R_bal = Rᵀ as angle-axis, t = −R_bal X0, f = c / pixel size; k1, k2 from the image's
    camera's forward lens model (``cameras.model``; 0 without one). The principal point is
    not a BAL parameter: :func:`write_bal` measures the observations from it. A camera BAL
    cannot express (a backward model, other forward terms ≠ 0) is refused.
    """
    cams = block.cameras
    models = list(getattr(cams, "model", None) or [{}] * len(cams))
    k = np.zeros((len(cams), 2))
    for i, spec in enumerate(models):
        if not spec:
            continue
        if spec.get("model") != "forward":
            what = spec.get("model") or f"additional {spec.get('additional')!r}"
            raise InputError(f"camera {cams.ids[i]!r}: BAL cameras have the forward lens "
                             f"model (f, k1, k2), this one has {what}")  # fmt: skip
        values = spec.get("values", {})
        other = {n: v for n, v in values.items() if n not in ("k1", "k2") and v != 0}
        if other:
            raise InputError(f"camera {cams.ids[i]!r}: BAL cameras have f, k1, k2 only, "
                             f"this one also {', '.join(other)}")  # fmt: skip
        k[i] = values.get("k1", 0.0), values.get("k2", 0.0)
    cam = block.images.camera
    a = block.images.angles
    R = matrix_from_opk(a[:, 0], a[:, 1], a[:, 2], block.sequence)
    Rb = np.swapaxes(R, 1, 2)
    t = -np.einsum("nij,nj->ni", Rb, block.images.X0)
    f = cams.c[cam] / pixel_size_mm
    return np.column_stack([rotvec_from_matrix(Rb), t, f, k[cam]])


def write_bal(
    block: Block, path: str | os.PathLike[str], *, pixel_size_mm: float | None = None
) -> Path:
    """Write a block as a BAL file, the inverse of :func:`read_bal`.

    Image coordinates mm → px, y up, measured from each camera's principal point
    (x − x0, y − y0: BAL's origin; the forward lens model distorts about that point, so a
    COLMAP camera with its principal point anywhere keeps its projection exactly). Cameras
    by :func:`bal_cameras` (k1, k2 from the cameras' forward lens models, else 0).
    ``pixel_size_mm`` defaults to the block's ``meta["pixel_size_mm"]``, else 0.010 mm.
    """
    p = float(pixel_size_mm or block.meta.get("pixel_size_mm") or DEFAULT_PIXEL_MM)
    params = bal_cameras(block, p)
    obs = block.observations
    cam = block.images.camera[obs.image]
    pp = np.column_stack([block.cameras.x0, block.cameras.y0])[cam]
    xy = obs.xy / p if not pp.any() else (obs.xy - pp) / p
    text = "".join(
        [
            f"{block.n_images} {block.n_points} {block.n_observations}\n",
            *(
                f"{c} {p_} {x:.9f} {y:.9f}\n"
                for c, p_, x, y in zip(
                    obs.image.tolist(), obs.point.tolist(), xy[:, 0].tolist(), xy[:, 1].tolist()
                )
            ),
            *(f"{v:.17g}\n" for v in params.ravel().tolist()),
            *(f"{v:.17g}\n" for v in block.points.xyz.ravel().tolist()),
        ]
    )
    return write_atomic(path, text)


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz import-bal FILE -o OUT.json [--fix-lens] [--control CSV]``: BAL → problem file."""
    if not os.path.exists(args.file) and args.file in SHIPPED:
        args.file = str(shipped_bal(args.file))
    lens = "fixed" if getattr(args, "fix_lens", False) else "refine"
    note = (
        "; f, k1, k2 of each camera held at the file's values (--fix-lens)"
        if lens == "fixed"
        else "; f, k1, k2 of each camera free (forward lens model, as BAL defines the "
        "problem; --fix-lens holds them)"
    )
    return import_to_problem(
        args,
        lambda px, sig: read_bal(args.file, pixel_size_mm=px, sigma_px=sig, lens=lens),
        Path(args.file).name.split(".")[0],
        default_pixel_mm=DEFAULT_PIXEL_MM,
        pixel_units=True,
        lens_note=note,
    )


def run_export(args: argparse.Namespace) -> int:
    """``orientviz export-bal FILE.json -o OUT.bal``: a block problem file → BAL file."""
    import sys

    prog = "orientviz export-bal"
    try:
        problem = load_problem(resolve_name(args.file))
        if problem.kind != "block":
            raise InputError(f"expected a block problem, got kind {problem.kind!r}", args.file)
        u = problem.units
        px = getattr(args, "pixel_size", None) or (
            u.pixel_size if u.image == "px" else DEFAULT_PIXEL_MM
        )
        block = problem.data
        bad = [i for i, x in enumerate(block.points.xyz) if not np.all(np.isfinite(x))]
        if bad:
            raise InputError(
                f"point {block.points.ids[bad[0]]!r} has no coordinates ({len(bad)} such "
                "point(s)): BAL needs every point; solve the file with -o first",
                args.file,
            )
        write_bal(block, args.output, pixel_size_mm=px)
    except InputError as exc:
        if not exc.source:
            exc = InputError(exc.message, args.file, exc.where)
        print(f"{prog}: {exc.one_line()}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}: {block.summary()} (pixel size {px} mm)")
    return 0
