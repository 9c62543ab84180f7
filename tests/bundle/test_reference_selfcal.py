"""Self-calibration and the camera model against the textbook reference.

The reference carries the additional parameters as further global unknowns of the
dense reduced system (N11 = [[U, E], [Eᵀ, F]]); the fast bundle borders its reduced
system with them and solves the border by conjugate gradients (an Fs formed once as
the preconditioner), reusing E, F while the geometry stands still. A
:class:`~orientviz.bundle.LensModel` is the projection itself in both: the reference
maps its normalised collinearity point through the package's one camera model.
Relative measures as in test_reference.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_reference import assert_same_optimum, one_blas_thread, textbook_cofactors  # noqa: F401

import orientviz as ov
from orientviz.bundle import BundleOptions, LensModel, ap_set
from orientviz.bundle.reference import reference_bundle, reference_data
from orientviz.simulate import simulate_calibration

TOL = 1e-8
RTOL_PREC = 1e-8  # the cofactors agree to ~1e-9 (measured); solves round differently

EBNER = ap_set("ebner12")
TRUE = np.array([6.0, -4.0, 3.0, 0.0, 5.0, -2.0, 0.0, 4.0, 0.0, -3.0, 2.0, 0.0])  # µm


@pytest.fixture(scope="module")
def distorted():
    """3 × 6 images whose observations carry an Ebner-12 image deformation."""

    def systematic(xy, img):
        return np.einsum("nij,j->ni", EBNER.design(xy), TRUE)

    return ov.simulate_block(3, 6, rng=9, extra=None, systematic=systematic).block


CASES = {
    "ebner12, one group, weighted": dict(additional="ebner12", ap_sigma=100.0),
    "ebner12 per strip, free": dict(additional="ebner12", ap_group="strip"),
    "brown, weighted": dict(additional="brown", ap_sigma=50.0),
}
_REFERENCE: dict[str, object] = {}


def _case(name: str, block) -> dict:
    kw = dict(CASES[name])
    if kw.get("ap_group") == "strip":
        kw["ap_group"] = block.images.strip
    return kw


def _reference(name: str, block):
    """The reference of a case, computed once (exact Newton steps: at tol 1e-8 it is
    within 1e-12 of its own optimum at 1e-10)."""
    if name not in _REFERENCE:
        _REFERENCE[name] = reference_bundle(block, tol=TOL, max_iter=60, **_case(name, block))
    return _REFERENCE[name]


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("solver", ["dense", "banded", "sparse"])
def test_additional_parameters_reach_the_reference_optimum(case, solver, distorted):
    ref = _reference(case, distorted)
    # the fast bundle reuses E, F of the border while the geometry stands still: those
    # steps are inexact and may not stop the run (see the next test); at tol 1e-10 the
    # stop is within the 1e-10 the optimum is compared to
    res = ov.bundle_adjust(distorted, solver=solver, tol=1e-10, max_iter=80, precision=False,
                           **_case(case, distorted))  # fmt: skip
    assert res.solver == solver
    log = res.reduced_info["ap_border"]
    assert any("cg" in entry for entry in log), log  # the border's iterative solve ran
    assert any("reused" in entry for entry in log), log  # and E, F were reused
    assert_same_optimum(res, ref, distorted)
    assert np.max(np.abs(ref.ap)) > 3.0  # µm: the parameters carry the deformation


def test_a_tight_tolerance_brings_the_self_calibrating_bundle_to_the_optimum(distorted):
    # E, F reused (options.ap_reuse) after steps that moved little: a reused step below
    # tol may not stop the run (it reads the distance to the optimum of the free per-strip
    # parameters badly: 8e-8 relative when it did), the run ends on a step of a fresh border
    case = "ebner12 per strip, free"
    ref = _reference(case, distorted)
    res = ov.bundle_adjust(distorted, solver="dense", tol=TOL, max_iter=60, precision=False,
                           **_case(case, distorted))  # fmt: skip
    assert_same_optimum(res, ref, distorted)


def test_without_the_reuse_of_the_border_a_tight_tolerance_reaches_the_optimum(distorted):
    # the same run with E, F formed anew at every step: its steps are exact Newton steps
    # of the bordered system, and a step below tol now means the optimum is met
    case = "ebner12 per strip, free"
    ref = _reference(case, distorted)
    opts = BundleOptions(solver="dense", tol=TOL, max_iter=60, ap_reuse=0.0)
    res = ov.bundle_adjust(distorted, options=opts, precision=False, **_case(case, distorted))
    assert not any("reused" in entry for entry in res.reduced_info["ap_border"])
    assert_same_optimum(res, ref, distorted)


@pytest.mark.parametrize("kind", ["backward", "forward"])
@pytest.mark.parametrize(
    "model",
    [
        {},  # c, x0, y0, as, K1–K3, P1, P2 free
        {"free": ()},  # a known camera applied: nothing estimated
        {"free": ("K1",), "prior": {"c": 1e-3}},  # one free, one weighted (k1 forward)
    ],
    ids=["free", "fixed", "prior"],
)
def test_the_camera_model_reaches_the_reference_optimum(kind, model):
    if kind == "forward" and "free" in model and model["free"]:
        model = dict(model, free=("k1",))
    sim = simulate_calibration(np.random.default_rng(1), kind=kind, sigma_mm=3e-4)
    ref = reference_bundle(sim.block, additional=LensModel(kind, **model), tol=TOL, max_iter=50)
    res = ov.bundle_adjust(sim.block, additional=LensModel(kind, **model), tol=TOL, max_iter=50)
    assert_same_optimum(res, ref, sim.block)
    ref_result = ov.bundle_adjust(
        sim.block, additional=LensModel(kind, **model), tol=TOL, max_iter=50, solver="reference"
    )
    # the camera in physical units and its σ from the same precision code
    np.testing.assert_allclose(ref_result.camera.value, res.camera.value, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(ref_result.camera.sigma, res.camera.sigma, rtol=1e-7)


def test_the_precision_with_additional_parameters_is_the_reference_inverse(distorted):
    # Q11 = S⁻¹ over (exterior, additional parameters) and the point cofactors
    # N22⁻¹ + Tᵀ Q11 T at the optimum, against the fast precision of a bordered system
    case = "ebner12, one group, weighted"
    ref = _reference(case, distorted)
    kw = _case(case, distorted)
    data = reference_data(distorted, "fixed", kw["additional"], None, kw["ap_sigma"])
    Q11, Q22 = textbook_cofactors(data, ref, distorted.sequence)
    fast = ov.bundle_adjust(distorted, solver="banded", tol=1e-10, max_iter=80, **kw)
    s0 = np.sqrt(ref.cost[-1] / fast.redundancy)
    std = fast.std()
    m = distorted.n_images
    np.testing.assert_allclose(
        std[fast.groups["exterior"]], s0 * np.sqrt(np.diag(Q11)[: 6 * m]), rtol=1e-7
    )
    np.testing.assert_allclose(
        std[fast.groups["additional"]], s0 * np.sqrt(np.diag(Q11)[6 * m :]), rtol=1e-7
    )
    got = std[fast.groups["points"]].reshape(-1, 3)[data.unknown]
    np.testing.assert_allclose(got, s0 * np.sqrt(np.einsum("pii->pi", Q22)), rtol=RTOL_PREC)
