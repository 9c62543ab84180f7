"""Generate the example problem files in ``orientviz/datasets/examples`` (seeded).

Run ``python -m orientviz.datasets.make_examples`` to rewrite them; the output is
deterministic. All examples are simulated (no third-party data), noisy at the stated σ,
and rounded in the file's units (0.1 µm image, 1 mm object, 10⁻⁶ gon) so that loading
and writing them back reproduces the files exactly.

* ``similarity_example`` — absolute orientation of a plotter model (model coordinates in
  mm at 1 : 5000, model base 220.7 mm as in Kovarik 1968) to object coordinates in m:
  4 full, 2 height-only and 1 planimetric-only control point, 5 new points.
* ``resection_example`` — one vertical wide-angle image (c = 152.7 mm) over 8 control
  points, no approximate orientation (the closed form starts it).
* ``intersection_example`` — a stereo pair with known orientation, the 6 Gruber points
  plus 3 more, one of them a check point.
* ``block_strip`` — a strip of 4 images (readable form), perimeter control, 2 check points.
* ``block_compact`` — 2 strips × 4 images in the compact columnar form.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..block import Block, Cameras, Images, Observations, Points
from ..camera import project
from ..io.kinds.similarity import similarity_problem
from ..io.problem import Problem, Units, save_problem
from ..rotation import matrix_from_opk
from ..simulate import simulate_block
from ..units import to_rad

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE / "examples"
SEED = 19680
LICENCE = "CC0-1.0"
GENERATOR = "simulated by orientviz.datasets.make_examples (seed 19680)"


def _r(a, decimals: int):
    return np.round(np.asarray(a, dtype=float), decimals)


def _frame_block(cam_c, X0, ang_gon, pts, role, obs_img, obs_pt, xy, sigma_mm, ids, names):
    """A Block from rounded file-unit values (m, gon, mm) → internal units."""
    m, p = X0.shape[0], pts.shape[0]
    nan3 = np.full((m, 3), np.nan)
    known = np.where((role > 0)[:, None], pts, np.nan)
    return Block(
        cameras=Cameras(["rmk_152"], np.array([cam_c]), np.zeros(1), np.zeros(1),
                        np.array([[230.0, 230.0]]), [""]),
        images=Images(names, np.zeros(m, np.int64), X0.copy(), to_rad(ang_gon, "gon"),
                      np.full(m, -1, np.int64), nan3, nan3.copy(), nan3.copy(), nan3.copy()),
        points=Points(ids, pts.copy(), role.astype(np.int8), known, np.zeros((p, 3))),
        observations=Observations(obs_img, obs_pt, xy, np.full((len(obs_img), 2), sigma_mm)),
        sequence="opk",
    )  # fmt: skip


def _observe(X0, ang_gon, pts, c, rng, sigma_mm, visible_mm=112.0):
    """All rays of all points in all images (within the format), noisy and rounded."""
    m, p = X0.shape[0], pts.shape[0]
    img = np.repeat(np.arange(m), p)
    pt = np.tile(np.arange(p), m)
    a = to_rad(ang_gon, "gon")
    R = matrix_from_opk(a[:, 0], a[:, 1], a[:, 2])
    xy = project(pts[pt], X0[img], R[img], np.full(img.size, c), 0.0, 0.0)
    inside = np.all(np.abs(xy) < visible_mm, axis=1)
    xy = xy + rng.normal(0.0, sigma_mm, xy.shape)
    return img[inside], pt[inside], _r(xy[inside], 4)


def similarity_example(rng: np.random.Generator):
    scale = 5000.0  # model 1 : 5000, model coordinates in mm
    R = matrix_from_opk(*to_rad([0.8, -1.2, 35.0], "gon"))
    T = np.array([5480.0, 3215.0, 1880.0])
    grid = np.array([[x, y] for y in (-100.0, 0.0, 100.0) for x in (0.0, 110.35, 220.7)])
    extra = np.array([[55.0, -50.0], [165.0, 50.0], [55.0, 50.0]])
    xy = np.vstack([grid, extra])
    z = -300.0 + rng.uniform(-12.0, 12.0, xy.shape[0])
    model_true = np.column_stack([xy, z]) / 1000.0  # m at model scale
    obj_true = T + scale * model_true @ R.T
    model_obs = _r((model_true * 1000.0) + rng.normal(0, 0.01, model_true.shape), 3)  # mm
    sig = np.array([0.05, 0.05, 0.08])
    obj_obs = _r(obj_true + rng.normal(0, 1, obj_true.shape) * sig, 3)
    ids = [f"{100 + k}" for k in range(xy.shape[0])]
    full = [0, 2, 6, 8]
    height = [3, 5]
    plan = [4]
    tgt_idx = full + height + plan
    tgt = obj_obs[tgt_idx].copy()
    tgt[len(full) : len(full) + 2, :2] = np.nan
    tgt[-1, 2] = np.nan
    data = similarity_problem(
        ids, model_obs / 1000.0, [ids[i] for i in tgt_idx], tgt,
        target_sigma=np.where(np.isnan(tgt), np.nan, sig), source_frame="model (plotter)",
        target_frame="object (local, Z up)", source_length="mm",
    )  # fmt: skip
    return data, {
        "truth": {"scale": scale, "omega_gon": 0.8, "phi_gon": -1.2, "kappa_gon": 35.0,
                  "T_m": T.tolist()},
        "noise": "model coordinates σ 0.01 mm; control σ 0.05 m (X, Y), 0.08 m (Z)",
    }  # fmt: skip


def resection_example(rng: np.random.Generator) -> tuple[Block, dict]:
    c = 152.7
    X0 = np.array([[2510.0, 1480.0, 1905.0]])
    ang = np.array([[1.3, -0.8, 12.0]])
    gx, gy = np.meshgrid([-800.0, 0.0, 800.0], [-750.0, 0.0, 750.0])
    pts = np.column_stack([gx.ravel() + 2500.0, gy.ravel() + 1500.0])
    pts = np.delete(pts, 4, axis=0)  # no point at the nadir: 8 control points
    pts = _r(np.column_stack([pts, 380.0 + rng.uniform(-60, 60, len(pts))]), 3)
    img, pt, xy = _observe(X0, ang, pts, c, rng, 0.005)
    ids = [f"P{k + 1}" for k in range(len(pts))]
    block = _frame_block(
        c, X0, ang, pts, np.ones(len(pts), np.int8), img, pt, xy, 0.005, ids, ["img1"]
    )
    block.images.X0[:] = np.nan
    block.images.angles[:] = np.nan
    return block, {"truth": {"X0_m": X0[0].tolist(), "omega_phi_kappa_gon": ang[0].tolist()},
                   "noise": "image coordinates σ 5 µm"}  # fmt: skip


def intersection_example(rng: np.random.Generator) -> tuple[Block, dict]:
    c = 152.7
    X0 = np.array([[0.0, 0.0, 1527.0], [920.0, 12.0, 1531.0]])
    ang = np.array([[0.35, -0.42, 0.9], [-0.61, 0.27, 1.4]])
    xs, ys = [0.0, 460.0, 920.0], [-700.0, 0.0, 700.0]
    pts = np.array([[x, y] for y in ys for x in xs])
    pts = _r(np.column_stack([pts, 150.0 + rng.uniform(-80, 80, len(pts))]), 3)
    img, pt, xy = _observe(X0, ang, pts, c, rng, 0.005)
    ids = [f"G{k + 1}" for k in range(len(pts))]
    role = np.zeros(len(pts), np.int8)
    role[4] = 2  # the middle point is a check point with known coordinates
    block = _frame_block(c, X0, ang, pts, role, img, pt, xy, 0.005, ids, ["L", "R"])
    block.points.xyz[role == 0] = np.nan
    return block, {"noise": "image coordinates σ 5 µm; orientations exact"}


def _rounded_sim(strips: int, images: int, rng: np.random.Generator, **kw) -> Block:
    sim = simulate_block(strips, images, rng=rng, **kw)
    b = sim.block
    b.images.X0 = _r(b.images.X0, 3)
    b.images.angles = to_rad(_r(b.images.angles * 200.0 / np.pi, 6), "gon")
    b.points.xyz = _r(b.points.xyz, 3)
    b.points.xyz_known = _r(b.points.xyz_known, 3)
    b.observations.xy = _r(b.observations.xy, 4)
    return b


def build_all(rng: np.random.Generator | None = None) -> dict[str, tuple]:
    """All examples: name → (kind, data, units, description, extra manifest fields)."""
    rng = np.random.default_rng(SEED) if rng is None else rng
    streams = rng.spawn(5)
    gon = Units(length="m", angle="gon", image="mm")
    sim, info = similarity_example(streams[0])
    res, rinfo = resection_example(streams[1])
    inter, iinfo = intersection_example(streams[2])
    strip = _rounded_sim(1, 4, streams[3], extra=None, n_check=2)
    compact = _rounded_sim(2, 4, streams[4], extra=None, n_check=2)
    return {
        "similarity_example": ("similarity", sim, gon, "absolute orientation of a plotter model "
                               "(7-parameter similarity, partial control)", info),
        "resection_example": ("resection", res, gon, "space resection of one image from 8 "
                              "control points", rinfo),
        "intersection_example": ("intersection", inter, gon, "forward intersection from a "
                                 "stereo pair with known orientation", iinfo),
        "block_strip": ("block", strip, gon, "a strip of 4 images, perimeter control "
                        "(readable form)", {"noise": "image σ 5 µm; approximations perturbed"}),
        "block_compact": ("block", compact, gon, "2 strips × 4 images in the compact "
                          "columnar form", {"noise": "image σ 5 µm; approximations perturbed"}),
    }  # fmt: skip


def main(folder: Path = EXAMPLES) -> list[Path]:
    """Write every example and ``MANIFEST.json``; return the paths written."""
    folder.mkdir(parents=True, exist_ok=True)
    written, manifest = [], []
    for name, (kind, data, units, desc, extra) in build_all().items():
        columnar = name == "block_compact"
        problem = Problem(kind=kind, data=data, units=units, sequence="opk", name=name,
                          description=desc, columnar=columnar)  # fmt: skip
        if kind == "block":
            problem.options = {"control": "fixed"}
        path = save_problem(problem, folder / f"{name}.json")
        written.append(path)
        entry = {
            "name": name,
            "file": path.name,
            "kind": kind,
            "form": "columnar" if columnar else "readable",
            "description": desc,
            "source": GENERATOR,
            "units": units.as_dict(),
            "frame": "local object frame, right-handed, Z up; image frame as in orientviz.camera",
            "licence": LICENCE,
        }
        entry.update(extra)
        manifest.append(entry)
    mpath = folder / "MANIFEST.json"
    text = json.dumps({"format": "orientviz-datasets/1", "datasets": manifest}, indent=1,
                      ensure_ascii=False)  # fmt: skip
    mpath.write_text(text + "\n", encoding="utf-8")
    return written + [mpath]


if __name__ == "__main__":  # pragma: no cover
    for p in main():
        print(p)
