"""The shipped Geier (1973) dataset: loader and (re)builder.

Files in ``orientviz/datasets/geier1973/``:

* ``MANIFEST.json`` — source, units, frame, licence, file list;
* ``fig7.json`` — the 25 grid points and the parameters/approximations of images 1-3
  as printed (angles in gon);
* ``surfaces.json`` — the ten surfaces of Fig. 8 with their heights and the image
  coordinates of the 25 points in images 1-3, error-free and rounded to whole metres;
* ``fig8_paper.json`` — the paper's Fig. 8 table (true errors, m0, correlations).

:func:`build` regenerates the first three from :mod:`orientviz.radar.geier1973`; the
tests check that the shipped files equal a fresh build. Run
``python -m orientviz.radar.data DIR`` to write them.
"""

from __future__ import annotations

import json
import sys
from importlib import resources
from typing import Any

import numpy as np

from ..errors import InputError
from . import geier1973 as G

#: Package-relative folder of the dataset.
DATASET = "datasets/geier1973"
FILES = ("MANIFEST.json", "fig7.json", "surfaces.json", "fig8_paper.json")


def _read(name: str) -> Any:
    if name not in FILES:
        raise InputError(f"unknown file {name!r} of the Geier 1973 dataset; expected {FILES}")
    path = resources.files("orientviz").joinpath(f"{DATASET}/{name}")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(
            f"the Geier 1973 dataset file {name} is missing from the package"
        ) from None


def load_manifest() -> dict[str, Any]:
    """The dataset's manifest (source, units, frame, licence, files)."""
    return _read("MANIFEST.json")


def load_fig7() -> dict[str, Any]:
    """Fig. 7: ``points`` (25 × [id, X, Y, Z] m), ``images`` and ``approximations`` (gon)."""
    return _read("fig7.json")


def load_surfaces() -> dict[str, Any]:
    """The Fig. 8 surfaces: per key, the heading, definition, Z and image coordinates."""
    return _read("surfaces.json")


def load_fig8_paper() -> dict[str, Any]:
    """The paper's Fig. 8 as printed: task → quantity → ten values (None = not printed)."""
    return _read("fig8_paper.json")


def load_surface(name: str, image: int, *, rounded: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Object points (25, 3) and image coordinates (25, 2) of one surface and image (m).

    Parameters
    ----------
    name : str
        Surface key, e.g. ``"fig7"``, ``"plane"``, ``"sphere150_convex"``.
    image : {1, 2, 3}
        Image number of Fig. 7.
    rounded : bool
        Whole-metre coordinates (as in the paper) or error-free ones.
    """
    s = load_surfaces()
    if name not in s["surfaces"]:
        raise InputError(f"unknown surface {name!r}; expected one of {', '.join(s['surfaces'])}")
    if image not in (1, 2, 3):
        raise InputError(f"expected image 1, 2 or 3, got {image!r}")
    d = s["surfaces"][name]
    xy = np.array(d["images"][str(image)]["rounded" if rounded else "exact"], float)
    return np.array(d["points"], float), xy


def build() -> dict[str, Any]:
    """Fresh contents of ``fig7.json`` and ``surfaces.json`` from the constants."""
    gon = G._GON
    io = G.interior()
    fig7 = {
        "description": "Geier (1973) Fig. 7: grid points, parameters and approximations",
        "units": {"length": "m", "angle": "gon", "image": "m"},
        "sequence": "pok",
        "points": [
            [i + 1, *map(float, p)] for i, p in enumerate(G.points("fig7").round(3).tolist())
        ],
        "interior": io,
        "images": {
            "1": {"X0": [0.0, 0.0, 0.0], "phi": 0.0, "omega": 0.0, "kappa": gon["alpha0"]},
            "2": {
                "X0": [30054.47, 28.16, -1039.87],
                "phi": gon["phi2"],
                "omega": gon["omega2"],
                "kappa": gon["kappa2"],
            },
            "3": {
                "X0": [25043.17, 9947.84, -472.16],
                "phi": gon["phi3"],
                "omega": gon["omega3"],
                "kappa": gon["kappa3"],
            },
        },
        "approximations": {
            "interior": {"x0": 400.0, "y0": 700.0, "h": 15000.0, "m": 1.125, "alpha0": 0.3},
            "2": {"X0": [30000.0, 0.0, -1000.0], "phi": 0.0, "omega": 0.0, "kappa": 0.0},
            "3": {"X0": [25000.0, 10000.0, -500.0], "phi": 6.1, "omega": 4.2, "kappa": 17.5},
        },
        "notes": [
            "Angles printed with a degree sign in the paper are gon (0.0955, 0.1273, 0.1592 gon"
            " = 0.0015, 0.0020, 0.0025 rad); the printed values are the inputs.",
            "Image 1 (normal case) is not listed: station at the origin, vertical axis, "
            "reference direction alpha0 (assumption, see docs/geier_conventions.md).",
        ],
    }
    surfaces: dict[str, Any] = {}
    T = G.images()
    for key, (heading, kind, radius, convex) in G.SURFACES.items():
        P = G.points(key)
        imgs = {}
        for i in (1, 2, 3):
            exact = G.project(P, T[i])
            imgs[str(i)] = {
                "exact": np.round(exact, 6).tolist(),
                "rounded": np.round(exact).tolist(),
            }
        surfaces[key] = {
            "heading": heading,
            "kind": kind,
            "radius_m": radius,
            "convex": convex if kind not in ("fig7", "plane") else None,
            "points": P.round(6).tolist(),
            "images": imgs,
        }
    return {
        "fig7.json": fig7,
        "surfaces.json": {
            "description": "Geier (1973) Fig. 8 surfaces with image coordinates of images 1-3",
            "units": {"length": "m", "image": "m"},
            "centre_xy": list(G.CENTRE_XY),
            "columns": list(G.COLUMNS),
            "surfaces": surfaces,
        },
    }


def write(directory: str) -> None:
    """Write :func:`build`'s files into ``directory`` (JSON, sorted keys, indent 1)."""
    import pathlib

    out = pathlib.Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    for name, content in build().items():
        (out / name).write_text(json.dumps(content, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":  # pragma: no cover
    write(sys.argv[1])
