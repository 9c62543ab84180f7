"""02 — Relative orientation of a stereo pair: form the stereo model.

Two overlapping aerial images see the same 15 ground points. Relative orientation finds
the five elements that make every pair of homologous rays intersect: for a *dependent*
pair the left image stays fixed (R = I) and the right one gets the base components
by, bz and the rotations ω, φ, κ. The result is the stereo model, at an arbitrary scale
(the base b = the median x-parallax in mm puts it at about image scale).

The image coordinates are simulated from a known pair plus 5 µm of noise, so the
estimated elements can be compared with the truth: angles directly, the base components
as ratios by/b and bz/b (the model's scale is free).

Run: ``python examples/02_relative_orientation.py``
"""

import numpy as np

import orientviz as ov


def main() -> None:
    rng = np.random.default_rng(2)
    c = 152.0  # principal distance, mm

    # the true pair, in a frame with the left projection centre at the origin (m)
    base = np.array([900.0, 15.0, 10.0])  # bx, by, bz
    angles = ov.to_rad(np.array([0.8, -1.1, 0.6]), "gon")  # ω, φ, κ of the right image
    R_left, R_right = np.eye(3), ov.matrix_from_opk(*angles)

    # ground points in the overlap, about 1500 m below the cameras, 10 % relief
    n = 15
    X = rng.uniform(-150.0, 1050.0, n)
    Y = rng.uniform(-900.0, 900.0, n)
    Z = -1500.0 + rng.uniform(-75.0, 75.0, n)
    points = np.column_stack([X, Y, Z])

    sigma = 0.005  # mm
    xy_left = ov.project(points, np.zeros(3), R_left, c) + rng.normal(0.0, sigma, (n, 2))
    xy_right = ov.project(points, base, R_right, c) + rng.normal(0.0, sigma, (n, 2))

    # the observations are y-parallaxes y' − y'' at image scale: σ√2 when each image
    # coordinate has σ
    adj = ov.relative_orientation(xy_left, xy_right, c, kind="dependent", sigma=np.sqrt(2) * sigma)
    print(adj.summary())

    b = adj.base  # the model base, mm at image scale
    by, bz, omega, phi, kappa = adj.x
    s_by, s_bz, *s_angles = adj.std()
    print(f"model base b = {b:.2f} mm (model at about image scale)")
    print(f"by/b  = {by / b:+.5f} ± {s_by / b:.5f}   (true {base[1] / base[0]:+.5f})")
    print(f"bz/b  = {bz / b:+.5f} ± {s_bz / b:.5f}   (true {base[2] / base[0]:+.5f})")
    for name, est, s, true in zip(
        ("omega", "phi", "kappa"), (omega, phi, kappa), s_angles, angles, strict=True
    ):
        e, s, t = ov.from_rad(np.array([est, s, true]), "gon")
        print(f"{name:5s} = {e:+.4f} ± {s:.4f} gon   (true {t:+.4f} gon)")
    z = np.abs(adj.x[2:] - angles) / np.asarray(s_angles)
    print(f"largest angle error / σ: {z.max():.2f}")
    model = adj.points  # model coordinates of the 15 points, model units (mm)
    print(
        f"model points: {len(model)}, heights Z from {model[:, 2].min():.1f} to {model[:, 2].max():.1f} mm"
    )
    print(f"sigma0 = {adj.sigma0:.3f}  redundancy = {adj.redundancy}")


if __name__ == "__main__":
    main()
