"""Lesson 10 (sparse normal equations): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson10 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson10


def test_lesson10_checks():
    assert_module_checks(lesson10, answers)


def test_lesson10_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson10,
        answers,
        {
            ("check_schur_step", "plus"): "sign is wrong",
            ("check_ray_partials", "R_not_transposed"): "instead of Rᵀ",
            ("check_ray_partials", "no_quotient"): "quotient rule",
            ("check_ray_partials", "X0_sign"): "X0 enters as X − X0",
            ("check_ray_partials", "own central differences"): "finite difference",
            ("check_my_bundle", "fixed_as_unknowns"): "held fixed (control) are no unknowns",
            ("check_my_bundle", "no_sqrt"): "square root is missing",
            ("check_point_covariance", "V_only"): "uncertainty of the orientations",
            ("check_coupled", "diagonal only where an unknown point is seen"): "only fixed points",
            ("check_point_covariance", "the whole N inverted"): "the whole N inverted",
            ("check_schur_step", "the whole system solved densely"): "never the whole V",
            ("check_schur_step", "the whole V inverted"): "never the whole V",
            ("check_schur_step", "no_coupling"): "coupling",
            ("check_schur_step", "W_transposed"): "is a matrix transposed",
            ("check_coupled", "no diagonal"): "diagonal blocks",
            ("check_coupled", "fixed"): "fixed point",
            ("check_coupled", "one triangle"): "symmetric",
            ("check_fill_pattern", "no fill"): "no fill-in",
            ("check_fill_pattern", "envelope"): "upper bound",
            ("check_point_covariance", "minus"): "ADDS to the point's",
            ("check_predicted_bandwidth", "same_direction"): "back and forth",
            ("check_predicted_bandwidth", "across_2s"): "2s + 1",
            ("check_predicted_bandwidth", "swapped"): "swapped",
        },
    )


def test_fill_in_start_is_found_and_the_bandwidth_misreading_named(capsys):
    import pytest

    from orientviz.exercises._common import CheckFailed, NotWrittenError

    # an independent look at the lesson's numbers: 4 strips, 3..25 images per strip
    fills = {}
    for n in range(3, 12):
        along, across, S, best = lesson10._block_patterns(4, n)
        fills[n] = (along, across, int(lesson10.cholesky_fill(S, None).sum()),
                    int(lesson10.cholesky_fill(S, best).sum()))  # fmt: skip
    first = min(n for n, f in fills.items() if f[3] < f[2])
    band = min(n for n, f in fills.items() if f[1] < f[0])
    assert band < first  # the lesson's point: a narrower band before any saving of fill-in
    lesson10.check_fill_in_start(lambda: first)
    assert capsys.readouterr().out.startswith("✓")
    with pytest.raises(CheckFailed, match="BANDWIDTH"):
        lesson10.check_fill_in_start(lambda: band)
    with pytest.raises(CheckFailed, match="same number of blocks"):
        lesson10.check_fill_in_start(first - 1)
    with pytest.raises(NotWrittenError):
        lesson10.check_fill_in_start(None)


def test_lesson10_checks_refuse_the_library_and_name_the_lost_control_weight():
    assert_diagnoses(
        lesson10,
        answers,
        {
            ("check_my_bundle", "library"): "calls the library's linearise",
            ("check_my_bundle", "no_control"): "add P_control to V",
            ("check_my_bundle", "control_not_counted"): "observations too",
        },
    )


def test_schur_step_check_refuses_the_dense_solution():
    import numpy as np

    from orientviz.exercises._common import rejection

    def dense_step(nb):  # the lesson's stand-in
        x = np.linalg.solve(*nb.dense())
        return x[: 6 * nb.n_images], x[6 * nb.n_images :]

    exc = rejection(lesson10.check_schur_step, dense_step)
    assert exc is not None and "nb.dense" in str(exc)


def test_first_state_below_reads_the_iteration_and_names_the_neighbours(capsys):
    import numpy as np
    import pytest

    import orientviz as ov
    from orientviz.bundle.reference import reference_data
    from orientviz.exercises._common import CheckFailed, NotWrittenError

    sim = ov.simulate_block(2, 4, rng=3, extra=None)
    data = reference_data(sim.block, "fixed")
    adj = ov.bundle_adjust(sim.block, control="fixed")
    eo = adj.x[adj.groups["exterior"]].reshape(-1, 6)
    xyz = adj.x[adj.groups["points"]].reshape(-1, 3)  # all points of the block
    start = (eo[:, :3], eo[:, 3:], xyz)  # the adjusted state: residuals at the noise level
    moved = (start[0] + 5.0, start[1] + 0.01, start[2])  # metres and 0.6 gon off: far above 10 µm
    states = [moved, moved, start, start]
    # an independent look: the library's projection of every ray
    c, x0, y0 = data.cam
    e = []
    for i in range(sim.block.n_images):
        m = data.image == i
        R = ov.matrix_from_opk(*start[1][i])
        e.append(
            ov.project(start[2][data.point[m]], start[0][i], R, c[m][0], x0[m][0], y0[m][0])
            - data.l[m]
        )
    assert np.sqrt(np.mean(np.concatenate(e) ** 2)) * 1000 < 10.0
    lesson10.check_first_state_below(lambda: 2, data, states)
    assert capsys.readouterr().out.startswith("✓")
    with pytest.raises(CheckFailed, match="not yet below"):
        lesson10.check_first_state_below(1, data, states)
    with pytest.raises(CheckFailed, match="already is"):
        lesson10.check_first_state_below(3, data, states)
    with pytest.raises(NotWrittenError):
        lesson10.check_first_state_below(None, data, states)


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls the library's simulate_block", "measured_bandwidths"]:
        assert_diagnoses(
            lesson10, answers, {("check_predicted_bandwidth", "the stand-in (measured)"): text}
        )
