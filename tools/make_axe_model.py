"""Write the shipped COLMAP model ``datasets/axe/`` from the MicroPasts photographs.

The photographs of the socketed axe from Arreton Down (MicroPasts, CC BY 4.0; see
``axe/MANIFEST.json`` for the source, its commit and the licence) are not shipped. With
them in a folder, this script runs COLMAP's own pipeline through pycolmap — SIFT features,
exhaustive matching, incremental mapping with one RADIAL camera (f, cx, cy, k1, k2) shared
by all photographs, then COLMAP's bundle adjustment refining f, k1, k2 (:func:`reconstruct`)
— and writes the model as COLMAP text files with only the keypoints that observe a 3D
point::

    python tools/make_axe_model.py PHOTOS_DIR MASKS_DIR [OUT_DIR]

MASKS_DIR holds MicroPasts' masks of the axe (``masks/IMG_8835_mask.JPG``); they are
written as COLMAP reads masks (:func:`colmap_masks`): the object was turned on a table in
front of a fixed camera, so only its own features may be matched.

It lives in tools/, not in the package: it needs the photographs (not shipped) and pycolmap
(``pip install pycolmap``), which orientviz itself does not use; orientviz reads the written
model with :func:`orientviz.io.colmap.read_colmap`. The numbers of the shipped model
(images, points, observations, the camera) are in its MANIFEST.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

#: What the shipped model was made with (pycolmap's options; all others its defaults).
MAX_IMAGE_SIZE = 1600  # px, the longer side SIFT sees (keypoints are in full-size pixels)
MAX_NUM_FEATURES = 2000
CAMERA_MODEL = "RADIAL"


def make(photos: Path, masks: Path, out: Path) -> Path:
    """Reconstruct ``photos`` with pycolmap and write the text model into ``out``.

    Returns the folder written (``cameras.txt``, ``images.txt``, ``points3D.txt``).
    """
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "database.db"
        features(db, photos, colmap_masks(masks, photos, Path(tmp) / "masks"))
        return write_model(reconstruct(db, photos, Path(tmp) / "sparse"), out)


def colmap_masks(masks: Path, photos: Path, out: Path) -> Path:
    """MicroPasts' JPEG masks as COLMAP's (``IMG_8835.JPG.png`` for ``IMG_8835.JPG``):
    grey > 127 is the object, grown by 15 px (the JPEG edge), 0 elsewhere."""
    import numpy as np
    from PIL import Image
    from scipy.ndimage import maximum_filter

    out.mkdir(parents=True, exist_ok=True)
    for photo in sorted(photos.iterdir()):
        mask = masks / f"{photo.stem}_mask{photo.suffix}"
        if mask.is_file():
            m = (np.asarray(Image.open(mask).convert("L")) > 127).astype(np.uint8)
            Image.fromarray(maximum_filter(m, size=31) * 255).save(out / f"{photo.name}.png")
    return out


def features(db: Path, photos: Path, masks: Path) -> None:
    """SIFT features (inside the masks) of every photograph and their exhaustive matches,
    into the COLMAP database ``db``; one RADIAL camera for all photographs."""
    import pycolmap  # the maker's tool only: orientviz does not depend on it

    names = sorted(p.name for p in photos.iterdir() if p.suffix.lower() in (".jpg", ".jpeg"))
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.max_image_size = MAX_IMAGE_SIZE
    extraction.sift.max_num_features = MAX_NUM_FEATURES
    reader = pycolmap.ImageReaderOptions()
    reader.camera_model = CAMERA_MODEL
    reader.mask_path = str(masks)
    pycolmap.extract_features(
        db, photos, image_names=names, camera_mode=pycolmap.CameraMode.SINGLE,
        reader_options=reader, extraction_options=extraction, device=pycolmap.Device.cpu,
    )  # fmt: skip
    pycolmap.match_exhaustive(db, device=pycolmap.Device.cpu)


def reconstruct(db: Path, photos: Path, work: Path):
    """COLMAP's incremental mapping with the camera held at its EXIF focal length and no
    distortion (refining them from the first two views of this narrow lens — 55 mm on
    APS-C — lost every further image), then COLMAP's global bundle adjustment of all
    images with f, k1, k2 free and the principal point held. Returns the
    pycolmap.Reconstruction with the most images."""
    import pycolmap  # the maker's tool only: orientviz does not depend on it

    opts = pycolmap.IncrementalPipelineOptions()
    opts.ba_refine_focal_length = False
    opts.ba_refine_extra_params = False
    models = pycolmap.incremental_mapping(db, photos, work, options=opts)
    best = max(models.values(), key=lambda r: r.num_reg_images())
    ba = pycolmap.BundleAdjustmentOptions()
    ba.refine_focal_length, ba.refine_extra_params = True, True
    ba.refine_principal_point = False
    pycolmap.bundle_adjustment(best, ba)
    return best


def write_model(reconstruction, out: Path) -> Path:
    """The reconstruction as COLMAP text files in ``out``, keypoints without a 3D point
    left out of images.txt."""
    out.mkdir(parents=True, exist_ok=True)
    reconstruction.write_text(str(out))
    for extra in ("rigs.txt", "frames.txt"):  # COLMAP ≥ 3.12's; it reads a model without them
        (out / extra).unlink(missing_ok=True)
    _keep_observed_keypoints(out)
    return out


def model_numbers(folder: Path) -> dict:
    """Images, points, observations (keypoints with a 3D point), the camera line and the
    sha256 of the three text files of a written model (for its MANIFEST)."""
    import hashlib

    def rows(name):
        text = (folder / name).read_text().splitlines()
        return [r for r in text if r.strip() and not r.startswith("#")]

    images = rows("images.txt")
    return {
        "images": len(images) // 2,
        "points": len(rows("points3D.txt")),
        "observations": sum(len(r.split()) // 3 for r in images[1::2]),
        "camera": rows("cameras.txt")[0],
        "sha256": {n: hashlib.sha256((folder / n).read_bytes()).hexdigest()
                   for n in ("cameras.txt", "images.txt", "points3D.txt")},
    }  # fmt: skip


def _keep_observed_keypoints(folder: Path) -> None:
    """Rewrite images.txt with only the keypoints that observe a 3D point (COLMAP writes
    every keypoint; the others carry POINT3D_ID −1 and no information for the bundle),
    and the tracks of points3D.txt with the keypoints' new POINT2D_IDX."""
    lines = (folder / "images.txt").read_text().splitlines()
    out, new_idx, k = [], {}, 0
    while k < len(lines):
        line = lines[k]
        if line.startswith("#") or not line.strip():
            out.append(line)
            k += 1
            continue
        image_id = line.split()[0]
        out.append(line)
        fields = lines[k + 1].split() if k + 1 < len(lines) else []
        kept = []
        for old, i in enumerate(range(0, len(fields), 3)):
            if fields[i + 2] != "-1":
                new_idx[(image_id, str(old))] = str(len(kept))
                kept.append(" ".join(fields[i : i + 3]))
        out.append(" ".join(kept))
        k += 2
    (folder / "images.txt").write_text("\n".join(out) + "\n")
    rows = []
    for line in (folder / "points3D.txt").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            w = line.split()
            track = [x for a, b in zip(w[8::2], w[9::2]) for x in (a, new_idx[(a, b)])]
            line = " ".join(w[:8] + track)
        rows.append(line)
    (folder / "points3D.txt").write_text("\n".join(rows) + "\n")


if __name__ == "__main__":  # pragma: no cover - needs the photographs and pycolmap
    if len(sys.argv) not in (3, 4):
        print(__doc__.split("::")[1].strip().splitlines()[0].strip(), file=sys.stderr)
        raise SystemExit(2)
    target = Path(sys.argv[3]) if len(sys.argv) == 4 else Path(__file__).parent / "axe"
    print(make(Path(sys.argv[1]), Path(sys.argv[2]), target))
