"""COLMAP's text model: the three files of a directory read into one :class:`ColmapModel`.

cameras.txt and points3D.txt are read by :mod:`orientviz.io.colmap_text`, images.txt by
:mod:`orientviz.io.colmap_images`; here the three are put together and checked against
each other (every image a track names is in images.txt).
"""

from __future__ import annotations

from pathlib import Path

from .colmap_images import read_images_text
from .colmap_text import ColmapModel, _fail, read_cameras_text, read_points_text


def read_text_model(directory: Path) -> ColmapModel:
    """The three text files of ``directory`` as a :class:`ColmapModel` (checked).

    Raises
    ------
    InputError
        A broken file (naming file and line), or a track naming an image that
        images.txt does not hold.
    """
    cams = read_cameras_text(directory / "cameras.txt")
    pts_path = directory / "points3D.txt"
    pid, xyz, track_first = read_points_text(pts_path)
    img_path = directory / "images.txt"
    im = read_images_text(img_path, pid, cams)
    known = set(im["image_ids"].tolist())
    for iid, line in sorted(track_first.items(), key=lambda kv: kv[1]):
        if iid not in known:
            raise _fail(pts_path, line, f"TRACK names IMAGE_ID {iid}, which is not in images.txt")
    return ColmapModel(
        cams, im["image_ids"], im["names"], im["qvec"], im["tvec"], im["camera"],
        im["obs_image"], im["obs_uv"], im["obs_point"], pid, xyz,
        source={"format": "colmap-text", "images": str(img_path)},
    )  # fmt: skip
