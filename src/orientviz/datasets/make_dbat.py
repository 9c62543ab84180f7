"""Convert data of DBAT (N. Börlin's Damped Bundle Adjustment Toolbox) into orientviz datasets.

Run ``python -m orientviz.datasets.make_dbat PATH_TO_DBAT`` on a checkout of
https://github.com/niclasborlin/dbat (files are read, never executed; no DBAT code is
used or shipped). It writes ``orientviz/datasets/dbat/``:

* ``dbat_sxb.json`` — the aerial block ``data/script/sxb`` as a problem file (kind
  ``block``): 5 images of an aerial camera (c = 123.9392 mm), 14 weighted control
  points, 2 check points (ids 351, 410, as in ``sxb.xml``), tie points; image
  coordinates in mm and the adjustment options of DBAT's script (weighted control,
  image σ 0.5 px for the marked and 1.0 px for the "smart" points, check points keep
  their rays).
* ``sxb/`` — DBAT's own input files and its report (``report.txt``, the published
  numbers of ``orientviz reproduce dbat-sxb``), unchanged.
* ``camcal/`` — DBAT's camera calibration demo (``data/script/camcaldemo``: 21 images of
  a target sheet by an Olympus C4040Z, 7.3 mm, 2074 image points, 4 fixed control
  points) and the report of its PhotoModeler-export route
  (``data/dbat/dbatexports/camcal-dbatreport.txt``), unchanged;
  :func:`orientviz.reproduce.dbat_files.read_camcal` reads it (``orientviz reproduce dbat-camcal``).
* ``roma/`` — DBAT's ROMA bundle demo (``data/script/romabundledemo``: 60 images of a
  Canon EOS 5D Mark II, 90 561 marked points of 26 321 object points, no control), its
  measurements gzipped, and its report; ``orientviz reproduce dbat-roma`` reads them
  (:mod:`orientviz.reproduce.dbat_roma`).
* ``LICENSE.txt`` (DBAT's licence, verbatim), ``CITATION.md`` and ``MANIFEST.json``.

Conversions (DBAT's conventions, read from its camera model): image coordinates are
pixels (column, row) with the origin at the upper-left corner and rows down; DBAT
multiplies them by the pixel size and negates y, and places the principal point at
(px, −py) in that frame. orientviz keeps that frame: x = col · p, y = −row · p (mm), the
camera's x0 = px, y0 = −py. DBAT's rotation M = R1(ω) R2(φ) R3(κ) (camera → object) is
orientviz's "opk" sequence, so the angles are comparable as printed.
"""

from __future__ import annotations

import argparse
import gzip
import json
import shutil
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from ..io.problem import dumps_problem, loads_problem
from ..reproduce.dbat_camcal import MANIFEST_ENTRY, problem_text
from ..reproduce.dbat_files import numbers, table_rows

HERE = Path(__file__).resolve().parent / "dbat"

#: DBAT's input files of the aerial block, relative to the checkout.
SXB = "data/script/sxb"
SXB_FILES = (
    "sxb.xml",
    "images/images.txt",
    "measurements/markpts.txt",
    "measurements/smartpts.txt",
    "reference/sxb-control.txt",
    "result/report.txt",
)

#: DBAT's camera calibration demo (script version) and the report of its pmexport route.
CAMCAL = "data/script/camcaldemo"
CAMCAL_FILES = (
    "camcaldemo.xml",
    "c4040z.xml",
    "images/images.txt",
    "measurements/markpts.txt",
    "reference/camcal-fixed.txt",
    "result/report.txt",
)
CAMCAL_REPORT = "data/dbat/dbatexports/camcal-dbatreport.txt"

#: DBAT's ROMA bundle demo (script version, self-calibration without control); the
#: measurements are gzipped (2.6 MB of text → 1.1 MB), the other files copied as they are.
ROMA = "data/script/romabundledemo"
ROMA_FILES = (
    "romabundledemo.xml",
    "cameras/EOS5DMarkII.xml",
    "images/images.txt",
    "prior/initial_eo.txt",
    "measurements/markpts.txt",
    "result/report.txt",
)

CITATION = """\
# Citing the DBAT data

These data sets come from DBAT, the Damped Bundle Adjustment Toolbox by Niclas Börlin
(Umeå University) and Pierre Grussenmeyer (INSA Strasbourg),
https://github.com/niclasborlin/dbat (release 0.9.2.0), distributed under the BSD-style
licence in LICENSE.txt beside this file. The licence asks that scientific publications
using the code or derivatives thereof refer to one or more of its papers; for these data:

* the aerial block `sxb` (Strasbourg):
  N. Börlin, A. Murtiyoso, P. Grussenmeyer (2019). Implementing Functional Modularity
  for Processing of General Photogrammetric Data with the Damped Bundle Adjustment
  Toolbox (DBAT). ISPRS Archives XLII-2/W17, 69-75.
  doi:10.5194/isprs-archives-XLII-2-W17-69-2019
  (and N. Börlin, P. Grussenmeyer (2016). External Verification of the Bundle
  Adjustment in Photogrammetric Software using the Damped Bundle Adjustment Toolbox.
  ISPRS Archives XLI-B5, 7-14. doi:10.5194/isprs-archives-XLI-B5-7-2016)
* the camera calibration `camcal`:
  N. Börlin, P. Grussenmeyer (2014). Camera Calibration using the Damped Bundle
  Adjustment Toolbox. ISPRS Annals II-5, 89-96. doi:10.5194/isprsannals-II-5-89-2014
* the ROMA bundle `roma` (60 images, self-calibration without control points;
  DBAT's script `romabundledemo.xml` says it was presented at LC3D 2019 in Strasbourg,
  the conference of the paper cited for `sxb` above, which is therefore cited for it too):
  N. Börlin, A. Murtiyoso, P. Grussenmeyer (2019), as for `sxb`; the images are not
  shipped (DBAT: http://www.cs.umu.se/~niclas/dbat_images/roma)
* the toolbox itself:
  N. Börlin, P. Grussenmeyer (2013). Bundle adjustment with and without damping.
  The Photogrammetric Record 28(144), 396-415. doi:10.1111/phor.12037

orientviz converted the files with its own script (`python -m orientviz.datasets.make_dbat`);
DBAT's original files are kept unchanged beside the converted problem files.
"""


def sxb_camera(xml_path: Path) -> dict[str, Any]:
    """The camera and the options of DBAT's ``sxb.xml`` (sensor mm, image px, cc, pp)."""
    root = ET.parse(xml_path).getroot()
    cam = root.find("input/cameras/camera")
    if cam is None or cam.findtext("unit", "").strip() != "mm":
        raise ValueError(f"{xml_path}: expected one camera in mm")
    sensor = numbers(cam.findtext("sensor", ""))
    image = numbers(cam.findtext("image", ""))
    out = {
        "sensor_mm": sensor,
        "image_px": [int(v) for v in image],
        "c_mm": float(cam.findtext("cc", "")),
        "pp_mm": numbers(cam.findtext("pp", "")),
        "K": numbers(cam.findtext("K", "")),
        "P": numbers(cam.findtext("P", "")),
        "aspect": float(cam.findtext("aspect", "1")),
        "skew": float(cam.findtext("skew", "0")),
    }
    if any(out["K"]) or any(out["P"]) or out["aspect"] != 1 or out["skew"] != 0:
        raise ValueError(f"{xml_path}: lens distortion is not expected in the sxb block")
    px = [s / n for s, n in zip(sensor, image)]
    if abs(px[0] - px[1]) > 1e-12:
        raise ValueError(f"{xml_path}: non-square pixels {px}")
    out["pixel_mm"] = px[0]
    files = {}
    for f in root.findall("input/image_pts/file"):
        files[(f.text or "").strip()] = float(f.get("sxy", "nan"))
    out["image_sigma_px"] = files
    checks = root.find("input/check_pts/filter")
    out["check_ids"] = [
        s.strip()
        for s in (checks.get("id", "") if checks is not None else "").split(",")
        if s.strip()
    ]
    return out


def _r(v: float) -> float:
    """Round a converted coordinate to 1e-9 (far below the data's own digits)."""
    return round(float(v), 9)


def sxb_problem(root: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """The sxb block as an ``orientviz/1`` document, and facts for the manifest."""
    base = root / SXB
    cam = sxb_camera(base / "sxb.xml")
    p = cam["pixel_mm"]
    images = {row[0]: Path(row[1]).stem for row in table_rows(base / "images/images.txt")}
    control = table_rows(base / "reference/sxb-control.txt")
    check = set(cam["check_ids"])
    points: list[dict[str, Any]] = []
    labels: dict[str, str] = {}
    known = set()
    for pid, label, X, Y, Z, sX, sY, sZ in control:
        labels[pid] = label
        known.add(pid)
        row: dict[str, Any] = {"id": pid, "role": "check" if pid in check else "control",
                               "X": float(X), "Y": float(Y), "Z": float(Z)}  # fmt: skip
        if pid not in check:
            row["sigma"] = [float(sX), float(sY), float(sZ)]
        points.append(row)
    observations: list[dict[str, Any]] = []
    ties: list[str] = []
    for name, sigma_px in cam["image_sigma_px"].items():
        for pid, im, col, row_px in table_rows(base / name):
            if pid not in known and pid not in ties:
                ties.append(pid)
            s = _r(sigma_px * p)
            observations.append({"image": images[im], "point": pid,
                                 "x": _r(float(col) * p), "y": _r(-float(row_px) * p),
                                 "sigma": s})  # fmt: skip
    points += [{"id": t, "role": "tie"} for t in sorted(ties, key=int)]
    order = {name: k for k, name in enumerate(images.values())}
    observations.sort(key=lambda o: (order[o["image"]], int(o["point"])))
    doc = {
        "format": "orientviz/1",
        "kind": "block",
        "name": "dbat_sxb",
        "description": (
            "DBAT's aerial block over Strasbourg (sxb): 5 images, 14 weighted control and "
            "2 check points, tie points; converted from DBAT's data/script/sxb by "
            "orientviz.datasets.make_dbat"
        ),
        "units": {"length": "m", "image": "mm", "angle": "deg"},
        "sequence": "opk",
        "options": {"control": "weighted", "check_points": "rays", "max_iter": 20},
        "cameras": [
            {
                "id": "aerial",
                "c": cam["c_mm"],
                "x0": cam["pp_mm"][0],
                "y0": -cam["pp_mm"][1],
                "format": cam["sensor_mm"],
            }
        ],  # fmt: skip
        "images": [{"id": name, "camera": "aerial"} for name in images.values()],
        "points": points,
        "observations": observations,
    }
    facts = {
        "pixel_size_mm": p,
        "image_px": cam["image_px"],
        "image_sigma_px": cam["image_sigma_px"],
        "labels": labels,
        "check_ids": sorted(check, key=int),
        "images": images,
    }
    return doc, facts


def make(dbat: Path, out: Path = HERE) -> list[Path]:
    """Convert from the DBAT checkout ``dbat`` into ``out``; return the written files."""
    dbat = Path(dbat)
    if not (dbat / "LICENSE.txt").is_file() or not (dbat / SXB / "sxb.xml").is_file():
        raise FileNotFoundError(f"{dbat}: not a DBAT checkout (LICENSE.txt, {SXB}/sxb.xml)")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    shutil.copyfile(dbat / "LICENSE.txt", out / "LICENSE.txt")
    (out / "CITATION.md").write_text(CITATION, encoding="utf-8")
    written += [out / "LICENSE.txt", out / "CITATION.md"]
    (out / "sxb").mkdir(exist_ok=True)
    for name in SXB_FILES:
        target = out / "sxb" / Path(name).name
        shutil.copyfile(dbat / SXB / name, target)
        written.append(target)
    (out / "camcal").mkdir(exist_ok=True)
    for name in CAMCAL_FILES:
        target = out / "camcal" / Path(name).name
        shutil.copyfile(dbat / CAMCAL / name, target)
        written.append(target)
    shutil.copyfile(dbat / CAMCAL_REPORT, out / "camcal" / "camcal-dbatreport.txt")
    written.append(out / "camcal" / "camcal-dbatreport.txt")
    (out / "roma").mkdir(exist_ok=True)
    for name in ROMA_FILES:
        target = out / "roma" / Path(name).name
        if name.endswith("markpts.txt"):  # the bytes unchanged, gzipped (mtime 0: reproducible)
            target = target.with_name(target.name + ".gz")
            with gzip.GzipFile(target, "wb", compresslevel=9, mtime=0) as f:
                f.write((dbat / ROMA / name).read_bytes())
        else:
            shutil.copyfile(dbat / ROMA / name, target)
        written.append(target)
    (out / "dbat_camcal.json").write_text(problem_text(out / "camcal"), encoding="utf-8")
    written.append(out / "dbat_camcal.json")
    doc, facts = sxb_problem(dbat)
    # through orientviz's own reader and writer: validated, and in the canonical form
    text = dumps_problem(loads_problem(json.dumps(doc), "dbat_sxb.json"))
    (out / "dbat_sxb.json").write_text(text, encoding="utf-8")
    written.append(out / "dbat_sxb.json")
    manifest = {
        "format": "orientviz-datasets/1",
        "datasets": [
            {
                "name": "dbat_sxb",
                "file": "dbat_sxb.json",
                "kind": "block",
                "form": "readable",
                "description": doc["description"],
                "source": (
                    "DBAT 0.9.2.0 (https://github.com/niclasborlin/dbat), data/script/sxb: "
                    "sxb.xml, images/images.txt, measurements/markpts.txt, "
                    "measurements/smartpts.txt, reference/sxb-control.txt; DBAT's result "
                    "report result/report.txt (copies in sxb/)"
                ),
                "citation": "CITATION.md",
                "licence": "BSD-style licence of DBAT, (C) 2013-2020 N. Börlin and P. Grussenmeyer: LICENSE.txt",
                "units": {"length": "m", "image": "mm", "angle": "deg"},
                "frame": (
                    "object: the control points' projected national grid (X east, Y north, "
                    "Z height, m) as given by DBAT; image: mm, x = column · pixel, "
                    "y = −row · pixel from the upper-left corner of the image "
                    f"({facts['image_px'][0]} × {facts['image_px'][1]} px of "
                    f"{facts['pixel_size_mm']} mm), principal point at (x0, y0)"
                ),
                "pixel_size_mm": facts["pixel_size_mm"],
                "image_sigma_px": facts["image_sigma_px"],
                "image_files": facts["images"],
                "point_labels": facts["labels"],
                "check_points": facts["check_ids"],
                "adjustment": (
                    "as DBAT's sxb.xml: control weighted (σ 0.02, 0.02, 0.04 m), check "
                    "points keep their rays but not their coordinates, interior "
                    "orientation fixed, no lens distortion"
                ),
            },
            MANIFEST_ENTRY,
        ],
    }
    (out / "MANIFEST.json").write_text(
        json.dumps(manifest, indent=1, ensure_ascii=False) + "\n", encoding="utf-8"
    )
    written.append(out / "MANIFEST.json")
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m orientviz.datasets.make_dbat",
        description="Convert DBAT's sxb block (and camera calibration) into orientviz datasets.",
    )
    parser.add_argument(
        "dbat", type=Path, help="path of a DBAT checkout (github.com/niclasborlin/dbat)"
    )
    parser.add_argument("-o", "--out", type=Path, default=HERE, help="output folder")
    args = parser.parse_args(argv)
    try:
        files = make(args.dbat, args.out)
    except (OSError, ValueError) as exc:
        print(f"make_dbat: {exc}", file=sys.stderr)
        return 2
    for f in files:
        print(f)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
