"""DBAT's script files as orientviz reads them: comma-separated tables and the
camera-calibration demo.

DBAT (N. Börlin's Damped Bundle Adjustment Toolbox) keeps a project as plain text: one
table per file (``images.txt``, ``markpts.txt``, control), ``#`` comments, fields
separated by commas; the camera in an XML file. :func:`read_camcal` reads the shipped
``datasets/dbat/camcal`` folder for ``orientviz reproduce dbat-camcal``;
:mod:`orientviz.datasets.make_dbat` uses the same readers when it converts a DBAT
checkout.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any


def table_rows(path: Path) -> list[list[str]]:
    """Comma-separated rows of a DBAT table, comments (#) and blank lines skipped."""
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            out.append([f.strip() for f in line.split(",")])
    return out


def numbers(text: str) -> list[float]:
    """The numbers of a DBAT text field, comma- or blank-separated."""
    return [float(v) for v in text.replace(",", " ").split()]


def read_camcal(folder: Path) -> dict[str, Any]:
    """DBAT's camera calibration demo from its script files in ``folder`` (copied flat).

    Returns the camera (sensor height mm, image size px, nominal focal length mm; the
    sensor width follows from square pixels, as DBAT's ``auto``), the image names, the
    marked points (image number, point id, column, row px, σ px) and the control points
    (id → X, Y, Z m, held fixed by DBAT's script).
    """
    root = ET.parse(folder / "camcaldemo.xml").getroot()
    cam = root.find("input/cameras/camera")
    if cam is None:
        raise ValueError(f"{folder}: no camera in camcaldemo.xml")
    sensor = cam.findtext("sensor", "").split(",")
    image = [int(v) for v in numbers(cam.findtext("image", ""))]
    height = float(sensor[1])
    pixel = height / image[1]
    marks = table_rows(folder / "markpts.txt")
    return {
        "image_px": image,
        "pixel_mm": pixel,
        "sensor_mm": [image[0] * pixel, height],
        "focal_mm": float(cam.findtext("focal", "")),
        "images": {row[0]: Path(row[1]).name for row in table_rows(folder / "images.txt")},
        "marks": [(m[0], m[1], float(m[2]), float(m[3]), float(m[4])) for m in marks],
        "control": {
            r[0]: (float(r[2]), float(r[3]), float(r[4]))
            for r in table_rows(folder / "camcal-fixed.txt")
        },
    }
