"""01 — Space resection: where was the camera?

Eight control points with known object coordinates are measured in one aerial image.
The resection finds the projection centre X0 (m) and the attitude ω, φ, κ of the image
by least squares (collinearity equations), starting from Grunert's closed form, and
tells how precisely they are determined.

The image coordinates are simulated here from a known orientation plus 5 µm of noise,
so the estimate can be compared with the truth.

Run: ``python examples/01_resection.py``
"""

import numpy as np

import orientviz as ov


def main() -> None:
    rng = np.random.default_rng(1)
    camera = ov.FrameCamera(c=152.0)  # principal distance in mm, format 230 × 230 mm

    # the truth: a vertical image 1500 m above ground, slightly tilted
    X0_true = np.array([500.0, 400.0, 1500.0])  # m
    angles_true = ov.to_rad(np.array([1.2, -0.8, 35.0]), "gon")  # ω, φ, κ
    R_true = ov.matrix_from_opk(*angles_true)

    # control points on hilly ground within the image footprint (m)
    XY = rng.uniform(-600.0, 600.0, size=(8, 2)) + X0_true[:2]
    Z = rng.uniform(0.0, 120.0, size=8)
    XYZ = np.column_stack([XY, Z])

    sigma = 0.005  # mm = 5 µm, a-priori σ of an image coordinate
    xy = ov.project(XYZ, X0_true, R_true, camera.c) + rng.normal(0.0, sigma, size=(8, 2))

    adj = ov.resection(xy, XYZ, camera, sigma=sigma)
    print(adj.summary())

    est, std = adj.x, adj.std()  # internal units: m and rad; σ a-posteriori
    truth = np.concatenate([X0_true, angles_true])
    print(f"{'':6s} {'estimate':>12s} {'σ':>9s} {'true error':>11s}")
    for k, name in enumerate(adj.names):
        if k < 3:  # projection centre: m
            print(f"{name:6s} {est[k]:10.3f} m {std[k]:7.3f} m {est[k] - truth[k]:9.3f} m")
        else:  # angles: gon, their σ and errors in mgon
            v, s, e = ov.from_rad(np.array([est[k], std[k], est[k] - truth[k]]), "gon")
            print(f"{name:6s} {v:8.4f} gon {1e3 * s:6.1f} mgon {1e3 * e:7.1f} mgon")
    z = np.abs(est - truth) / std
    print(f"largest error / σ: {z.max():.2f}")
    print(f"sigma0 = {adj.sigma0:.3f}  redundancy = {adj.redundancy}")


if __name__ == "__main__":
    main()
