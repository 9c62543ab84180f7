"""COLMAP text models (cameras.txt, images.txt, points3D.txt) ↔ :class:`~orientviz.model.Block`.

Conventions
-----------
COLMAP stores world → camera poses ``X_cam = R_cw X + t`` with quaternion
``(qw, qx, qy, qz)``, a camera frame with x right, y *down*, z forward, and pixel
coordinates with the origin at the upper-left corner of the image (the centre of the
first pixel at (0.5, 0.5)). orientviz uses the photogrammetric frame (x right, y *up*,
viewing along −z), image coordinates in mm and R image → object. Hence

    R_orientviz = R_cwᵀ · diag(1, −1, −1),   X0 = −R_cwᵀ t,
    x_mm = (u − cx) · p,   y_mm = −(v − cy) · p,   c = f · p,

with a nominal pixel size ``p`` in mm (default 0.01 mm = 10 µm; it only scales image
units, the adjustment is unchanged). Lens distortion of the COLMAP camera models
(SIMPLE_RADIAL, RADIAL, OPENCV) is removed from the observations at import (iterative
inversion), so the Block holds distortion-free image coordinates; the parameters are
kept in ``block.meta["colmap_cameras"]`` and restored on export. Angles come out in the
block's sequence (ω-φ-κ by default).

Broken files raise :class:`~orientviz.errors.InputError` naming the file and line.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..model import CHECK, CONTROL, Block
from ..rotation import opk_from_matrix

FLIP = np.diag([1.0, -1.0, -1.0])
#: Coordinates and translations beyond ± this are refused (not adjustable in doubles).
MAX_VALUE: float = 1e15

#: COLMAP camera models understood here: name → parameter names.
CAMERA_MODELS: dict[str, tuple[str, ...]] = {
    "SIMPLE_PINHOLE": ("f", "cx", "cy"),
    "PINHOLE": ("fx", "fy", "cx", "cy"),
    "SIMPLE_RADIAL": ("f", "cx", "cy", "k"),
    "RADIAL": ("f", "cx", "cy", "k1", "k2"),
    "OPENCV": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"),
}


@dataclass
class _Camera:
    model: str
    width: int
    height: int
    params: NDArray[np.float64]

    def focal(self) -> float:
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return float(p.get("f", 0.5 * (p.get("fx", 0.0) + p.get("fy", 0.0))))

    def principal_point(self) -> tuple[float, float]:
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return float(p["cx"]), float(p["cy"])

    def distortion(self) -> tuple[float, float, float, float]:
        """k1, k2, p1, p2 (zeros where the model has none)."""
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return (p.get("k", p.get("k1", 0.0)), p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0))


def _read(path: Path) -> str:
    """The text of a model file, checked (:func:`~orientviz.io.safeio.read_input_text`)."""
    from .safeio import read_input_text

    return read_input_text(path, f"a COLMAP text file {path.name}")


def _lines(path: Path):
    text = _read(path)
    for no, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            yield no, s


def _numbers(path: Path, no: int, fields: list[str], kinds: str, what: str) -> list:
    if len(fields) < len(kinds):
        raise InputError(
            f"expected {what} with {len(kinds)} fields, got {len(fields)}",
            source=str(path),
            where=f"line {no}",
        )
    out = []
    for i, (f, k) in enumerate(zip(fields, kinds)):
        try:
            v = int(f) if k == "i" else float(f) if k == "f" else f
        except ValueError:
            raise InputError(
                f"field {i + 1} of {what}: expected {'an integer' if k == 'i' else 'a number'}, "
                f"got {f!r}",
                source=str(path),
                where=f"line {no}",
            ) from None
        if k == "f" and not np.isfinite(v):
            raise InputError(
                f"field {i + 1} of {what}: expected a finite number, got {f!r}",
                source=str(path),
                where=f"line {no}",
            )
        out.append(v)
    return out


def _read_cameras(path: Path) -> dict[int, _Camera]:
    cams: dict[int, _Camera] = {}
    for no, line in _lines(path):
        f = line.split()
        cid, model, w, h = _numbers(path, no, f, "isii", "a camera")
        if model not in CAMERA_MODELS:
            raise InputError(
                f"camera model {model!r} is not supported (supported: {', '.join(CAMERA_MODELS)})",
                source=str(path),
                where=f"line {no}",
            )
        names = CAMERA_MODELS[model]
        params = _numbers(path, no, f[4:], "f" * len(names), f"{model} parameters")
        if len(f) - 4 != len(names):
            raise InputError(
                f"{model} has {len(names)} parameters, got {len(f) - 4}",
                source=str(path),
                where=f"line {no}",
            )
        if cid in cams:
            raise InputError(f"duplicate camera id {cid}", source=str(path), where=f"line {no}")
        cam = _Camera(model, w, h, np.array(params))
        bad = _camera_problem(cam)
        if bad:
            raise InputError(f"camera {cid}: {bad}", source=str(path), where=f"line {no}")
        cams[cid] = cam
    if not cams:
        raise InputError("no cameras in the file", source=str(path), where=_end(path))
    return cams


def _camera_problem(cam: _Camera) -> str | None:
    """Why a camera cannot be used (sizes, focal length), or None."""
    if not (0 < cam.width < 10**7 and 0 < cam.height < 10**7):
        return f"expected WIDTH and HEIGHT of 1..10^7 pixels, got {cam.width} {cam.height}"
    p = dict(zip(CAMERA_MODELS[cam.model], cam.params))
    for name in ("f", "fx", "fy"):
        if name in p and not 0 < p[name] < 1e12:
            return f"expected a focal length {name} > 0 px (below 1e12), got {p[name]:g}"
    for name in ("cx", "cy"):
        if abs(p[name]) > 1e12:
            return f"principal point {name} = {p[name]:g} px lies far outside the image"
    return None


def _refuse_nonfinite(values: NDArray[np.float64], lines: list[int], path: Path, what: str):
    """Values that overflowed in the conversion (e.g. ±1e308 in a file) name their line."""
    bad = np.flatnonzero(~np.all(np.isfinite(values.reshape(len(values), -1)), axis=1))
    if bad.size:
        raise InputError(
            f"the {what} overflows after conversion (a value near ±1e308 in the file?)",
            source=str(path),
            where=f"line {lines[int(bad[0])]}",
        )


def _end(path: Path) -> str:
    """``"line N"`` of the last line of an existing text file (for "nothing found" errors)."""
    try:
        n = len(_read(path).splitlines())
    except InputError:
        n = 0
    return f"line {max(n, 1)}"


def _read_points(path: Path) -> tuple[list[int], list[list[float]], list[tuple[int, list[int]]]]:
    """POINT3D_ID, X, Y, Z and the TRACK image ids (with the line number) of points3D.txt."""
    pid: list[int] = []
    xyz: list[list[float]] = []
    tracks: list[tuple[int, list[int]]] = []
    seen: set[int] = set()
    for no, line in _lines(path):
        f = line.split()
        vals = _numbers(path, no, f, "ifff", "a 3D point")
        if max(abs(v) for v in vals[1:4]) > MAX_VALUE:
            raise InputError(
                f"a coordinate beyond ±{MAX_VALUE:g}: not a position",
                source=str(path),
                where=f"line {no}",
            )
        if vals[0] < 0:
            raise InputError(
                f"POINT3D_ID {vals[0]}: expected an id ≥ 0 (-1 is COLMAP's 'no 3D point')",
                source=str(path),
                where=f"line {no}",
            )
        if vals[0] in seen:
            raise InputError(
                f"duplicate POINT3D_ID {vals[0]}", source=str(path), where=f"line {no}"
            )
        seen.add(vals[0])
        track = f[8:]
        if len(track) % 2:
            raise InputError(
                f"expected TRACK[] as pairs IMAGE_ID POINT2D_IDX, got {len(track)} fields",
                source=str(path),
                where=f"line {no}",
            )
        ids = _numbers(path, no, track, "i" * len(track), "the TRACK") if track else []
        pid.append(vals[0])
        xyz.append(vals[1:4])
        tracks.append((no, ids[0::2]))
    return pid, xyz, tracks


def _undistort(cam: _Camera, uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """Remove COLMAP's radial/tangential distortion from pixel coordinates."""
    k1, k2, p1, p2 = cam.distortion()
    if k1 == k2 == p1 == p2 == 0.0:
        return uv
    p = dict(zip(CAMERA_MODELS[cam.model], cam.params))
    fx = p.get("fx", p.get("f"))
    fy = p.get("fy", p.get("f"))
    cx, cy = cam.principal_point()
    d = np.column_stack([(uv[:, 0] - cx) / fx, (uv[:, 1] - cy) / fy])
    u = d.copy()
    for _ in range(20):  # fixed-point inversion of x_d = x (1 + k1 r² + k2 r⁴) + tangential
        x, y = u[:, 0], u[:, 1]
        r2 = x * x + y * y
        radial = k1 * r2 + k2 * r2 * r2
        dx = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = y * radial + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)
        u = d - np.column_stack([dx, dy])
    return np.column_stack([u[:, 0] * fx + cx, u[:, 1] * fy + cy])


def read_colmap(
    directory: str | Path,
    *,
    pixel_size_mm: float = 0.01,
    sigma_px: float = 1.0,
    sequence: str = "opk",
) -> Block:
    """Read a COLMAP text model into a Block.

    Parameters
    ----------
    directory : str or Path
        Folder with ``cameras.txt``, ``images.txt`` and ``points3D.txt``.
    pixel_size_mm : float, default 0.01
        Nominal pixel size in mm used to express image coordinates in mm.
    sigma_px : float, default 1.0
        A-priori σ of the image coordinates in pixels.
    sequence : {"opk", "pok"}
        Rotation sequence for the returned angles.

    Returns
    -------
    Block
        All points as tie points (COLMAP has no control); object units are COLMAP's.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InputError(
            "expected a directory with cameras.txt, images.txt, points3D.txt", source=str(d)
        )
    cams = _read_cameras(d / "cameras.txt")
    cam_ids = sorted(cams)
    cam_index = {c: i for i, c in enumerate(cam_ids)}

    pts_path = d / "points3D.txt"
    pid, xyz, tracks = _read_points(pts_path)
    p_index = {p: i for i, p in enumerate(pid)}

    img_path = d / "images.txt"
    lines = list(_lines(img_path))
    # images.txt: two lines per image; the second (the 2D points) may be empty, which the
    # comment-stripping reader drops, so read by position in the raw text instead.
    raw = _read(img_path).splitlines()
    body = [(no, s) for no, s in enumerate(raw, start=1) if not s.strip().startswith("#")]
    image_ids, names, cam_of, X0s, Rs, img_lines = [], [], [], [], [], []
    oi, op, uv, obs_lines = [], [], [], []
    k = 0
    while k < len(body):
        no, s = body[k]
        if not s.strip():
            k += 1
            continue
        f = s.split()
        iid, qw, qx, qy, qz, tx, ty, tz, cid = _numbers(img_path, no, f, "ifffffffi", "an image")
        name = f[9] if len(f) > 9 else str(iid)
        if len(name) > 256:
            raise InputError(
                f"image NAME of {len(name)} characters, expected at most 256",
                source=str(img_path),
                where=f"line {no}",
            )
        if iid in image_ids:
            raise InputError(f"duplicate IMAGE_ID {iid}", source=str(img_path), where=f"line {no}")
        if cid not in cams:
            raise InputError(f"unknown camera id {cid}", source=str(img_path), where=f"line {no}")
        if max(abs(tx), abs(ty), abs(tz)) > MAX_VALUE:
            raise InputError(
                f"translation beyond ±{MAX_VALUE:g}: not a position",
                source=str(img_path),
                where=f"line {no}",
            )
        q = np.array([qw, qx, qy, qz])
        if not 0.5 < np.linalg.norm(q) < 2.0:
            raise InputError(
                "quaternion is not normalised", source=str(img_path), where=f"line {no}"
            )
        q = q / np.linalg.norm(q)
        w, x, y, z = q
        Rcw = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        t = np.array([tx, ty, tz])
        image_ids.append(iid)
        img_lines.append(no)
        names.append(name)
        cam_of.append(cam_index[cid])
        X0s.append(-Rcw.T @ t)
        Rs.append(Rcw.T @ FLIP)
        pts_line = body[k + 1] if k + 1 < len(body) else (no + 1, "")
        f2 = pts_line[1].split()
        if len(f2) % 3:
            raise InputError(
                "expected triplets X Y POINT3D_ID",
                source=str(img_path),
                where=f"line {pts_line[0]}",
            )
        img_idx = len(image_ids) - 1
        for j in range(0, len(f2), 3):
            u, v, p3 = _numbers(img_path, pts_line[0], f2[j : j + 3], "ffi", "a 2D point")
            if p3 == -1:
                continue
            cam = cams[cid]
            if not (abs(u) <= 100 * cam.width and abs(v) <= 100 * cam.height):
                raise InputError(
                    f"2D point ({u:g}, {v:g}) px lies far outside the {cam.width} × "
                    f"{cam.height} image",
                    source=str(img_path),
                    where=f"line {pts_line[0]}",
                )
            if p3 not in p_index:
                raise InputError(
                    f"unknown POINT3D_ID {p3}", source=str(img_path), where=f"line {pts_line[0]}"
                )
            oi.append(img_idx)
            obs_lines.append(pts_line[0])
            op.append(p_index[p3])
            uv.append((u, v))
        k += 2
    del lines
    if not image_ids:
        raise InputError("no images in the file", source=str(img_path), where=_end(img_path))
    known = set(image_ids)
    for no, ids in tracks:
        dangling = [i for i in ids if i not in known]
        if dangling:
            raise InputError(
                f"TRACK names IMAGE_ID {dangling[0]}, which is not in images.txt",
                source=str(pts_path),
                where=f"line {no}",
            )
    # readable image ids: COLMAP's image names where they are unique, else its IMAGE_IDs
    ids = names if len(set(names)) == len(names) else [str(i) for i in image_ids]
    uv_arr = np.array(uv, dtype=float).reshape(-1, 2)
    oi_arr = np.array(oi, dtype=np.int64)
    cam_arr = np.array(cam_of, dtype=np.int64)
    xy = np.empty_like(uv_arr)
    for ci, cid in enumerate(cam_ids):
        sel = cam_arr[oi_arr] == ci
        cam = cams[cid]
        und = _undistort(cam, uv_arr[sel])
        cx, cy = cam.principal_point()
        xy[sel, 0] = (und[:, 0] - cx) * pixel_size_mm
        xy[sel, 1] = -(und[:, 1] - cy) * pixel_size_mm
    _refuse_nonfinite(np.array(X0s).reshape(-1, 3), img_lines, img_path, "projection centre")
    _refuse_nonfinite(xy, obs_lines, img_path, "image point (mm)")
    R = np.array(Rs)
    ang = np.column_stack(opk_from_matrix(R, sequence))
    block = Block.from_arrays(
        camera_c=[cams[c].focal() * pixel_size_mm for c in cam_ids],
        camera_format_mm=[
            (cams[c].width * pixel_size_mm, cams[c].height * pixel_size_mm) for c in cam_ids
        ],
        camera_ids=[str(c) for c in cam_ids],
        image_camera=cam_arr,
        X0=np.array(X0s),
        angles=ang,
        image_ids=ids,
        xyz=np.array(xyz, dtype=float).reshape(-1, 3),
        point_ids=[str(p) for p in pid],
        obs_image=oi_arr,
        obs_point=np.array(op, dtype=np.int64),
        obs_xy=xy,
        obs_sigma=sigma_px * pixel_size_mm,
        sequence=sequence,
        meta={
            "source": str(d),
            "format": "colmap-text",
            "pixel_size_mm": pixel_size_mm,
            "image_names": names,
            "colmap_image_ids": image_ids,
            "colmap_cameras": {
                str(c): {
                    "model": cams[c].model,
                    "width": cams[c].width,
                    "height": cams[c].height,
                    "params": cams[c].params.tolist(),
                }
                for c in cam_ids
            },
        },
    )
    return block


def write_colmap(
    block: Block, directory: str | Path, *, pixel_size_mm: float | None = None
) -> None:
    """Write a Block as a COLMAP text model (PINHOLE cameras unless the block came from COLMAP).

    Image coordinates are written distortion-free (the COLMAP camera is written as
    PINHOLE/SIMPLE_PINHOLE); object coordinates are written as they are.
    """
    from .safeio import prepare_output_dir, write_atomic

    d = prepare_output_dir(directory)
    p = float(pixel_size_mm or block.meta.get("pixel_size_mm", 0.01))
    cams = block.cameras
    lines = [
        "# Camera list with one line of data per camera:",
        "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
    ]
    for i in range(len(cams)):
        w = int(round(cams.format_mm[i, 0] / p))
        h = int(round(cams.format_mm[i, 1] / p))
        f = cams.c[i] / p
        cx = w / 2 + cams.x0[i] / p
        cy = h / 2 - cams.y0[i] / p
        lines.append(f"{i + 1} SIMPLE_PINHOLE {w} {h} {f:.10g} {cx:.10g} {cy:.10g}")
    tmp = {}
    tmp["cameras.txt"] = "\n".join(lines) + "\n"
    R = block.rotations()
    obs = block.observations
    order = np.argsort(obs.image, kind="stable")
    starts = np.searchsorted(obs.image[order], np.arange(block.n_images + 1))
    lines = [
        "# Image list with two lines of data per image:",
        "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
        "#   POINTS2D[] as (X, Y, POINT3D_ID)",
    ]
    from scipy.spatial.transform import Rotation

    track: dict[int, list[tuple[int, int]]] = {}
    names = _image_names(block)
    pids = _point3d_ids(block)
    for i in range(block.n_images):
        Rcw = FLIP @ R[i].T
        t = -Rcw @ block.images.X0[i]
        qx, qy, qz, qw = Rotation.from_matrix(Rcw).as_quat()
        cam = block.images.camera[i]
        w = cams.format_mm[cam, 0] / p
        h = cams.format_mm[cam, 1] / p
        cx = w / 2 + cams.x0[cam] / p
        cy = h / 2 - cams.y0[cam] / p
        name = names[i]
        lines.append(
            f"{i + 1} {qw:.12g} {qx:.12g} {qy:.12g} {qz:.12g} {t[0]:.12g} {t[1]:.12g} {t[2]:.12g} {cam + 1} {name}"
        )
        sel = order[starts[i] : starts[i + 1]]
        parts = []
        for k2, j in enumerate(sel):
            u = obs.xy[j, 0] / p + cx - cams.x0[cam] / p
            v = -obs.xy[j, 1] / p + cy + cams.y0[cam] / p
            parts.append(f"{u:.6f} {v:.6f} {pids[obs.point[j]]}")
            track.setdefault(int(obs.point[j]), []).append((i + 1, k2))
        lines.append(" ".join(parts))
    tmp["images.txt"] = "\n".join(lines) + "\n"
    lines = [
        "# 3D point list with one line of data per point:",
        "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)",
    ]
    colour = {0: "200 200 200", CONTROL: "230 60 60", CHECK: "60 120 230"}
    for j in range(block.n_points):
        X = block.points.xyz[j]
        tr = " ".join(f"{a} {b}" for a, b in track.get(j, []))
        lines.append(
            f"{pids[j]} {X[0]:.10g} {X[1]:.10g} {X[2]:.10g} {colour[int(block.points.role[j])]} 0 {tr}"
        )
    tmp["points3D.txt"] = "\n".join(lines) + "\n"
    for name, text in tmp.items():  # write each file atomically
        write_atomic(d / name, text)


def _image_names(block: Block) -> list[str]:
    """NAME per image: the block's ids, or COLMAP's names where the ids are its IMAGE_IDs."""
    ids = list(block.images.ids)
    names = block.meta.get("image_names")
    cids = block.meta.get("colmap_image_ids")
    if names is None or cids is None or len(names) != len(ids) or len(cids) != len(ids):
        return ids
    return [n if i == str(c) else i for i, n, c in zip(ids, names, cids)]


def _point3d_ids(block: Block) -> list[int]:
    """POINT3D_ID per point: the ids themselves if they are distinct positive integers, else 1..p."""
    try:
        ids = [int(p) for p in block.points.ids]
    except ValueError:
        ids = []
    if len(ids) == block.n_points and min(ids, default=1) > 0 and len(set(ids)) == len(ids):
        return ids
    return list(range(1, block.n_points + 1))


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz import-colmap DIR -o OUT.json [--control CSV]``: COLMAP text → problem file."""
    from .importing import import_to_problem

    return import_to_problem(
        args,
        lambda px, sig: read_colmap(args.directory, pixel_size_mm=px, sigma_px=sig),
        Path(args.directory).resolve().name,
        default_pixel_mm=0.01,
    )
