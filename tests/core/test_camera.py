import numpy as np

import orientviz as ov
from orientviz.camera import collinearity_jacobian, rays


def test_vertical_photo_signs():
    # camera 1000 m above the origin, R = I: a point ahead (+X) images at +x
    xy = ov.project([[100.0, 50.0, 0.0]], [0, 0, 1000.0], np.eye(3), 150.0)
    np.testing.assert_allclose(xy, [[15.0, 7.5]])


def test_jacobian_against_finite_differences():
    rng = np.random.default_rng(3)
    n = 7
    P = rng.uniform(-500, 500, (n, 3)) * [1, 1, 0.1]
    X0 = np.array([10.0, -20.0, 1500.0])
    ang = np.array([0.02, -0.03, 1.2])
    c, x0, y0 = 152.0, 0.01, -0.02
    xy, Je, Jp, Ji = collinearity_jacobian(P, X0, ang, c, x0, y0)
    R = ov.matrix_from_opk(*ang)
    np.testing.assert_allclose(xy, ov.project(P, X0, R, c, x0, y0))

    def f_ext(e):
        return ov.project(P, e[:3], ov.matrix_from_opk(*e[3:]), c, x0, y0)

    e0 = np.r_[X0, ang]
    for k in range(6):
        h = 1e-3 if k < 3 else 1e-7
        d = np.zeros(6)
        d[k] = h
        np.testing.assert_allclose(
            Je[:, :, k], (f_ext(e0 + d) - f_ext(e0 - d)) / (2 * h), rtol=1e-6, atol=1e-9
        )
    for k in range(3):
        d = np.zeros(3)
        d[k] = 1e-3
        fd = (ov.project(P + d, X0, R, c, x0, y0) - ov.project(P - d, X0, R, c, x0, y0)) / 2e-3
        np.testing.assert_allclose(Jp[:, :, k], fd, rtol=1e-6, atol=1e-10)
    io = np.array([x0, y0, c])
    for k in range(3):
        d = np.zeros(3)
        d[k] = 1e-4
        a, b = io + d, io - d
        fd = (
            ov.project(P, X0, R, a[2], a[0], a[1]) - ov.project(P, X0, R, b[2], b[0], b[1])
        ) / 2e-4
        np.testing.assert_allclose(Ji[:, :, k], fd, rtol=1e-6, atol=1e-10)


def test_rays_point_back_to_object():
    R = ov.matrix_from_opk(0.05, -0.02, 0.7)
    X0 = np.array([1.0, 2.0, 1200.0])
    P = np.array([[30.0, -40.0, 5.0]])
    xy = ov.project(P, X0, R, 100.0)
    d = rays(xy, R, 100.0)[0]
    v = P[0] - X0
    np.testing.assert_allclose(d / np.linalg.norm(d), v / np.linalg.norm(v), atol=1e-12)


def test_camera_validation():
    import pytest

    with pytest.raises(ValueError, match="c > 0"):
        ov.FrameCamera(c=-1.0)
