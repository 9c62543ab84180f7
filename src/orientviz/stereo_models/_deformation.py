"""Model deformation parameters: self-calibration for block adjustment by independent models.

Systematic image errors do not vanish in model formation: relative orientation absorbs
part of them, the rest deforms every stereo model in a regular way (Ackermann 1974, the
systematic-error sections; :func:`orientviz.simulate.systematic.model_field` shows the
fields). The independent-model adjustment can estimate these deformations as additional
parameters. The observed model coordinates m of a point are taken to carry the
deformation ``A(m)·p``, which is removed *before* the similarity transformation ::

    X + v = λ R (m − A(m) · p) + T

with ``A(m)`` (3 × q per point) a fixed field per parameter. The fields are written in
normalised model coordinates of each model: u along the base, v across it, w height,
each divided by the half extent of the model's ground points (so u, v ∈ [−1, 1] at the
model corners). The classical terms:

============== ===================== ==============================================
term           field (dx, dy, dz)    typical cause
============== ===================== ==============================================
affinity       (u, −v, 0)            different image scales in x and y (film, affinity)
shear          (v, u, 0)             non-orthogonal image axes
trapezoid_x    (u·v, 0, 0)           scale along the base changing across it
trapezoid_y    (0, u·v, 0)           scale across the base changing along it
twist          (0, 0, u·v)           torsion of the model about the base (ω-type errors)
bend_along     (0, 0, u²)            parabolic bending along the base (radial distortion)
bend_across    (0, 0, v²)            parabolic bending across the base (film unflatness)
height_scale   (0, 0, w)             height scale differing from planimetry (c error)
============== ===================== ==============================================

Any part of a field that the 7 similarity parameters can produce (3 shifts, 3 rotations,
scale) is removed per model by a weighted least-squares projection on that model's
ground points: the fields that remain are orthogonal to the similarity in the metric of
the adjustment, so the similarity parameters keep their meaning and no parameter is
absorbed silently. Projection centres are not deformed (they define the model frame).

Units: **one unit of a parameter is 1 mm** of model deformation (in object scale) at a
model corner (u = v = 1 before the projection); ``sigma`` of the pseudo-observations
p = 0 ± σ is therefore in mm as well.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
MM = 1e-3  # m per mm

#: All terms, in the order of the table in the module docstring.
TERMS: tuple[str, ...] = (
    "affinity",
    "shear",
    "trapezoid_x",
    "trapezoid_y",
    "twist",
    "bend_along",
    "bend_across",
    "height_scale",
)

#: Named sets of terms.
MODEL_SETS: dict[str, tuple[str, ...]] = {
    "planimetric": ("affinity", "shear", "trapezoid_x", "trapezoid_y"),
    "height": ("twist", "bend_along", "bend_across"),
    "classical": TERMS[:7],
    "all": TERMS,
}

#: A projected field whose RMS over a model's points is below this fraction of its
#: nominal size (1 mm per unit) counts as zero on that model.
DEAD_FIELD: float = 1e-2

#: Ways of sharing parameters between models.
GROUPS: tuple[str, ...] = ("model", "strip", "block")


def _field(term: str, u: F64, v: F64, w: F64) -> F64:
    z = np.zeros_like(u)
    return {
        "affinity": (u, -v, z),
        "shear": (v, u, z),
        "trapezoid_x": (u * v, z, z),
        "trapezoid_y": (z, u * v, z),
        "twist": (z, z, u * v),
        "bend_along": (z, z, u * u),
        "bend_across": (z, z, v * v),
        "height_scale": (z, z, w),
    }[term]


@dataclass
class ModelDeformation:
    """A set of model deformation terms (see the module docstring).

    Attributes
    ----------
    name : str
        Set name (or ``"custom"``).
    terms : tuple of str
        Terms of :data:`TERMS`, in order.
    """

    name: str
    terms: tuple[str, ...]

    @property
    def names(self) -> list[str]:
        """Parameter names (the terms)."""
        return list(self.terms)

    @property
    def k(self) -> int:
        """Number of parameters."""
        return len(self.terms)

    def fit(
        self, m: F64, row_model: I64, ground: NDArray[np.bool_], w3: F64, n_models: int
    ) -> DeformationField:
        """The fields of this set for a block of models, orthogonal to the similarity.

        Parameters
        ----------
        m : ndarray, shape (n, 3)
            Model coordinates of the rows (m).
        row_model : ndarray of int, shape (n,)
            Model of each row.
        ground : ndarray of bool, shape (n,)
            Rows of ground points (the projection centres are not deformed and do not
            take part in the normalisation and projection).
        w3 : ndarray, shape (3,)
            Weights of a model coordinate (x, y, z) for the weighted projection.
        n_models : int
            Number of models.
        """
        lo = np.full((n_models, 3), np.inf)
        hi = np.full((n_models, 3), -np.inf)
        g = row_model[ground]
        np.minimum.at(lo, g, m[ground])
        np.maximum.at(hi, g, m[ground])
        has = np.isfinite(lo[:, 0])
        lo[~has], hi[~has] = 0.0, 1.0
        centre = 0.5 * (lo + hi)
        half = np.maximum(0.5 * (hi - lo), 1e-9)
        # heights: normalised by the planimetric half extent (a flat model has w ≈ 0)
        half[:, 2] = np.maximum(half[:, 0], half[:, 1])
        fld = DeformationField(
            self, centre, half, np.zeros((n_models, 7, self.k)), np.ones((n_models, self.k), bool)
        )
        A = fld.raw(m, row_model)
        S = similarity_columns(m)
        sw = np.sqrt(np.asarray(w3, float))[None, :, None]
        order = np.argsort(row_model[ground], kind="stable")
        rows_all = np.flatnonzero(ground)[order]
        starts = np.searchsorted(row_model[rows_all], np.arange(n_models + 1))
        for j in range(n_models):
            rows = rows_all[starts[j] : starts[j + 1]]
            if rows.size == 0:
                continue
            Sj = (S[rows] * sw).reshape(-1, 7)
            Aj = (A[rows] * sw).reshape(-1, self.k)
            fld.coef[j] = np.linalg.lstsq(Sj, Aj, rcond=1e-10)[0]
            left = A[rows] - np.einsum("nip,pk->nik", S[rows], fld.coef[j])
            rms = np.sqrt(np.mean(np.sum(left**2, axis=1), axis=0))
            # a field the similarity (nearly) reproduces on this model's points, e.g. a
            # height scale on flat ground, is no parameter here: zero, not round-off
            fld.dead[j] = rms < DEAD_FIELD * MM
        return fld


@dataclass
class DeformationField:
    """The fields of a :class:`ModelDeformation` fitted to the models of a block.

    Attributes
    ----------
    spec : ModelDeformation
    centre, half : ndarray, shape (n_models, 3)
        Normalisation of the model coordinates (m).
    coef : ndarray, shape (n_models, 7, k)
        Similarity part removed from each field, per model.
    dead : ndarray of bool, shape (n_models, k)
        Fields that vanish on a model after the projection (set to exactly zero there).
    """

    spec: ModelDeformation
    centre: F64
    half: F64
    coef: F64
    dead: NDArray[np.bool_]

    def raw(self, m: F64, row_model: I64) -> F64:
        """Fields before the projection, (n, 3, k) in m per unit (1 mm at a corner)."""
        q = (m - self.centre[row_model]) / self.half[row_model]
        u, v, w = q[:, 0], q[:, 1], q[:, 2]
        A = np.zeros((m.shape[0], 3, self.spec.k))
        for i, term in enumerate(self.spec.terms):
            A[:, :, i] = np.column_stack(_field(term, u, v, w)) * MM
        return A

    def evaluate(self, m: F64, row_model: I64, ground: NDArray[np.bool_] | None = None) -> F64:
        """Fields orthogonal to the similarity at model points, (n, 3, k) in m per unit.

        ``ground`` False marks projection centres (zero field); default all ground.
        """
        A = self.raw(m, row_model) - np.einsum(
            "nip,npk->nik", similarity_columns(m), self.coef[row_model]
        )
        A *= ~self.dead[row_model][:, None, :]
        if ground is not None:
            A[~ground] = 0.0
        return A


def similarity_columns(m: F64) -> F64:
    """Displacements (n, 3, 7) that shifts, small rotations and scale make at points m."""
    n = m.shape[0]
    S = np.zeros((n, 3, 7))
    S[:, :, :3] = np.eye(3)
    x, y, z = m[:, 0], m[:, 1], m[:, 2]
    zero = np.zeros(n)
    S[:, :, 3] = np.column_stack([zero, -z, y])  # rotation about x: e_x × m
    S[:, :, 4] = np.column_stack([z, zero, -x])
    S[:, :, 5] = np.column_stack([-y, x, zero])
    S[:, :, 6] = m
    return S


def model_ap_set(spec: str | Sequence[str] | ModelDeformation) -> ModelDeformation:
    """A model deformation set by name or by a list of terms.

    Parameters
    ----------
    spec : str, sequence of str or ModelDeformation
        A set name of :data:`MODEL_SETS` (``"planimetric"``, ``"height"``,
        ``"classical"``, ``"all"``) or term names of :data:`TERMS`.

    Raises
    ------
    InputError
        For an unknown set or term name (naming the valid ones) or a repeated term.
    """
    if isinstance(spec, ModelDeformation):
        return spec
    if isinstance(spec, str):
        key = spec.lower().replace("-", "_")
        if key in MODEL_SETS:
            return ModelDeformation(key, MODEL_SETS[key])
        if key not in TERMS:
            raise InputError(
                f"unknown model deformation set {spec!r}; expected one of "
                f"{', '.join(MODEL_SETS)} or terms {', '.join(TERMS)}"
            )
        spec = [key]
    terms = [str(t).lower().replace("-", "_") for t in spec]
    bad = [t for t in terms if t not in TERMS]
    if bad:
        raise InputError(
            f"unknown model deformation term(s) {', '.join(map(repr, bad))}; expected "
            f"terms of {', '.join(TERMS)} or a set {', '.join(MODEL_SETS)}"
        )
    if len(set(terms)) != len(terms) or not terms:
        raise InputError(f"model deformation terms: expected distinct terms, got {terms}")
    return ModelDeformation("custom", tuple(terms))


def group_index(group: str | Sequence[int], model_strip: I64) -> I64:
    """Group of each model: ``"model"`` (own parameters), ``"strip"``, ``"block"``, or
    an explicit integer per model.

    Raises
    ------
    InputError
        For an unknown grouping or a wrong length.
    """
    n = model_strip.size
    if isinstance(group, str):
        if group == "model":
            return np.arange(n, dtype=np.int64)
        if group == "strip":
            return np.unique(model_strip, return_inverse=True)[1].astype(np.int64)
        if group == "block":
            return np.zeros(n, np.int64)
        raise InputError(f"deformation_group: expected one of {', '.join(GROUPS)}, got {group!r}")
    g = np.asarray(group, np.int64)
    if g.shape != (n,) or (n and g.min() < 0):
        raise InputError(f"deformation_group: expected {n} non-negative group indices")
    return np.unique(g, return_inverse=True)[1].astype(np.int64)


def deformation_table(adj) -> str:
    """Plain-text table of the estimated deformation parameters of an adjustment by
    :func:`orientviz.stereo_models.independent_models` (value and σ in mm at a model
    corner, t, significant), followed by the analysis' warnings."""
    an = adj.deformation.analysis
    w = max([len(n) for n in an.names] + [9])
    lines = [f"{'parameter':<{w}} {'value mm':>9} {'σ mm':>7} {'t':>6}  significant"]
    for n, v, s, t, g in zip(an.names, an.value, an.sigma, an.t, an.significant):
        lines.append(f"{n:<{w}} {v:9.1f} {s:7.1f} {t:6.1f}  {'yes' if g else 'no'}")
    return "\n".join(lines + list(an.warnings))
