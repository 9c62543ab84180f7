"""03 — A simulated block, its bundle adjustment and its precision.

A block of 3 strips × 6 vertical images (wide angle, 1 : 10 000, 60 % / 20 % overlap)
over hilly terrain, with XYZ control on the perimeter and 6 check points, is simulated
with 5 µm noise on the image coordinates and perturbed start values. The bundle
adjustment estimates every exterior orientation and every tie point at once; its
precision (the cofactor blocks of the points, scaled with σ̂0) says how well each point
is determined. Two independent checks of that claim: σ̂0 should be near 1 (the noise
is what the a-priori σ says), and the true errors of the tie points (known here, it is
a simulation) should be about as large as their predicted σ.

Run: ``python examples/03_bundle_block.py``
"""

import numpy as np

import orientviz as ov


def main() -> None:
    sim = ov.simulate_block(3, 6, rng=np.random.default_rng(3), n_check=6)
    block = sim.block
    print(block.summary())

    adj = ov.bundle_adjust(block)  # precision=True by default
    print(adj.summary())

    # adjusted points (p, 3) m and their a-posteriori σ from the 3 × 3 cofactor blocks
    # (adj is a BundleResult: exterior (m, 6), points (p, 3), check_points, history, …)
    xyz = adj.points
    Q = adj.cofactor_groups["points"]  # (p, 3, 3), m² per unit weight
    sigma_xyz = adj.sigma0 * np.sqrt(np.diagonal(Q, axis1=1, axis2=2))

    tie = block.points.role == ov.TIE  # the point roles: ov.TIE, ov.CONTROL, ov.CHECK
    err = (xyz - sim.truth.points.xyz)[tie]
    rms_true = np.sqrt(np.mean(err**2, axis=0))
    rms_sigma = np.sqrt(np.mean(sigma_xyz[tie] ** 2, axis=0))
    print(f"tie points: {int(tie.sum())}")
    print("                      X       Y       Z   [m]")
    print(f"predicted σ (RMS) {rms_sigma[0]:7.3f} {rms_sigma[1]:7.3f} {rms_sigma[2]:7.3f}")
    print(f"true error (RMS)  {rms_true[0]:7.3f} {rms_true[1]:7.3f} {rms_true[2]:7.3f}")
    ratio = rms_true / rms_sigma
    print(f"true / predicted: {ratio[0]:.2f} {ratio[1]:.2f} {ratio[2]:.2f}")

    check = adj.check_rms  # check points, intersected after the adjustment
    print(f"check points RMS: X {check[0]:.3f}  Y {check[1]:.3f}  Z {check[2]:.3f} m")
    print(f"sigma0 = {adj.sigma0:.3f}  redundancy = {adj.redundancy}")


if __name__ == "__main__":
    main()
