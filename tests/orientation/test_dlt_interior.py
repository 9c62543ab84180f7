"""DLT and fiducial (interior-orientation) transformations against simulated truth."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.camera import project
from orientviz.errors import InputError, NotDeterminableError
from orientviz.orientation.dlt import dlt, dlt_design, dlt_project, dlt_to_orientation
from orientviz.orientation.interior import (
    affine_parameters,
    apply_interior,
    fiducial_transformation,
)
from orientviz.rotation import matrix_from_opk


def _field(rng, n=12):
    X = rng.uniform([-3, -2, 0], [3, 2, 2.5], (n, 3))
    X0 = np.array([0.5, -7.0, 1.6])
    ang = np.array([1.45, 0.12, -0.2])
    return X, X0, ang


def test_dlt_recovers_the_camera_from_error_free_points():
    X, X0, ang = _field(np.random.default_rng(3))
    xy = project(X, X0, matrix_from_opk(*ang), 24.0, 0.12, -0.08)
    r = dlt(xy, X)
    assert r.rms < 1e-10 and r.redundancy == 2 * 12 - 11
    o = dlt_to_orientation(r.L)
    np.testing.assert_allclose(o.X0, X0, atol=1e-9)
    np.testing.assert_allclose(o.angles, ang, atol=1e-11)
    np.testing.assert_allclose([o.c, o.x0, o.y0], [24.0, 0.12, -0.08], atol=1e-9)
    assert abs(o.scale_y) < 1e-12 and abs(o.shear) < 1e-12
    A, b = dlt_design(xy, X)
    np.testing.assert_allclose(A @ r.L, b, atol=1e-9)
    np.testing.assert_allclose(dlt_project(r.L, X), xy, atol=1e-10)


def test_dlt_finds_affine_image_terms():
    X, X0, ang = _field(np.random.default_rng(4))
    xy = project(X, X0, matrix_from_opk(*ang), 24.0)
    xy[:, 1] *= 1.002  # y scale 0.2 % larger
    xy[:, 0] += 0.001 * xy[:, 1]  # x sheared by 0.001 y
    o = dlt_to_orientation(dlt(xy, X).L)
    assert o.scale_y == pytest.approx(0.002, abs=1e-12)
    assert o.shear == pytest.approx(0.001, abs=1e-12)
    assert o.c == pytest.approx(24.0, abs=1e-9)


def test_dlt_rejects_a_plane_and_too_few_points():
    rng = np.random.default_rng(5)
    X, X0, ang = _field(rng)
    X[:, 2] = 0.0
    xy = project(X, X0, matrix_from_opk(*ang), 24.0)
    with pytest.raises(NotDeterminableError, match="plane"):
        dlt(xy, X)
    with pytest.raises(InputError, match="at least 6"):
        dlt(xy[:5], X[:5])


def _fiducials():
    return np.array([[-106, -106], [106, -106], [106, 106], [-106, 106],
                     [0, -110], [110, 0], [0, 110], [-110, 0.0]])  # fmt: skip


def test_affine_fiducial_transformation_recovers_scales_rotation_shear():
    cal = _fiducials()
    al, sx, sy, k = 0.01, 1.0005, 1.0010, 0.0003
    Rm = np.array([[np.cos(al), -np.sin(al)], [np.sin(al), np.cos(al)]])
    A = Rm @ np.diag([sx, sy]) @ np.array([[1, k], [0, 1]])
    t = np.array([0.3, -0.2])
    machine = (cal - t) @ np.linalg.inv(A).T
    res = fiducial_transformation(machine, cal)
    g = affine_parameters(res.x)
    np.testing.assert_allclose(
        [g.scale_x, g.scale_y, g.rotation, g.shear], [sx, sy, al, k], atol=1e-12
    )
    np.testing.assert_allclose(apply_interior(res.x, machine), cal, atol=1e-10)
    assert res.redundancy == 16 - 6
    sim = fiducial_transformation(machine, cal, model="similarity")
    # the similarity cannot take up the different scales: residuals of tens of µm remain
    assert np.abs(sim.residuals).max() > 0.02


def test_fiducial_input_errors():
    with pytest.raises(InputError):
        fiducial_transformation(np.zeros((4, 2)), np.zeros((3, 2)))
    with pytest.raises(InputError, match="model"):
        fiducial_transformation(_fiducials(), _fiducials(), model="projective")
