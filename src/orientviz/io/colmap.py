"""COLMAP models (text or binary) ↔ :class:`~orientviz.block.Block`.

Conventions
-----------
COLMAP stores world → camera poses ``X_cam = R_cw X + t`` with quaternion
``(qw, qx, qy, qz)``, a camera frame with x right, y *down*, z forward, and pixel
coordinates with the origin at the upper-left corner of the image (the centre of the
first pixel at (0.5, 0.5)). orientviz uses the photogrammetric frame (x right, y *up*,
viewing along −z), image coordinates in mm and R image → object. Hence

    R_orientviz = R_cwᵀ · diag(1, −1, −1),   X0 = −R_cwᵀ t,
    x_mm = x_n · c,   y_mm = −y_n · c,   c = fx · p,

where (x_n, y_n) are COLMAP's undistorted normalised coordinates ((u − cx)/fx,
(v − cy)/fy before distortion) and ``p`` a nominal pixel size in mm (default 0.01 mm;
it only scales image units, the adjustment is unchanged). The mapping is exact for the
supported models (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV): the lens
distortion, with COLMAP's fixed parameters, is inverted at import (Newton, to 1e-10 px)
and fx ≠ fy stays in the data (y_n is in units of fy; nothing is averaged). The
parameters are kept in ``block.meta["colmap_cameras"]``; :func:`write_colmap` writes
the distortion-free equivalent (SIMPLE_PINHOLE). Angles come out in the block's
sequence (ω-φ-κ by default). The text files are read in one streaming pass keeping only
matched keypoints (:mod:`orientviz.io.colmap_text`); the binary files by
:mod:`orientviz.io.colmap_bin`.

Broken files raise :class:`~orientviz.errors.InputError` naming the file and line
(binary files: the byte offset).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, Block
from ..errors import InputError
from ..rotation import opk_from_matrix
from .colmap_bin import read_binary_model
from .colmap_lens import (
    LENS_MODES,
    colmap_model_of,
    colmap_params,
    forward_camera,
    repeated_observations,
)
from .colmap_text import CAMERA_MODELS, ColmapModel
from .colmap_text_model import read_text_model
from .colmap_undistort import normalised
from .importing import import_to_problem
from .safeio import prepare_output_dir, write_atomic

__all__ = ["CAMERA_MODELS", "block_from_colmap", "read_colmap", "write_colmap"]

FLIP = np.diag([1.0, -1.0, -1.0])


def _rotation_cw(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """World → camera rotations (m, 3, 3) from unit quaternions (m, 4) ``qw qx qy qz``."""
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def block_from_colmap(
    model: ColmapModel,
    *,
    pixel_size_mm: float = 0.01,
    sigma_px: float = 1.0,
    sequence: str = "opk",
    lens: str = "refine",
) -> Block:
    """Convert a :class:`ColmapModel` (text or binary) into a Block, exactly.

    ``lens="refine"`` (default) or ``"fixed"``: COLMAP's objective
    (:mod:`orientviz.io.colmap_lens`): the observations stay COLMAP's distorted pixels
    (x = u·p, y = −v·p mm from the upper-left corner), each camera is a forward lens
    model with COLMAP's parameters, free as COLMAP's bundle adjuster refines them
    (``"refine"``) or held (``"fixed"``). ``lens="undistort"``: each camera becomes a
    distortion-free camera with c = fx · p and the principal point at the origin:
    observations are undistorted (COLMAP's own distortion model, fixed parameters) and
    expressed as x = x_n · c, y = −y_n · c (mm); a camera with fx ≠ fy keeps its
    affinity exactly: y_n = (v − cy)/fy carries it, so the y-coordinates are in units of
    fx (σ_y = σ_px · p · fx/fy); nothing is averaged.

    Only the cameras some image uses are kept. A 3D point matched to two keypoints of
    one image keeps the first (:func:`~orientviz.io.colmap_lens.repeated_observations`;
    ``meta["colmap_repeated"]`` = (count left out, largest distance px)). The COLMAP
    parameters are kept in ``block.meta["colmap_cameras"]``.
    """
    if lens not in LENS_MODES:
        raise InputError(f"lens: expected one of {', '.join(LENS_MODES)}, got {lens!r}")
    cams = model.cameras
    cam_ids = sorted(set(int(c) for c in model.image_camera))
    cam_index = {c: i for i, c in enumerate(cam_ids)}
    keep, far = repeated_observations(model.obs_image, model.obs_point, model.obs_uv)
    repeated = (model.obs_image.size - keep.size, far)
    if repeated[0]:
        model.obs_image, model.obs_point = model.obs_image[keep], model.obs_point[keep]
        model.obs_uv = model.obs_uv[keep]
    if lens != "undistort":
        return _distorted_block(model, cam_ids, pixel_size_mm, sigma_px, sequence, lens, repeated)
    X0, angles = _poses(model, sequence)
    cam_arr = np.array([cam_index[int(c)] for c in model.image_camera], dtype=np.int64)
    n = model.obs_image.size
    xy = np.empty((n, 2))
    sigma = np.empty((n, 2) if len(cam_ids) > 1 else (1, 2))  # one camera: broadcast
    c_mm = []
    for ci, cid in enumerate(cam_ids):
        cam = cams[cid]
        p = cam.named()
        fx, fy = p.get("fx", p.get("f")), p.get("fy", p.get("f"))
        c = fx * pixel_size_mm
        c_mm.append(c)
        sel = slice(None) if len(cam_ids) == 1 else cam_arr[model.obs_image] == ci
        xn = normalised(cam, model.obs_uv[sel], model.source.get("images", ""))
        xn *= [c, -c]
        if len(cam_ids) == 1:
            xy = xn  # one camera: no copy
        else:
            xy[sel] = xn
        del xn
        sigma[sel] = sigma_px * pixel_size_mm * np.array([1.0, fx / fy])
    obs_point = model.obs_point  # indices into model.point_ids
    names = list(model.names)
    ids = names if len(set(names)) == len(names) else [str(i) for i in model.image_ids]
    return Block.from_arrays(
        camera_c=c_mm,
        camera_format_mm=[
            (cams[c].width * pixel_size_mm, cams[c].height * pixel_size_mm) for c in cam_ids
        ],
        camera_ids=[str(c) for c in cam_ids],
        image_camera=cam_arr,
        X0=X0,
        angles=angles,
        image_ids=ids,
        xyz=model.xyz.reshape(-1, 3),
        point_ids=list(map(str, model.point_ids.tolist())),
        obs_image=model.obs_image,
        obs_point=obs_point,
        obs_xy=xy,
        obs_sigma=sigma,
        sequence=sequence,
        meta={
            "source": model.source.get("directory", ""),
            "format": model.source.get("format", ""),
            "pixel_size_mm": pixel_size_mm,
            "image_names": names,
            "colmap_image_ids": model.image_ids.tolist(),
            "colmap_repeated": list(repeated),
            "lens": "undistort",
            "colmap_cameras": _camera_records(cams, cam_ids),
        },
    )


def _camera_records(cams, cam_ids) -> dict[str, dict]:
    """COLMAP's camera entries (model, width and height in px, parameters) by camera id, for ``block.meta``."""
    return {
        str(c): {
            "model": cams[c].model,
            "width": cams[c].width,
            "height": cams[c].height,
            "params": cams[c].params.tolist(),
        }
        for c in cam_ids
    }


def _poses(model: ColmapModel, sequence: str):
    """X0 (m, 3) and ω, φ, κ (m, 3) of COLMAP's world → camera poses."""
    q = model.qvec
    norm = np.linalg.norm(q, axis=1)
    if np.any(~((norm > 0.5) & (norm < 2.0))):
        k = int(np.flatnonzero(~((norm > 0.5) & (norm < 2.0)))[0])
        raise InputError(
            f"image {model.names[k]!r}: quaternion is not normalised",
            source=model.source.get("images", ""),
        )
    Rcw = _rotation_cw(q / norm[:, None])
    X0 = -np.einsum("nji,nj->ni", Rcw, model.tvec)
    R = np.transpose(Rcw, (0, 2, 1)) @ FLIP
    return X0, np.column_stack(opk_from_matrix(R, sequence)).reshape(-1, 3)


def _distorted_block(model, cam_ids, pixel_mm, sigma_px, sequence, lens, repeated) -> Block:
    """The block of COLMAP's objective: distorted pixels, forward lens models."""
    cams = model.cameras
    kinds = {cams[c].model for c in cam_ids}
    if lens == "refine" and len(kinds) > 1:
        raise InputError(
            f"the cameras are of different COLMAP models ({', '.join(sorted(kinds))}): "
            "one free parameter set per block; give --fix-lens (cameras held) or "
            "--undistort",
            source=model.source.get("cameras", ""),
        )
    io = [forward_camera(cams[c].model, cams[c].named(), pixel_mm, lens) for c in cam_ids]
    cam_index = {c: i for i, c in enumerate(cam_ids)}
    X0, angles = _poses(model, sequence)
    names = list(model.names)
    ids = names if len(set(names)) == len(names) else [str(i) for i in model.image_ids]
    block = Block.from_arrays(
        camera_c=[v[0] for v in io],
        camera_x0=[v[1] for v in io],
        camera_y0=[v[2] for v in io],
        camera_format_mm=[(cams[c].width * pixel_mm, cams[c].height * pixel_mm) for c in cam_ids],
        camera_ids=[str(c) for c in cam_ids],
        image_camera=np.array([cam_index[int(c)] for c in model.image_camera], dtype=np.int64),
        X0=X0,
        angles=angles,
        image_ids=ids,
        xyz=model.xyz.reshape(-1, 3),
        point_ids=list(map(str, model.point_ids.tolist())),
        obs_image=model.obs_image,
        obs_point=model.obs_point,
        obs_xy=model.obs_uv * [pixel_mm, -pixel_mm],
        obs_sigma=sigma_px * pixel_mm,
        sequence=sequence,
        meta={
            "source": model.source.get("directory", ""),
            "format": model.source.get("format", ""),
            "pixel_size_mm": pixel_mm,
            "image_origin": "corner",
            "lens": lens,
            "image_names": names,
            "colmap_image_ids": model.image_ids.tolist(),
            "colmap_repeated": list(repeated),
            "colmap_cameras": _camera_records(cams, cam_ids),
        },
    )
    block.cameras.model = [v[3] for v in io]
    return block


def read_colmap(
    directory: str | Path,
    *,
    pixel_size_mm: float = 0.01,
    sigma_px: float = 1.0,
    sequence: str = "opk",
    lens: str = "refine",
) -> Block:
    """Read a COLMAP model (text or binary) into a Block.

    Parameters
    ----------
    directory : str or Path
        Folder with ``cameras.txt``, ``images.txt`` and ``points3D.txt`` or with
        ``cameras.bin``, ``images.bin`` and ``points3D.bin`` (text is read when both are
        present).
    pixel_size_mm : float, default 0.01
        Nominal pixel size in mm used to express image coordinates in mm.
    sigma_px : float, default 1.0
        A-priori σ of the image coordinates in pixels.
    sequence : {"opk", "pok"}
        Rotation sequence for the returned angles.
    lens : {"refine", "fixed", "undistort"}
        COLMAP's objective (distorted pixels) with the cameras' focal length and
        distortion free as COLMAP's bundle adjuster refines them (default) or held, or
        undistorted observations of distortion-free cameras (see
        :func:`block_from_colmap`).

    Returns
    -------
    Block
        All points as tie points (COLMAP has no control); object units are COLMAP's;
        image ids are COLMAP's NAMEs when unique (else IMAGE_IDs), point ids POINT3D_IDs.
        Only keypoints matched to a 3D point are kept.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InputError(
            "expected a directory with cameras.txt, images.txt, points3D.txt "
            "(or cameras.bin, images.bin, points3D.bin)",
            source=str(d),
        )
    if (d / "images.txt").exists() or not (d / "images.bin").exists():
        model = read_text_model(d)
    else:
        model = read_binary_model(d)
    model.source["directory"] = str(d)
    return block_from_colmap(
        model, pixel_size_mm=pixel_size_mm, sigma_px=sigma_px, sequence=sequence, lens=lens
    )


def write_colmap(
    block: Block, directory: str | Path, *, pixel_size_mm: float | None = None
) -> None:
    """Write a Block as a COLMAP text model (PINHOLE cameras unless the block came from COLMAP).

    Image coordinates are written distortion-free (the COLMAP camera is written as
    PINHOLE/SIMPLE_PINHOLE); object coordinates are written as they are.
    """
    d = prepare_output_dir(directory)
    p = float(pixel_size_mm or block.meta.get("pixel_size_mm", 0.01))
    cams = block.cameras
    lines = [
        "# Camera list with one line of data per camera:",
        "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
    ]
    corner = _corner_origin(block)
    for i in range(len(cams)):
        w = int(round(cams.format_mm[i, 0] / p))
        h = int(round(cams.format_mm[i, 1] / p))
        if corner:
            kind, params = _forward_colmap(block, i, p)
            lines.append(f"{i + 1} {kind} {w} {h} " + " ".join(f"{v:.17g}" for v in params))
            continue
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
        cx = 0.0 if corner else w / 2 + cams.x0[cam] / p
        cy = 0.0 if corner else h / 2 - cams.y0[cam] / p
        name = names[i]
        lines.append(
            f"{i + 1} {qw:.12g} {qx:.12g} {qy:.12g} {qz:.12g} {t[0]:.12g} {t[1]:.12g} {t[2]:.12g} {cam + 1} {name}"
        )
        sel = order[starts[i] : starts[i + 1]]
        parts = []
        for k2, j in enumerate(sel):
            u = obs.xy[j, 0] / p + (0.0 if corner else cx - cams.x0[cam] / p)
            v = -obs.xy[j, 1] / p + (0.0 if corner else cy + cams.y0[cam] / p)
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


def _forward_colmap(block: Block, i: int, p: float) -> tuple[str, list[float]]:
    """COLMAP model name and parameters (px) of camera ``i`` of a block in COLMAP's pixel
    frame: its forward lens model in the COLMAP model it was imported from (else OPENCV,
    or PINHOLE without distortion)."""
    cams = block.cameras
    models = list(getattr(cams, "model", None) or [])
    spec = models[i] if i < len(models) else {}
    if spec and spec.get("model") != "forward":
        raise InputError(f"camera {cams.ids[i]!r}: COLMAP cameras have the forward model")
    values = dict(spec.get("values", {})) if spec else {}
    known = block.meta.get("colmap_cameras", {}).get(str(cams.ids[i]), {})
    kind = known.get("model") or colmap_model_of(values)
    return kind, colmap_params(kind, cams.c[i], cams.x0[i], cams.y0[i], values, p)


def _corner_origin(block: Block) -> bool:
    """Whether the block's image coordinates are COLMAP's pixel frame (origin at the
    upper-left corner: x ≥ 0, y ≤ 0 mm, as ``units.image = "px"`` reads pixels): said by
    ``meta["image_origin"]`` (import), else seen in the observations and principal points."""
    if "image_origin" in block.meta:
        return block.meta["image_origin"] == "corner"
    xy, cams = block.observations.xy, block.cameras
    return bool(xy.size and np.all(xy[:, 0] >= 0) and np.all(xy[:, 1] <= 0)
                and np.all(cams.x0 > 0) and np.all(cams.y0 < 0))  # fmt: skip


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


#: The COLMAP model shipped with orientviz (``orientviz import-colmap axe``): its folder
#: in ``orientviz/datasets`` (see its MANIFEST.json).
SHIPPED = {"axe": "axe"}


def shipped_colmap(name: str = "axe") -> Path:
    """Folder of a COLMAP text model shipped in ``orientviz/datasets``."""
    from importlib import resources

    if name not in SHIPPED:
        raise InputError(f"no shipped COLMAP model {name!r} (shipped: {', '.join(SHIPPED)})")
    return Path(str(resources.files("orientviz.datasets").joinpath(SHIPPED[name])))


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz import-colmap DIR -o OUT.json [--fix-lens | --undistort] [--control CSV]``;
    DIR ``axe`` (no such folder here) is the shipped model."""
    if not Path(args.directory).exists() and args.directory in SHIPPED:
        args.directory = str(shipped_colmap(args.directory))
    lens = "undistort" if getattr(args, "undistort", False) else (
        "fixed" if getattr(args, "fix_lens", False) else "refine")  # fmt: skip
    notes = {
        "refine": "; COLMAP's objective (distorted pixels), focal length and distortion free "
        "as COLMAP refines them (--fix-lens holds them)",
        "fixed": "; COLMAP's objective (distorted pixels), cameras held (--fix-lens)",
        "undistort": "; observations undistorted with COLMAP's cameras, held (--undistort)",
    }

    def read(px: float, sig: float) -> Block:
        block = read_colmap(args.directory, pixel_size_mm=px, sigma_px=sig, lens=lens)
        n, far = block.meta["colmap_repeated"]
        if n:
            notes[lens] += (
                f"; {n} observation(s) of a point already seen in the same image left out "
                f"(the first keypoint kept; the others lay up to {far:.3g} px from it)"
            )
        return block

    return import_to_problem(
        args, read, Path(args.directory).resolve().name, default_pixel_mm=0.01,
        pixel_units=lens != "undistort", lens_note_of=lambda: notes[lens],
    )  # fmt: skip
