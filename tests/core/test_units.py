import math

import numpy as np
import pytest

import orientviz as ov
from orientviz.units import RHO_C, RHO_CC, convert_angle, format_angle, wrap_angle


def test_rho_values_of_the_papers():
    assert round(RHO_C, 1) == 6366.2  # Kovarik: rho^c = 6366.2 c
    assert round(RHO_CC) == 636620


def test_conversions():
    assert ov.to_rad(200.0, "gon") == pytest.approx(math.pi)
    assert convert_angle(1.0, "gon", "cc") == pytest.approx(10_000.0)
    assert convert_angle(1.0, "gon", "c") == pytest.approx(100.0)
    assert convert_angle(90.0, "deg", "gon") == pytest.approx(100.0)
    np.testing.assert_allclose(ov.from_rad(ov.to_rad(np.array([1.0, 2.0]), "c"), "c"), [1.0, 2.0])


def test_wrap_and_format():
    assert wrap_angle(3 * math.pi) == pytest.approx(-math.pi)
    assert format_angle(ov.to_rad(12.5, "gon"), "gon") == "12.5000 gon"


def test_unknown_unit():
    with pytest.raises(ValueError, match="expected an angle unit"):
        ov.to_rad(1.0, "grad")
