"""Precision of the bundle (orientviz.bundle.precision._precision) against the dense full inverse."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from band_storage import lower_band
from orientviz.bundle.precision import banded_selected_inverse
from orientviz.camera import collinearity_jacobian


class Affinity:
    """A tiny additional-parameter set for the tests: affinity and shear, µm at x = 100 mm."""

    name = "affinity"
    names = ["a1", "a2"]

    def design(self, xy):
        A = np.zeros((xy.shape[0], 2, 2))
        A[:, 0, 0] = 1e-3 * xy[:, 0] / 100.0  # Δx = a1 · x
        A[:, 1, 0] = -1e-3 * xy[:, 1] / 100.0  # Δy = −a1 · y (affinity, not a scale)
        A[:, 1, 1] = 1e-3 * xy[:, 0] / 100.0  # Δy = a2 · x (shear)
        return A


def dense_reference(
    res, block, control_sigma=None, additional=None, ap_group=None, ap_sigma=None, x=None
):
    """Full Jacobian, N = JᵀPJ and Q = N⁻¹ (unknowns: images, free points, APs).

    Evaluated at the solution, or at the parameter vector ``x`` (layout of ``res.x``).
    """
    m = block.n_images
    ext = res["exterior"].reshape(m, 6) if x is None else x[: 6 * m].reshape(m, 6)
    pts = res["points"].reshape(-1, 3) if x is None else x[6 * m :].reshape(-1, 3)[: block.n_points]
    obs = block.observations
    free = np.flatnonzero(block.points.role == 0)
    if control_sigma is not None:
        free = np.flatnonzero(block.points.role != 2)
    col = -np.ones(block.n_points, int)
    col[free] = np.arange(free.size)
    used = np.flatnonzero(block.points.role[obs.point] != 2)
    cam = block.images.camera[obs.image[used]]
    _, Je, Jp, _ = collinearity_jacobian(
        pts[obs.point[used]],
        ext[obs.image[used], :3],
        ext[obs.image[used], 3:],
        block.cameras.c[cam],
        block.cameras.x0[cam],
        block.cameras.y0[cam],
        block.sequence,
    )
    k = 0 if additional is None else len(additional.names)
    G = 0 if additional is None else int(np.max(ap_group)) + 1
    u = 6 * m + 3 * free.size + k * G
    J = np.zeros((2 * used.size, u))
    for r, o in enumerate(used):
        i = obs.image[o]
        J[2 * r : 2 * r + 2, 6 * i : 6 * i + 6] = Je[r]
        if col[obs.point[o]] >= 0:
            c0 = 6 * m + 3 * col[obs.point[o]]
            J[2 * r : 2 * r + 2, c0 : c0 + 3] = Jp[r]
        if k:
            g = ap_group[i]
            c0 = 6 * m + 3 * free.size + k * g
            J[2 * r : 2 * r + 2, c0 : c0 + k] = additional.design(obs.xy[o][None])[0]
    p = (1.0 / obs.sigma[used] ** 2).reshape(-1)
    N = J.T @ (p[:, None] * J)
    if control_sigma is not None:
        ctrl = np.flatnonzero(block.points.role == 1)
        idx = (6 * m + 3 * col[ctrl][:, None] + np.arange(3)).ravel()
        N[idx, idx] += 1.0 / control_sigma**2
    if k and ap_sigma is not None:
        idx = np.arange(6 * m + 3 * free.size, u)
        N[idx, idx] += 1.0 / ap_sigma**2
    Q = np.linalg.inv(N)
    r = 1.0 - p * np.einsum("ij,jk,ik->i", J, Q, J)
    return Q, free, used, r


@pytest.mark.parametrize("case", ["fixed", "weighted", "ap"])
def test_precision_equals_dense_inverse(case):
    sim = ov.simulate_block(2, 4, rng=11, extra=6, n_check=2)
    block = sim.block
    kw = {}
    csig = None
    if case == "weighted":
        csig = 0.03
        block.points.sigma[block.points.role == 1] = csig
        kw["control"] = "weighted"
    if case == "ap":
        kw.update(additional=Affinity(), ap_group=np.arange(block.n_images) % 2, ap_sigma=50.0)
    res = ov.bundle_adjust(block, **kw)
    # without additional parameters the cofactors are those of the last linearisation
    # point (the state before the final correction, whose normal equations are reused)
    x_lin = res.history[-2].x if case != "ap" else None
    Q, free, used, r_ref = dense_reference(
        res, block, csig, kw.get("additional"), kw.get("ap_group"), kw.get("ap_sigma"), x_lin
    )
    m = block.n_images
    ext_blocks = np.stack([Q[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    # exact algebra on a well-conditioned system: agreement to rounding
    np.testing.assert_allclose(
        res.cofactor_groups["exterior"], ext_blocks, rtol=1e-7, atol=1e-9 * np.abs(ext_blocks).max()
    )
    pt_blocks = np.stack(
        [
            Q[6 * m + 3 * j : 6 * m + 3 * j + 3, 6 * m + 3 * j : 6 * m + 3 * j + 3]
            for j in range(free.size)
        ]
    )
    np.testing.assert_allclose(
        res.cofactor_groups["points"][free],
        pt_blocks,
        rtol=1e-7,
        atol=1e-9 * np.abs(pt_blocks).max(),
    )
    rn = res.redundancy_numbers[: 2 * block.n_observations].reshape(-1, 2)
    np.testing.assert_allclose(rn[used].reshape(-1), r_ref, atol=1e-8)
    # the redundancy numbers add up to the redundancy (Σ r_i = n − u)
    assert np.isclose(np.nansum(res.redundancy_numbers), res.redundancy, atol=1e-6)
    if case == "ap":
        q0 = 6 * m + 3 * free.size
        np.testing.assert_allclose(res.cofactor_groups["additional"], Q[q0:, q0:], rtol=1e-7)


@pytest.mark.parametrize("nb", [16, 96])  # 96: block rows wider than the band (kd = 34)
def test_banded_selected_inverse_matches_dense(nb):
    rng = np.random.default_rng(5)
    n, kd = 230, 17
    A = np.zeros((n, n))
    for d in range(kd + 1):
        v = rng.normal(size=n - d)
        A[np.arange(d, n), np.arange(n - d)] = v
    S = A @ A.T + n * np.eye(n)  # banded with half-bandwidth 2·kd
    kd2 = 2 * kd
    ab = lower_band(S, kd2)
    import scipy.linalg

    cb = scipy.linalg.cholesky_banded(ab, lower=True)
    Zb = banded_selected_inverse(cb, nb=nb)
    Z = np.linalg.inv(S)
    for d in range(kd2 + 1):
        np.testing.assert_allclose(Zb[: n - d, d], np.diagonal(Z, d), rtol=1e-9, atol=1e-13)


def test_precision_at_last_linearisation_is_that_of_the_solution():
    """The reused linearisation differs from the solution by less than the stopping rule."""
    sim = ov.simulate_block(2, 4, rng=11, extra=6, n_check=2)
    res = ov.bundle_adjust(sim.block)
    assert len(res.history) >= 3  # at least two corrections: the last one is tiny
    Q_final = dense_reference(res, sim.block)[0]
    Q_lin = dense_reference(res, sim.block, x=res.history[-2].x)[0]
    m = sim.block.n_images
    ext = np.stack([Q_final[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    got = res.cofactor_groups["exterior"]
    lin = np.stack([Q_lin[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    np.testing.assert_allclose(got, lin, rtol=1e-7, atol=1e-9 * np.abs(lin).max())
    # σ of the orientations at the solution and at the reused point: same to 1e-5
    np.testing.assert_allclose(
        np.sqrt(np.einsum("nii->ni", got)), np.sqrt(np.einsum("nii->ni", ext)), rtol=1e-5
    )


def _assert_cofactors_close(got, ref, rtol):
    """Cofactor blocks (..., a, b) equal to ``rtol`` in units of σ_i σ_j (scale-free).

    Entries are compared relative to sqrt(Q_ii Q_jj) of the reference, i.e. as
    correlation-scaled cofactors: an element of 1e-12 m·rad next to σ's of 1e-3 m and
    1e-5 rad is judged on that scale, not on its own.
    """
    da = np.sqrt(np.einsum("...ii->...i", ref))
    scale = da[..., :, None] * da[..., None, :]
    err = np.abs(got - ref) / scale
    assert np.max(err) <= rtol, f"max scaled difference {np.max(err):.3g} > {rtol:g}"


def _cross_scale(Q, i, j):
    """sqrt(Q_ii Q_jj) for the off-diagonal block of rows i, columns j."""
    d = np.sqrt(np.diag(Q))
    return d[i][:, None] * d[j][None, :]


@pytest.mark.parametrize("path", ["dense", "banded", "banded-at"])
def test_precision_with_strip_parameters_equals_dense_inverse(path, monkeypatch):
    """Ebner's 12 parameters per strip (3 strips): the sparse-by-group parameter terms and,
    with ``path="banded"``, the banded border solves against the full dense inverse (the
    band's blocks by one gather from the whole band, or with ``"banded-at"`` only the
    wanted entries, as for a band above ``BAND_GATHER_LIMIT``)."""
    from orientviz.bundle import BundleOptions, ap_set
    from orientviz.bundle.precision import _precision

    if path == "banded-at":
        monkeypatch.setattr(_precision, "BAND_GATHER_LIMIT", 0)

    # "banded": the banded selected inverse and banded solves even when small
    opts = BundleOptions(dense_inverse_limit=0 if path != "dense" else 3000)
    sim = ov.simulate_block(3, 5, rng=21, extra=6, n_check=2)
    block = sim.block
    aps = ap_set("ebner12")
    grp = block.images.strip
    res = ov.bundle_adjust(block, additional=aps, ap_group=grp, ap_sigma=10.0, options=opts)
    assert res.converged
    Q, free, used, r_ref = dense_reference(res, block, None, aps, grp, 10.0)
    m = block.n_images
    ext = np.stack([Q[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    tol = 1e-9
    _assert_cofactors_close(res.cofactor_groups["exterior"], ext, tol)
    o = 6 * m
    pts = np.stack(
        [Q[o + 3 * j : o + 3 * j + 3, o + 3 * j : o + 3 * j + 3] for j in range(free.size)]
    )
    _assert_cofactors_close(res.cofactor_groups["points"][free], pts, tol)
    q0 = 6 * m + 3 * free.size
    _assert_cofactors_close(res.cofactor_groups["additional"], Q[q0:, q0:], tol)
    # image-pair blocks of Q_cc (used by the 2-D tests of check rays)
    keys, blocks = res.exterior_pairs.keys, res.exterior_pairs.blocks
    r6 = np.arange(6)
    for key, blk in zip(keys, blocks):
        i, j = divmod(int(key), m)
        ref = Q[6 * i : 6 * i + 6, 6 * j : 6 * j + 6]
        err = np.abs(blk - ref) / _cross_scale(Q, 6 * i + r6, 6 * j + r6)
        assert err.max() <= tol, (i, j, err.max())
    rn = res.redundancy_numbers[: 2 * block.n_observations].reshape(-1, 2)
    np.testing.assert_allclose(rn[used].reshape(-1), r_ref, rtol=0, atol=tol)
    # pseudo-observations of the parameters: r = 1 − p·Q_aa,ii
    r_ap = res.redundancy_numbers[res.obs_slices["additional"]]
    np.testing.assert_allclose(r_ap, 1.0 - np.diag(Q[q0:, q0:]) / 10.0**2, rtol=0, atol=tol)
    assert np.isclose(np.nansum(res.redundancy_numbers), res.redundancy, rtol=0, atol=1e-8)
