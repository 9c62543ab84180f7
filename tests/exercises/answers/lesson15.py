"""Lesson 15: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson15.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from orientviz.exercises.lesson15 import expected_rms_library, residual_pattern_library


def _pattern(xy, v):
    A = np.zeros((2 * len(xy), 4))
    A[0::2, 0], A[1::2, 1] = 1.0, 1.0
    A[0::2, 2], A[1::2, 2] = xy[:, 0], xy[:, 1]
    A[0::2, 3], A[1::2, 3] = -xy[:, 1], xy[:, 0]
    p = np.linalg.lstsq(A, v.ravel(), rcond=None)[0]
    return p[:2], p[2], p[3]


_RIGHT = {
    "v not flipped": "no pattern",
    "principal point at the image centre": "shift",
    "pixel size 0.012 mm instead of 0.010 mm": "none",
}


def _with(**change):
    return lambda: {**_RIGHT, **change}


def _smallest_redundancy(ratio, alpha, tail=2, square=False, offset=0):
    r = 1
    while True:  # a plain search upwards
        bound = chi2.ppf(1 - alpha / tail, r) / r
        if (bound if square else np.sqrt(bound)) < ratio:
            return r + offset
        r += 1


def _expected_rms(image, sigma, r, m, mistake=None):
    var = sigma**2 * (r**2 if mistake == "r squared" else r)
    if mistake == "no r":
        var = sigma**2
    out = np.array([np.sqrt(np.mean(var[image == i], axis=0)) for i in range(m)])
    return out**2 if mistake == "no sqrt" else out


SOLUTIONS = {
    "check_residual_pattern": _pattern,
    "check_import_mistakes": lambda: dict(_RIGHT),
    "check_smallest_redundancy": _smallest_redundancy,
    "check_expected_rms": _expected_rms,
}

MUTANTS = {
    "check_residual_pattern": {
        "the stand-in": residual_pattern_library,
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
    "check_import_mistakes": {
        "mirror as a rotation": _with(**{"v not flipped": "rotation"}),
        "mirror as a scale": _with(**{"v not flipped": "scale"}),
        "principal point as none": _with(**{"principal point at the image centre": "none"}),
        "pixel size as a scale": _with(**{"pixel size 0.012 mm instead of 0.010 mm": "scale"}),
    },
    "check_smallest_redundancy": {
        "one-sided": lambda q, a: _smallest_redundancy(q, a, tail=1),
        "squared": lambda q, a: _smallest_redundancy(q, a, square=True),
        "off by one": lambda q, a: _smallest_redundancy(q, a, offset=-1),
    },
    "check_expected_rms": {
        **{
            k: (lambda image, sigma, r, m, k=k: _expected_rms(image, sigma, r, m, k))
            for k in ("no r", "no sqrt", "r squared")
        },
        "the stand-in": expected_rms_library,
    },
}
