"""The three-point resection keeps the true solution when the rays are symmetric.

Above the circumcentre of an equilateral triangle all three ray lengths are equal; Grunert's
elimination u = N(v)/D(v) is then 0/0 at a double root, and the true camera used to be
dropped ("no real solution", or only the wrong candidates).
"""

import numpy as np
import pytest

import orientviz as ov
from orientviz.orientation.resection import resection_closed_form

TRIANGLE = np.array([[500 * np.cos(a), 500 * np.sin(a), 0.0] for a in np.radians([90, 210, 330])])


@pytest.mark.parametrize("height", [150.0, 200.0, 600.0, 1000.0, 1500.0])
@pytest.mark.parametrize("offset", [0.0, 1e-3, 100.0])
def test_true_camera_is_a_candidate(height, offset):
    X0 = np.array([offset, 0.0, height])
    xy = ov.project(TRIANGLE, X0, np.eye(3), 152.7)
    cands = resection_closed_form(xy, TRIANGLE, 152.7)
    assert 1 <= len(cands) <= 4
    assert any(
        np.allclose(c.X0, X0, atol=1e-5) and np.allclose(c.R, np.eye(3), atol=1e-8) for c in cands
    )
    positions = np.array([c.X0 for c in cands])
    gaps = np.linalg.norm(positions[:, None] - positions[None], axis=-1) + np.eye(len(cands)) * 1e9
    assert gaps.min() > 1e-3  # no candidate twice
