"""Lesson 12's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson12 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson12


def test_checks():
    assert_module_checks(lesson12, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson12,
        answers,
        {
            ("check_snoop", "all at once"): "one at a time",
            ("check_snoop", "no abs"): "not w",
            ("check_snoop", "one round"): "go on until",
            ("check_new_position", "in the cluster"): "stays alone",
            ("check_new_position", "half way"): "closer to the far point",
            ("check_new_position", "far beyond"): "the NEW observation is the lonely one",
            ("check_flag_probability", "one tail"): "one tail only",
            ("check_flag_probability", "no sqrt r"): "√r is missing",
            ("check_flag_probability", "no sigma_true"): "σ_true is left out",
            ("check_flag_probability", "mean by sigma_true"): "its mean is √r ∇/σ",
            ("check_flag_probability", "variance"): "variance",
            ("check_flag_probability", "not flagging"): "NOT flagging",
            ("check_bias_to_noise", "the MDB"): "the MDB in units of the observation's σ",
            ("check_bias_to_noise", "sqrt(1 - r)"): "not δ0 σ",
            ("check_bias_to_noise", "no root"): "needs its square root",
            ("check_bias_to_noise", "inverted"): "inverted",
        },
    )


def test_bias_to_noise_check_refuses_the_library():
    from orientviz.adjust.gross import reliability
    from orientviz.exercises._common import rejection

    def via_library(r, delta0):  # the library's δ̄0 through a stand-in adjustment
        from types import SimpleNamespace

        import numpy as np

        adj = SimpleNamespace(redundancy_numbers=r, sigma_obs=np.ones_like(r), cofactor=None)
        return reliability(adj).external

    exc = rejection(lesson12.check_bias_to_noise, via_library)
    assert exc is not None and "calls the library's reliability" in str(exc)
