"""The peer's side of the SfM benchmarks: a BAL problem or a COLMAP model as a pycolmap
``Reconstruction`` holding the same model orientviz solves.

Imported by the worker processes of ``bench_sfm.py`` and ``verify_sfm.py`` (each puts this
folder on ``sys.path``); needs pycolmap, which only the benchmarks use.
"""

from __future__ import annotations

import numpy as np
import pycolmap

from orientviz.io.bal import read_bal_arrays
from orientviz.rotation import matrix_from_rotvec

#: BAL's camera frame (x right, y up, looking along −z) to COLMAP's (y down, looking along +z).
FLIP = np.diag([1.0, 1.0, -1.0])


def bal_reconstruction(path: str) -> pycolmap.Reconstruction:
    """A BAL problem as a reconstruction: one RADIAL camera (f, k1, k2) per BAL camera.

    The principal point is 0 (BAL's pixels are about the image centre); the image size
    2000 px only bounds pycolmap's checks. Image ``i`` of the file is image id ``i + 1``.
    """
    obs, cams, pts = read_bal_arrays(path)
    rec = pycolmap.Reconstruction()
    ci, pi = obs[:, 0].astype(int), obs[:, 1].astype(int)
    order = np.argsort(ci, kind="stable")
    oc, op, uv = ci[order], pi[order], obs[order, 2:4]
    starts = np.searchsorted(oc, np.arange(len(cams) + 1))
    Rb = matrix_from_rotvec(cams[:, :3])
    for i in range(len(cams)):
        cam = pycolmap.Camera(model="RADIAL", width=2000, height=2000, camera_id=i + 1,
                              params=[cams[i, 6], 0.0, 0.0, cams[i, 7], cams[i, 8]])  # fmt: skip
        rec.add_camera_with_trivial_rig(cam)
        pose = pycolmap.Rigid3d(pycolmap.Rotation3d(FLIP @ Rb[i] @ FLIP), FLIP @ cams[i, 3:6])
        img = pycolmap.Image(name=f"img{i}", keypoints=uv[starts[i] : starts[i + 1]],
                             camera_id=i + 1, image_id=i + 1)  # fmt: skip
        rec.add_image_with_trivial_frame(img, pose)
    index_in_image = np.arange(len(oc)) - starts[oc]
    by_point = np.argsort(op, kind="stable")
    point_starts = np.searchsorted(op[by_point], np.arange(len(pts) + 1))
    for j in range(len(pts)):
        track = pycolmap.Track()
        for k in by_point[point_starts[j] : point_starts[j + 1]]:
            track.add_element(int(oc[k]) + 1, int(index_in_image[k]))
        rec.add_point3D(FLIP @ pts[j], track)
    return rec


def drop_repeated_observations(rec: pycolmap.Reconstruction) -> int:
    """Delete every observation of a point in an image that already observes it.

    The first keypoint (lowest POINT2D_IDX) is kept, as orientviz's ``import-colmap``
    keeps it, so both solvers minimise the same ½Σr²; a track left with one observation
    loses its point (COLMAP's rule). Returns the number of observations deleted.
    """
    repeated = 0
    for pid in list(rec.point3D_ids()):
        if not rec.exists_point3D(pid):
            continue
        seen = set()
        track = sorted((e.image_id, e.point2D_idx) for e in rec.point3D(pid).track.elements)
        for image_id, idx in track:
            if image_id in seen and rec.exists_point3D(pid):
                rec.delete_observation(image_id, idx)
                repeated += 1
            seen.add(image_id)
    return repeated


def full_model_options(num_threads: int) -> pycolmap.BundleAdjustmentOptions:
    """pycolmap's bundle adjustment of orientviz's full model: f and the distortion terms
    refined per camera, the principal point held; no summary printed."""
    opts = pycolmap.BundleAdjustmentOptions()
    opts.refine_focal_length = True
    opts.refine_principal_point = False
    opts.refine_extra_params = True
    opts.print_summary = False
    opts.ceres.solver_options.num_threads = num_threads
    return opts


def adjuster(rec: pycolmap.Reconstruction, opts: pycolmap.BundleAdjustmentOptions):
    """The default bundle adjuster over every registered image, the gauge held by two
    cameras (COLMAP's ``TWO_CAMS_FROM_WORLD``)."""
    config = pycolmap.BundleAdjustmentConfig()
    for i in sorted(rec.reg_image_ids()):
        config.add_image(i)
    config.fix_gauge(pycolmap.BundleAdjustmentGauge.TWO_CAMS_FROM_WORLD)
    return pycolmap.create_default_bundle_adjuster(opts, config, rec)
