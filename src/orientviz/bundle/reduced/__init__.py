"""The reduced camera system: form → factor → solve → back-substitute.

The bundle's normal equations in image unknowns c (6 per image: X0, Y0, Z0 in m,
ω, φ, κ in rad) and point unknowns p (3 per point, m) ::

    [ U   W ] [dc]   [bc]        U: 6×6 blocks (images), V: 3×3 blocks (points),
    [ Wᵀ  V ] [dp] = [bp]        W = J_cᵀ P J_p per ray (6×3)

are never formed as a whole. The point blocks are inverted and eliminated (the Schur
complement), which leaves the reduced camera system ::

    S dc = bc − W V⁻¹ bp,     S = U − W V⁻¹ Wᵀ,

a sparse matrix of 6×6 blocks: block (i, k) is non-zero only if images i and k see a
common point. After solving, the points follow by back-substitution
dp = V⁻¹ (bp − Wᵀ dc). Additional parameters and auxiliary offsets border S; their
elimination is the problem's (:mod:`orientviz.bundle.problem`).

The door of this room, stage by stage:

* structure (once per problem): :class:`ReducedStructure` — the pattern of S, the rays
  grouped by track length, and the solver chosen from the structure (:data:`SOLVERS`,
  ``"auto"``: banded for strips, dense for small or densely connected networks,
  sparse — nested dissection and a multifrontal Cholesky — otherwise), with the
  band-minimising image order (:func:`geometric_orderings`);
* form (per iteration): :func:`point_products` (V, W, bp per point),
  :func:`inv3` (V⁻¹; :func:`inv3_held` in the iterations: a numerically singular
  point block is held for the step), :func:`ray_couplings` (T = W V⁻¹), :class:`ImageGram` (U and
  the reduced right-hand side), :func:`schur_blocks` or :func:`dense_schur` (S), all
  held by :class:`NormalEquations`;
* factor: :func:`factor_reduced` → :class:`Factor` (a singular S raises
  :class:`~orientviz.errors.NotDeterminableError` naming the parameters);
* solve: :meth:`Factor.solve`;
* back-substitute: :func:`back_substitute`.

Nothing here knows photogrammetry: the blocks come in, corrections go out.
"""

from ._choice import SOLVERS, SolverChoice
from ._factor import Factor, dense_matrix, factor_reduced, raise_not_determinable
from ._normal import APBorder, AuxBorder, NormalEquations
from ._options import ReducedOptions
from ._orderings import geometric_orderings
from ._schur import (
    DENSE_CHUNK_BYTES,
    SINGULAR_REL_EIG,
    HeldDepths,
    ImageGram,
    ImageRays,
    dense_schur,
    inv3,
    inv3_held,
)
from ._structure import ReducedStructure
from ._tracks import (
    TrackGroups,
    back_substitute,
    point_products,
    point_sums_wt,
    ray_couplings,
    schur_blocks,
    schur_buffer_size,
)

__all__ = [
    "SOLVERS",
    "ReducedOptions",
    "SolverChoice",
    "ReducedStructure",
    "TrackGroups",
    "geometric_orderings",
    "point_products",
    "inv3",
    "inv3_held",
    "SINGULAR_REL_EIG",
    "HeldDepths",
    "ray_couplings",
    "ImageGram",
    "ImageRays",
    "schur_blocks",
    "schur_buffer_size",
    "dense_schur",
    "NormalEquations",
    "APBorder",
    "AuxBorder",
    "factor_reduced",
    "Factor",
    "dense_matrix",
    "raise_not_determinable",
    "DENSE_CHUNK_BYTES",
    "back_substitute",
    "point_sums_wt",
]
