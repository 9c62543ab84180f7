"""Auxiliary data together with self-calibration, and the precision with auxiliary data.

The bundle's bordered solve (additional parameters + offsets/drifts,
orientviz.bundle.problem._auxiliary_border) and its precision are compared with a dense reference
built here from scratch: the full weighted Jacobian of all observations (image rays by
orientviz.camera.collinearity_jacobian, the parameters' pseudo-observations, the
auxiliary rows straight from the Auxiliary data) over all unknowns.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CHECK, CONTROL, TIE
from orientviz.bundle import adjust_with_auxiliary, ap_set
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
from orientviz.camera import collinearity_jacobian
from orientviz.simulate import height_control_at_ends, simulate_auxiliary

AP_SIGMA = 10.0  # µm


@pytest.fixture(scope="module")
def case():
    """2 × 6 block, full control only in the chains at both ends (the others made tie
    points); statoscope (offset and drift per strip), APR (offset per strip), absolute
    GNSS."""
    sim = ov.simulate_block(
        2, 6, rng=np.random.default_rng(8), control="chains", control_kind="xy+z",
        chain_spacing=2, n_check=6,
    )  # fmt: skip
    block = height_control_at_ends(sim.block)
    pts = block.points
    partial = (pts.role == CONTROL) & ~np.isfinite(pts.xyz_known).all(axis=1)
    pts.role[partial] = TIE
    pts.xyz_known[partial] = np.nan
    assert 4 <= np.sum(pts.role == CONTROL) < 12
    rng = np.random.default_rng(1)
    st = simulate_auxiliary(
        sim, "statoscope", rng=rng, sigma=0.3, offset_sigma=20.0, drift_sigma=2.0
    )
    apr = simulate_auxiliary(sim, "apr", rng=rng, sigma=0.5, offset_sigma=20.0)
    gnss = simulate_auxiliary(
        sim, "gnss", rng=rng, sigma=0.1, offset_sigma=0.0, estimate_offsets=False
    )
    return sim, block, {"stat+apr": [st, apr], "gnss": [gnss]}


class Dense:
    """All observations of the joint adjustment as one dense weighted system."""

    def __init__(self, block, aux, aps, group):
        self.block, self.aux, self.aps, self.group = block, aux, aps, group
        obs = block.observations
        self.used = np.flatnonzero(block.points.role[obs.point] != CHECK)
        self.var = np.flatnonzero(block.points.role == TIE)
        self.col = -np.ones(block.n_points, int)
        self.col[self.var] = np.arange(self.var.size)
        m = block.n_images
        self.k = len(aps.names) if aps else 0
        self.q = self.k * (int(group.max()) + 1 if aps else 0)
        # offsets/drifts: named like the bundle's ("statoscope.drift_Z@s1")
        self.gnames = []
        for a in aux:
            if not a.offsets:
                continue
            dims = "XYZ" if a.kind == "gnss" else "Z"
            for s in range(int(a.strip.max()) + 1):
                for p in ("offset", "drift")[: 1 + bool(a.drift)]:
                    self.gnames += [f"{a.kind}.{p}_{d}@s{s}" for d in dims]
        self.o_ap = 6 * m + 3 * self.var.size
        self.o_g = self.o_ap + self.q
        self.u = self.o_g + len(self.gnames)

    def split(self, x):
        m = self.block.n_images
        ext = x[: 6 * m].reshape(m, 6)
        xyz = self.block.points.xyz.copy()
        ctrl = self.block.points.role != TIE
        xyz[ctrl] = np.where(
            np.isfinite(self.block.points.xyz_known[ctrl]),
            self.block.points.xyz_known[ctrl],
            xyz[ctrl],
        )
        xyz[self.var] = x[6 * m : self.o_ap].reshape(-1, 3)
        return ext, xyz, x[self.o_ap : self.o_g], x[self.o_g :]

    def system(self, x):
        """Weighted misclosures f − l over σ and the weighted Jacobian (rows, u)."""
        b, obs = self.block, self.block.observations
        ext, xyz, a, g = self.split(x)
        u, m = self.used, b.n_images
        cam = b.images.camera[obs.image[u]]
        f, Je, Jp, _ = collinearity_jacobian(
            xyz[obs.point[u]], ext[obs.image[u], :3], ext[obs.image[u], 3:],
            b.cameras.c[cam], b.cameras.x0[cam], b.cameras.y0[cam], b.sequence,
        )  # fmt: skip
        J = np.zeros((2 * u.size, self.u))
        for r, o in enumerate(u):
            rows = slice(2 * r, 2 * r + 2)
            i = obs.image[o]
            J[rows, 6 * i : 6 * i + 6] = Je[r]
            c = self.col[obs.point[o]]
            if c >= 0:
                J[rows, 6 * m + 3 * c : 6 * m + 3 * c + 3] = Jp[r]
        if self.q:
            A = self.aps.design(obs.xy[u])
            for r, o in enumerate(u):
                c0 = self.o_ap + self.k * self.group[obs.image[o]]
                J[2 * r : 2 * r + 2, c0 : c0 + self.k] = A[r]
                f[r] += A[r] @ a[c0 - self.o_ap : c0 - self.o_ap + self.k]
        sw = (1.0 / obs.sigma[u]).reshape(-1)
        parts_r, parts_J = [(f - obs.xy[u]).reshape(-1) * sw], [J * sw[:, None]]
        if self.q:  # a = 0 ± σ
            Ja = np.zeros((self.q, self.u))
            Ja[np.arange(self.q), self.o_ap + np.arange(self.q)] = 1.0 / AP_SIGMA
            parts_r.append(a / AP_SIGMA)
            parts_J.append(Ja)
        for d in self.aux:
            on_img = d.kind != "apr"
            dims = (0, 1, 2) if d.kind == "gnss" else (2,)
            vals = np.asarray(d.values, float).reshape(d.index.size, len(dims))
            for j, c in enumerate(dims):
                Jr = np.zeros((d.index.size, self.u))
                rows = np.arange(d.index.size)
                if on_img:
                    val = ext[d.index, c]
                    Jr[rows, 6 * d.index + c] = 1.0
                else:
                    val = xyz[d.index, c]
                    Jr[rows, 6 * m + 3 * self.col[d.index] + c] = 1.0
                if d.offsets:
                    for s in range(int(d.strip.max()) + 1):
                        sel = d.strip == s
                        k = self.o_g + self.gnames.index(f"{d.kind}.offset_{'XYZ'[c]}@s{s}")
                        val = val + sel * x[k]
                        Jr[sel, k] = 1.0
                        if d.drift:
                            k = self.o_g + self.gnames.index(f"{d.kind}.drift_{'XYZ'[c]}@s{s}")
                            val = val + sel * d.time * x[k]
                            Jr[sel, k] = d.time[sel]
                parts_r.append((val - vals[:, j]) / d.sigma)
                parts_J.append(Jr / d.sigma)
        return np.concatenate(parts_r), np.vstack(parts_J)

    def step(self, x):
        r, J = self.system(x)
        return np.linalg.solve(J.T @ J, -J.T @ r)

    def adjust(self, x, iterations=12):
        for _ in range(iterations):
            x = x + self.step(x)
        return x

    def from_bundle(self, ext, xyz, ap, g, names):
        """The bundle's state in this layout (g by name)."""
        gd = dict(zip(names, g, strict=True))
        return np.concatenate(
            [ext.ravel(), xyz[self.var].ravel(), ap, [gd[n] for n in self.gnames]]
        )


def _problem(block, aux, aps, group):
    return BundleProblem(
        block, point_setup(block, "fixed"), additional=aps, ap_group=group,
        ap_sigma=AP_SIGMA if aps else None, auxiliary=aux,
    )  # fmt: skip


@pytest.mark.parametrize("kind", ["stat+apr", "gnss"])
@pytest.mark.parametrize("held", [False, True])
def test_joint_step_equals_the_dense_step(case, kind, held):
    """One Gauss-Newton step of the bordered system (parameters + offsets/drifts),
    from a state away from the solution, equals the dense normal-equation step."""
    sim, block, auxs = case
    aux, aps, grp = auxs[kind], ap_set("ebner12"), block.images.strip
    prob = _problem(block, aux, aps, grp)
    dense = Dense(block, aux, aps, grp)
    assert prob.q == dense.q > 0 and prob.na == len(dense.gnames)
    assert np.array_equal(prob.points.unknown, dense.var)
    rng = np.random.default_rng(3)
    st = BundleState(
        block.images.X0.copy(), block.images.angles.copy(), block.points.xyz.copy(),
        rng.normal(0, 3, prob.q), rng.normal(0, 2, prob.na),
    )  # fmt: skip
    fixed = block.points.role != TIE
    st.xyz[fixed] = np.where(
        np.isfinite(block.points.xyz_known[fixed]), block.points.xyz_known[fixed], st.xyz[fixed]
    )
    prob.run.border.hold = held
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    dc, dp, d, _ = prob.solve(ne, prob.names()[: 6 * prob.m])
    assert d.size == prob.q + prob.na and ne.diagF.size == d.size
    names = prob.aux.rows.names
    x0 = dense.from_bundle(np.hstack([st.X0, st.angles]), st.xyz, st.ap, st.g, names)
    got = dense.from_bundle(dc, np.zeros_like(st.xyz), d[: prob.q], d[prob.q :], names)
    got[6 * prob.m : dense.o_ap] = dp.ravel()
    if held:  # the parameters held at their values: their columns leave the system
        r, J = dense.system(x0)
        keep = np.r_[0 : dense.o_ap, dense.o_g : dense.u]
        Jk = J[:, keep]
        ref = np.zeros(dense.u)
        ref[keep] = np.linalg.solve(Jk.T @ Jk, -Jk.T @ r)
    else:
        ref = dense.step(x0)
    assert np.abs(ref).max() > 1.0  # a real step (metres), not a converged state
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


@pytest.fixture(scope="module")
def joint(case):
    """Bundle with statoscope + APR and Ebner's 12 parameters per strip, and the dense
    Gauss-Newton solution of the same model from the same start."""
    sim, block, auxs = case
    aux, aps, grp = auxs["stat+apr"], ap_set("ebner12"), block.images.strip
    res = ov.bundle_adjust(
        block, additional=aps, ap_group=grp, ap_sigma=AP_SIGMA, auxiliary=aux, tol=1e-9
    )
    dense = Dense(block, aux, aps, grp)
    prob = _problem(block, aux, aps, grp)
    x0 = dense.from_bundle(
        np.hstack([block.images.X0, block.images.angles]), block.points.xyz,
        np.zeros(prob.q), np.zeros(prob.na), prob.aux.rows.names,
    )  # fmt: skip
    return res, dense, dense.adjust(x0), aux


def _bundle_x(res, dense):
    m = dense.block.n_images
    ext = res.exterior
    xyz = res.points
    ap = res.x[res.groups["additional"]]
    gd = {}
    for kind, arr in res.auxiliary.offsets.items():
        names = [n for n in res.auxiliary.names if n.startswith(kind + ".")]
        # names run strip-major, then offset/drift, then coordinate: arr (strips, dims, npar)
        flat = arr.transpose(0, 2, 1).reshape(-1)
        gd.update(zip(names, flat, strict=True))
    g = [gd[n] for n in dense.gnames]
    assert ext.shape == (m, 6)
    return dense.from_bundle(ext, xyz, ap, np.asarray(g), dense.gnames)


def test_joint_solution_equals_dense_gauss_newton(joint):
    res, dense, x_ref, aux = joint
    assert res.converged
    x = _bundle_x(res, dense)
    # the dense solution is a fixed point of the dense iteration
    assert np.abs(dense.step(x_ref)).max() < 1e-9
    scale = np.maximum(np.abs(x_ref), 1.0)
    np.testing.assert_array_less(np.abs(x - x_ref) / scale, 1e-8)
    # σ0 from the same vᵀPv and redundancy
    r, J = dense.system(x_ref)
    assert res.redundancy == r.size - dense.u
    assert res.sigma0 == pytest.approx(np.sqrt(r @ r / (r.size - dense.u)), rel=1e-8)
    # the drift names of the bundle decode like the dense layout
    assert all(re.match(r"(statoscope|apr)\.(offset|drift)_Z@s\d", n) for n in dense.gnames)


def test_precision_with_auxiliary_data_equals_the_dense_inverse(joint):
    res, dense, x_ref, aux = joint
    r, J = dense.system(x_ref)
    Q = np.linalg.inv(J.T @ J)
    m, pv = dense.block.n_images, dense.var.size
    ext = np.stack([Q[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    o = 6 * m + 3 * np.arange(pv)
    pts = np.stack([Q[a : a + 3, a : a + 3] for a in o])

    def close(got, ref):
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())

    close(res.cofactor_groups["exterior"], ext)
    close(res.cofactor_groups["points"][dense.var], pts)
    close(res.cofactor_groups["additional"], Q[dense.o_ap : dense.o_g, dense.o_ap : dense.o_g])
    # offsets/drifts: the bundle's order mapped onto the dense one
    perm = [res.auxiliary.names.index(n) for n in dense.gnames]
    Qg = res.cofactor_groups["auxiliary"][np.ix_(perm, perm)]
    close(Qg, Q[dense.o_g :, dense.o_g :])
    # redundancy numbers: image rays (used ones), parameter pseudo-observations, aux rows
    ref_r = 1.0 - np.einsum("ij,jk,ik->i", J, Q, J)
    n_img = 2 * dense.block.n_observations
    rn = res.redundancy_numbers
    sl = res.obs_slices
    rimg = rn[:n_img].reshape(-1, 2)[dense.used].reshape(-1)
    n_used = 2 * dense.used.size
    np.testing.assert_allclose(rimg, ref_r[:n_used], rtol=0, atol=1e-9)
    np.testing.assert_allclose(rn[sl["additional"]], ref_r[n_used : n_used + dense.q], atol=1e-9)
    r_aux = rn[sl["auxiliary"]]
    np.testing.assert_allclose(r_aux, ref_r[n_used + dense.q :], rtol=0, atol=1e-9)
    assert r_aux.size == sum(a.index.size for a in aux) and np.all((r_aux > 0) & (r_aux < 1))
    # Σ r = n − u, over all observations of the joint adjustment
    assert np.nansum(rn) == pytest.approx(res.redundancy, abs=1e-6)
    assert res.redundancy_check == pytest.approx(res.redundancy, abs=1e-6)
    # residuals and normalised residuals of the aux rows: same length, v / (σ √r)
    v = res.residuals[sl["auxiliary"]]
    np.testing.assert_allclose(v, res.auxiliary.residuals)
    s = res.sigma_obs[sl["auxiliary"]]
    np.testing.assert_allclose(res.normalized_residuals[sl["auxiliary"]], v / (s * np.sqrt(r_aux)))
    assert res.residuals.size == res.sigma_obs.size == rn.size == res.normalized_residuals.size


def test_ray_gains_with_auxiliary_data_equal_the_dense_inverse(joint):
    """``ray_gains`` (external reliability of the rays) = Q Jᵀ P½ per ray."""
    res, dense, x_ref, _ = joint
    _, J = dense.system(x_ref)
    Q = np.linalg.inv(J.T @ J)
    obs, m = dense.block.observations, dense.block.n_images
    u = dense.used
    QJ = np.stack([Q @ J[2 * k : 2 * k + 2].T for k in range(u.size)])  # (rays, unknowns, 2)
    ie = 6 * obs.image[u][:, None] + np.arange(6)
    ref_e = np.take_along_axis(QJ, ie[:, :, None], axis=1)
    got_e = res.ray_gains.exterior[u]
    for sl in (slice(0, 3), slice(3, 6)):  # m and rad
        ref = ref_e[:, sl]
        np.testing.assert_allclose(got_e[:, sl], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    c = dense.col[obs.point[u]]
    v = c >= 0
    ip = 6 * m + 3 * c[v][:, None] + np.arange(3)
    ref_p = np.take_along_axis(QJ[v], ip[:, :, None], axis=1)
    got_p = res.ray_gains.points[u]
    np.testing.assert_allclose(got_p[v], ref_p, rtol=0, atol=1e-9 * np.abs(ref_p).max())
    assert np.all(got_p[~v] == 0.0)  # fixed points do not move


@pytest.mark.parametrize("kind", ["stat+apr", "gnss"])
def test_precision_without_parameters_equals_the_dense_inverse(case, kind):
    """Auxiliary data alone (no self-calibration), also absolute GNSS (no offsets)."""
    sim, block, auxs = case
    aux = auxs[kind]
    res = ov.bundle_adjust(block, auxiliary=aux, tol=1e-9)
    dense = Dense(block, aux, None, None)
    r, J = dense.system(_bundle_x_plain(res, dense))
    Q = np.linalg.inv(J.T @ J)
    m = block.n_images
    ext = np.stack([Q[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] for i in range(m)])
    np.testing.assert_allclose(
        res.cofactor_groups["exterior"], ext, rtol=1e-9, atol=1e-9 * np.abs(ext).max()
    )
    ref_r = 1.0 - np.einsum("ij,jk,ik->i", J, Q, J)
    sl = res.obs_slices
    np.testing.assert_allclose(
        res.redundancy_numbers[sl["auxiliary"]], ref_r[2 * dense.used.size :], atol=1e-9
    )
    assert np.nansum(res.redundancy_numbers) == pytest.approx(res.redundancy, abs=1e-6)
    assert res.cofactor_groups["auxiliary"].shape == (len(dense.gnames),) * 2


def test_points_and_rays_with_offsets_alone_equal_the_dense_inverse(case):
    """Statoscope + APR without self-calibration: the border's terms are computed only at
    the points an offset couples (APR ground points, orientviz.bundle.precision.
    _border_points); every point's cofactors, every ray's redundancy numbers and gains
    still equal the dense inverse, and the offsets couple some points but not all."""
    sim, block, auxs = case
    aux = auxs["stat+apr"]
    res = ov.bundle_adjust(block, auxiliary=aux, tol=1e-9)
    dense = Dense(block, aux, None, None)
    r, J = dense.system(_bundle_x_plain(res, dense))
    Q = np.linalg.inv(J.T @ J)
    m, u = block.n_images, dense.used
    o = 6 * m + 3 * np.arange(dense.var.size)
    pts = np.stack([Q[a : a + 3, a : a + 3] for a in o])
    got = res.cofactor_groups["points"][dense.var]
    np.testing.assert_allclose(got, pts, rtol=1e-9, atol=1e-9 * np.abs(pts).max())
    ref_r = 1.0 - np.einsum("ij,jk,ik->i", J, Q, J)
    rimg = res.redundancy_numbers[: 2 * block.n_observations].reshape(-1, 2)[u].reshape(-1)
    np.testing.assert_allclose(rimg, ref_r[: 2 * u.size], rtol=0, atol=1e-9)
    QJ = np.stack([Q @ J[2 * k : 2 * k + 2].T for k in range(u.size)])  # (rays, unknowns, 2)
    obs = block.observations
    c = dense.col[obs.point[u]]
    v = c >= 0
    ip = 6 * m + 3 * c[v][:, None] + np.arange(3)
    ref_p = np.take_along_axis(QJ[v], ip[:, :, None], axis=1)
    got_p = res.ray_gains.points[u][v]
    np.testing.assert_allclose(got_p, ref_p, rtol=0, atol=1e-9 * np.abs(ref_p).max())
    ie = 6 * obs.image[u][:, None] + np.arange(6)
    ref_e = np.take_along_axis(QJ, ie[:, :, None], axis=1)
    got_e = res.ray_gains.exterior[u]
    np.testing.assert_allclose(got_e, ref_e, rtol=0, atol=1e-9 * np.abs(ref_e).max())
    apr = next(a for a in aux if a.kind == "apr")
    coupled = np.isin(dense.var, apr.index)
    assert 0 < coupled.sum() < dense.var.size


def _bundle_x_plain(res, dense):
    gd = {}
    for kind, arr in res.auxiliary.offsets.items():
        names = [n for n in res.auxiliary.names if n.startswith(kind + ".")]
        gd.update(zip(names, arr.transpose(0, 2, 1).reshape(-1), strict=True))
    return dense.from_bundle(
        res.exterior, res.points, np.zeros(0),
        np.asarray([gd[n] for n in dense.gnames]), dense.gnames,
    )  # fmt: skip


def test_joint_with_parameters_equals_the_alternation(case):
    """The joint adjustment with self-calibration reaches the alternation's fixed point."""
    sim, block, auxs = case
    aux, aps, grp = auxs["stat+apr"], ap_set("ebner12"), block.images.strip
    kw = dict(additional=aps, ap_group=grp, ap_sigma=AP_SIGMA)
    joint = ov.bundle_adjust(block, control="weighted", auxiliary=aux, **kw)
    alt = adjust_with_auxiliary(block, aux, tol=0.005, **kw)
    assert joint.converged and alt.converged and alt.rounds > 1
    for kind in ("statoscope", "apr"):
        np.testing.assert_allclose(joint.auxiliary.offsets[kind], alt.offsets[kind], atol=0.03)
    d = joint.points - alt.adjustment.points
    assert np.nanmax(np.abs(d)) < 0.05
    a = joint.groups["additional"]
    da = joint.x[a] - alt.adjustment.x[a]
    sa = joint.sigma0 * np.sqrt(np.diag(joint.cofactor_groups["additional"]))
    assert np.abs(da / sa).max() < 0.05  # the parameters agree to a few per cent of their σ
