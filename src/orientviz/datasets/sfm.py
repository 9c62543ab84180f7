"""The real structure-from-motion models shipped with orientviz, read by the importers.

* ``axe`` — a COLMAP model (text) of 52 photographs of a Bronze Age socketed axe
  (MicroPasts, CC BY 4.0), reconstructed by COLMAP (pycolmap) with one RADIAL camera;
  ``datasets/axe/MANIFEST.json`` gives its source, licence, sha256, units and frame,
  ``tools/make_axe_model.py`` in the repository the script that wrote it.
* ``ladybug`` — the BAL problem 49-7776 (``datasets/bal``; :func:`orientviz.io.bal.shipped_bal`;
  its MANIFEST says what is known of its licence).

>>> from orientviz.datasets.sfm import read_axe
>>> read_axe().n_images
52
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..block import Block
from ..io.colmap import read_colmap, shipped_colmap

#: Pixel pitch of the axe's camera (Canon EOS 600D: 22.3 mm over 5184 px), mm.
AXE_PIXEL_MM: float = 22.3 / 5184


def axe_model() -> Path:
    """Folder of the shipped COLMAP model ``axe`` (cameras.txt, images.txt, points3D.txt)."""
    return shipped_colmap("axe")


def axe_manifest() -> dict[str, Any]:
    """The model's MANIFEST.json: source (with commit), licence, sha256, units, frame."""
    return json.loads((axe_model() / "MANIFEST.json").read_text(encoding="utf-8"))


def read_axe(*, lens: str = "refine", sigma_px: float = 1.0) -> Block:
    """The shipped COLMAP model ``axe`` as a Block (:func:`orientviz.io.colmap.read_colmap`).

    Parameters
    ----------
    lens : {"refine", "fixed", "undistort"}
        ``"refine"`` (default): COLMAP's objective (distorted pixels) with the camera's
        focal length and k1, k2 free, as COLMAP's bundle adjustment refines them;
        ``"fixed"`` holds them; ``"undistort"`` undistorts the observations.
    sigma_px : float
        A-priori σ of an image coordinate in pixels (1: σ̂0 reads as the pixel RMS).

    Returns
    -------
    Block
        52 images, one camera, image coordinates in mm at the camera's pixel pitch
        (:data:`AXE_PIXEL_MM`), object coordinates in COLMAP's arbitrary frame and
        scale (no control: adjust it as a free network, ``solve --free``).
    """
    return read_colmap(axe_model(), pixel_size_mm=AXE_PIXEL_MM, sigma_px=sigma_px, lens=lens)
