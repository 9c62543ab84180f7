"""Lesson 15: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson15.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2, norm


def _pattern(xy, v):
    A = np.zeros((2 * len(xy), 4))
    A[0::2, 0], A[1::2, 1] = 1.0, 1.0
    A[0::2, 2], A[1::2, 2] = xy[:, 0], xy[:, 1]
    A[0::2, 3], A[1::2, 3] = -xy[:, 1], xy[:, 0]
    p = np.linalg.lstsq(A, v.ravel(), rcond=None)[0]
    return p[:2], p[2], p[3]


def _colmap_to_photo(uv, cx, cy, p):
    return np.column_stack([(uv[:, 0] - cx) * p, -(uv[:, 1] - cy) * p])


def _sigma0_interval(vPv, r, alpha):
    return (
        np.sqrt(vPv / r),
        np.sqrt(chi2.ppf(alpha / 2, r) / r),
        np.sqrt(chi2.ppf(1 - alpha / 2, r) / r),
    )


def _rms_per_image(image, v, m):
    return np.array([np.sqrt(np.mean(v[image == i] ** 2, axis=0)) for i in range(m)])


SOLUTIONS = {
    "check_residual_pattern": _pattern,
    "check_colmap_to_photo": _colmap_to_photo,
    "check_sigma0_interval": _sigma0_interval,
    "check_rms_per_image": _rms_per_image,
}

MUTANTS = {
    "check_residual_pattern": {
        "rotation sign": lambda xy, v: (lambda t, s, r: (t, s, -r))(*_pattern(xy, v)),
        "swapped": lambda xy, v: (lambda t, s, r: (t, r, s))(*_pattern(xy, v)),
        "x only": lambda xy, v: (
            np.linalg.lstsq(
                np.column_stack([np.ones(len(xy)), xy[:, 0], -xy[:, 1]]), v[:, 0], rcond=None
            )[0][0]
            * np.ones(2),
            *np.linalg.lstsq(
                np.column_stack([np.ones(len(xy)), xy[:, 0], -xy[:, 1]]), v[:, 0], rcond=None
            )[0][1:],
        ),
    },
    "check_colmap_to_photo": {
        "no flip": lambda uv, cx, cy, p: _colmap_to_photo(uv, cx, cy, p) * [1, -1],
        "swapped": lambda uv, cx, cy, p: _colmap_to_photo(uv, cy, cx, p),
        "divided": lambda uv, cx, cy, p: _colmap_to_photo(uv, cx, cy, 1 / p),
    },
    "check_sigma0_interval": {
        "one-sided": lambda q, r, a: _sigma0_interval(q, r, 2 * a),
        "squared": lambda q, r, a: (lambda s, lo, hi: (s, lo**2, hi**2))(
            *_sigma0_interval(q, r, a)
        ),
        "normal": lambda q, r, a: (
            np.sqrt(q / r),
            1 - norm.ppf(1 - a / 2) / np.sqrt(2 * r),
            1 + norm.ppf(1 - a / 2) / np.sqrt(2 * r),
        ),
        "dof n": lambda q, r, a: _sigma0_interval(q, r + 40, a),
    },
    "check_rms_per_image": {
        "mean": lambda image, v, m: np.array([np.mean(v[image == i], axis=0) for i in range(m)]),
        "std": lambda image, v, m: np.array([np.std(v[image == i], axis=0) for i in range(m)]),
        "global": lambda image, v, m: np.tile(np.sqrt(np.mean(v**2, axis=0)), (m, 1)),
    },
}
