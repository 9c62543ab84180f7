"""The observation labels of a block solution: formed on access, the same labels as a list."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.datasets import load_dataset
from orientviz.io.kinds._labels import ObservationLabels


@pytest.fixture(scope="module")
def solved():
    problem = load_dataset("dbat_sxb")
    return problem, ov.solve_problem(problem)


def test_image_labels_are_image_point_coordinate(solved):
    problem, sol = solved
    block, labels = problem.data, sol.adjustment.obs_labels
    obs = block.observations
    want = [
        f"{block.images.ids[i]}/{block.points.ids[p]}/{a}"
        for i, p in zip(obs.image, obs.point)
        for a in "xy"
    ]
    n_img = 2 * obs.image.size
    assert labels[:n_img] == want
    assert [labels[j] for j in range(n_img)] == want
    assert list(labels)[:n_img] == want
    assert labels[-1] == list(labels)[-1]
    assert len(labels) == sol.adjustment.n_observations
    with pytest.raises(IndexError):
        labels[len(labels)]


def test_pseudo_observations_keep_their_names(solved):
    _, sol = solved
    labels = sol.adjustment.obs_labels
    sl = sol.adjustment.obs_slices["control"]
    assert labels[sl] and all(lab.endswith(("/X", "/Y", "/Z")) for lab in labels[sl])
    assert labels == list(labels) and labels != list(labels)[:-1]


def test_unlabelled_places_are_numbered():
    labels = ObservationLabels(["a"], ["p", "q"], np.array([0, 0]), np.array([0, 1]),
                               [None, None, None, None, "", "c/X"])  # fmt: skip
    assert list(labels) == ["a/p/x", "a/p/y", "a/q/x", "a/q/y", "observation no. 5", "c/X"]
    assert labels[-2:] == ["observation no. 5", "c/X"]
    assert "a/q/y" in labels and "a/q/z" not in labels
