"""Kind ``block``: a photogrammetric block for the bundle (or model/polynomial) adjustment.

Tables: ``cameras``, ``images``, ``points``, ``observations`` (see
:mod:`orientviz.io.kinds._frame` and ``schema/block.json``). Images need approximate
orientations (X0, Y0, Z0, ω, φ, κ); tie points may leave X, Y, Z out, they are then
intersected from the approximate orientations before the adjustment. Every tie and
check point needs at least two rays, every control point at least one.

Options: ``control`` (``"fixed"``/``"weighted"``), ``check_points``
(``"independent"``: check points and their rays stay out of the adjustment, the points
are intersected afterwards; ``"rays"``: their rays are adjusted like tie points and only
their given coordinates are withheld, as DBAT does), ``max_iter``, ``tol``, ``critical``,
``image_sigma``; for ``--method models`` ``model_method`` (``"rigorous"``/``"pat-m"``),
for ``--method polynomial`` ``degree_xy``, ``degree_z``. Methods: ``bundle`` (default), ``models``, ``polynomial``
(:mod:`orientviz.stereo_models`, :mod:`orientviz.polynomial`).
"""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING, Any

import numpy as np

from ...block import CHECK, CONTROL, ROLES, TIE, Block
from ...errors import InputError
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ._cameras import camera_notes, camera_parameters
from ._diverge import divergence_note
from ._frame import block_from_tables, read_frame_tables, require_finite, tables_from_block
from ._labels import ObservationLabels

# The solvers (SciPy, the bundle, approximate values) are imported inside the functions
# that adjust, a solution's types inside those that make one: reading and writing a block
# file (import-bal, import-colmap) never loads them.
if TYPE_CHECKING:  # annotations only
    from ..solution import Solution

METHODS = ("bundle", "models", "polynomial")


def load(doc: dict[str, Any], units: Units, source: str) -> Block:
    """Read a ``block`` document into a :class:`Block` (m, mm, rad)."""
    t = read_frame_tables(doc, source)
    opts = doc.get("options", {})
    block = block_from_tables(
        t, units, source, sequence=doc["sequence"], image_sigma=opts.get("image_sigma"),
        camera_models=True,
    )  # fmt: skip
    im = block.images
    given = np.isfinite(np.column_stack([im.X0, im.angles]))
    if given.any() and not given.all():  # all approximations or none (then computed)
        require_finite(t.images, np.column_stack([im.X0, im.angles]),
                       ("X0", "Y0", "Z0", "omega", "phi", "kappa"),
                       "an approximate value (give all images' or none)")  # fmt: skip
    check_rays(block, t.points)
    block.meta["name"] = doc.get("name", "")
    return block


def check_rays(block: Block, points_table) -> None:
    """Tie and check points need ≥ 2 rays, control points ≥ 1 (InputError at the point)."""
    rays = block.rays_per_point()
    need = np.where(block.points.role == CONTROL, 1, 2)
    bad = np.flatnonzero(rays < need)
    if bad.size:
        i = int(bad[0])
        role = ROLES[block.points.role[i]]
        raise points_table.fail(
            i,
            "id",
            f"{role} point {block.points.ids[i]!r} is observed in {rays[i]} image(s), "
            f"needs at least {need[i]} ray(s)"
            + (f" ({bad.size - 1} more such points)" if bad.size > 1 else ""),
        )


def dump(block: Block, units: Units, columnar: bool) -> dict[str, Any]:
    """The tables of ``block`` in ``units``."""
    return tables_from_block(block, units, columnar)


def approximate(block: Block, frame: str = "control") -> Block:
    """Fill in missing approximate values before an adjustment.

    No image approximations at all: everything is computed from scratch by
    :func:`orientviz.approximate.approximate_values` (relative orientation of a
    seed pair, resections, intersections, a similarity onto the control). Otherwise the
    given orientations are first carried into the control's frame when they are in
    another one (:func:`._align.align_to_control`, a 7-parameter similarity), and tie/check
    points without coordinates are intersected from them. ``frame="model"`` (a free
    network): computed approximations stay in the seed pair's model frame.
    """
    from ._align import align_to_control  # the solver stack: only when adjusting

    if not np.all(np.isfinite(block.images.X0)) or not np.all(np.isfinite(block.images.angles)):
        from ...approximate import approximate_values  # only for a block without approximations

        return approximate_values(block, frame=frame)

    block, alignment = align_to_control(block)
    if alignment.applied:
        block.meta = dict(block.meta, alignment=alignment.note())
    return _approximate_tie_points(block)


def _approximate_tie_points(block: Block) -> Block:
    """Intersect tie/check points without approximate coordinates from the approximate orientations."""
    missing = np.flatnonzero(~np.all(np.isfinite(block.points.xyz), axis=1))
    if missing.size == 0:
        return block

    from ._align import intersect_from_orientations  # the solver stack: only when adjusting

    mask = np.zeros(block.n_points, bool)
    mask[missing] = True
    xyz = intersect_from_orientations(block, mask)
    block = block.copy()
    block.points.xyz[missing] = xyz[missing]
    still = missing[~np.all(np.isfinite(block.points.xyz[missing]), axis=1)]
    if still.size:
        raise InputError(
            f"point {block.points.ids[still[0]]!r}: no approximate coordinates given and its "
            "rays do not intersect (parallel or behind the cameras); give X, Y, Z",
            block.meta.get("source"),
            "points",
        )
    return block


def _call(func, block: Block, options: dict[str, Any], **extra):
    """Call a solver with the options it accepts (max_iter, tol, control, …)."""
    params = inspect.signature(func).parameters
    kw = {k: v for k, v in {**options, **extra}.items() if k in params}
    return func(block, **kw)


#: ``options.check_points``: how check points enter the adjustment.
CHECK_MODES = {
    "independent": "check points independent: their rays are left out of the adjustment, "
    "the points are intersected afterwards from the adjusted orientations",
    "rays": "check points keep their image rays in the adjustment (as DBAT does); only "
    "their given coordinates are withheld",
}


def check_mode(problem: Problem) -> str:
    """The problem's check-point handling, ``"independent"`` (default) or ``"rays"``."""
    return str(problem.options.get("check_points", "independent"))


def with_check_rays(block: Block) -> Block:
    """A copy in which check points are tie points: their rays are adjusted, their given
    coordinates withheld (the caller compares the estimates with them afterwards)."""
    chk = block.points.role == CHECK
    if not chk.any():
        return block
    out = block.copy()
    out.points.role[chk] = TIE
    out.points.xyz_known[chk] = np.nan
    out.points.sigma[chk] = np.nan
    return out


def solve(problem: Problem, method: str | None, **bundle: Any) -> Solution:
    """Adjust the block by ``method`` and collect the report.

    Datum options (:mod:`orientviz.io.datum`): ``free`` (a free network, minimum constraints) and
    ``fix`` (images/points held at their given values); ``robust`` (``"huber"``,
    ``"cauchy"``, ``"soft_l1"``) with ``robust_scale``: the bundle minimises that loss
    (:mod:`._robust`). The
    solution's ``start`` is the block the adjustment started from (approximations
    computed, datum applied). ``bundle``: further keywords of the bundle run
    (:func:`adjust_block`, e.g. ``precision=False``).
    """
    method = method or "bundle"
    loss = str(problem.options.get("robust", "none"))
    if loss != "none" and method != "bundle":
        raise InputError(f"robust = {loss!r} applies to the bundle only, not --method {method}",
                         problem.source, "options.robust")  # fmt: skip
    block, datum_notes = prepare(problem)
    if method == "bundle":
        adj, robust_note = adjust_block(problem, block, **bundle)
        sol = solution_from_block_adjustment(problem, block, adj, method)
        sol.notes[:0] = datum_notes + ([robust_note] if robust_note else []) + far_notes(block, adj)
        sol.start = block
        return sol
    from ...polynomial import polynomial_adjust  # the solver stack: only when adjusting
    from ...stereo_models import independent_models  # the solver stack: only when adjusting

    opts = _options(problem)
    if method == "models":
        opts["method"] = problem.options.get("model_method", "rigorous")
        adj = _call(independent_models, block, opts, precision=True)
        return solution_from_models(problem, block, adj)

    adj = _call(polynomial_adjust, block, opts)
    if "exterior" not in adj.groups:
        return solution_from_points(problem, block, adj, method, polynomial_adjust)
    return solution_from_block_adjustment(problem, block, adj, method)


def far_notes(block: Block, adj) -> list[str]:
    """Notes on points near infinity (their rays meet at < ``FAR_PARALLAX`` rad: kept in
    the adjustment, depth not determined) and on a result without precision."""
    from ...bundle.loop import FAR_PARALLAX, ray_parallax  # the solver stack: only when adjusting

    notes = []
    if adj.exterior is not None and adj.points is not None:
        par = ray_parallax(block, adj.exterior[:, :3], adj.points)
        far = np.flatnonzero((par < FAR_PARALLAX) & (block.points.role == TIE))
        if far.size:
            ids = ", ".join(str(block.points.ids[j]) for j in far[:5])
            notes.append(
                f"{far.size} point(s) near infinity (their rays meet at < {FAR_PARALLAX:g} rad: "
                f"{ids}{' …' if far.size > 5 else ''}): kept in the adjustment, their depth is "
                "not determined (a robust loss lets points seen only by down-weighted rays drift away)"
            )
    if getattr(adj, "precision_error", None):
        notes.append(adj.precision_error)
    return notes


def prepare(problem: Problem) -> tuple[Block, list[str]]:
    """The block the adjustment starts from, and the notes on its datum.

    Approximate values where the file gives none (:func:`approximate`), then the datum
    options ``free`` and ``fix`` (:mod:`orientviz.io.datum`).
    """
    from ..datum import apply_fix, free_network, minimum_datum, parse_fix  # the solver stack

    o = problem.options
    fix = parse_fix(o.get("fix"), problem.source)
    free = bool(o.get("free", False))
    block: Block = problem.data
    datum_notes = []
    if free:
        block, note = free_network(block)
        datum_notes += [note] if note else []
    block = approximate(block, frame="model" if free else "control")
    if free and not fix:
        block, note = minimum_datum(block)
        datum_notes.append(note)
    elif fix:
        block = apply_fix(block, fix)
        datum_notes.append("datum: " + ", ".join(i + (":" + ",".join(p) if p else "") for i, p in fix)
                           + " held at the given values" + (" (free network otherwise)" if free else ""))  # fmt: skip
    return block, datum_notes


def _options(problem: Problem) -> dict[str, Any]:
    keys = ("control", "max_iter", "tol", "degree_xy", "degree_z", "solver", "damping", "ftol")
    return {k: v for k, v in problem.options.items() if k in keys}


def adjust_block(problem: Problem, block: Block, **overrides: Any) -> tuple[Any, str | None]:
    """The bundle adjustment of ``block`` with the file's model and options.

    What ``orientviz solve`` runs on the prepared block (:func:`prepare`): the options
    ``control``, ``max_iter``, ``tol``, ``solver``, the cameras' lens models and
    additional parameters, ``check_points`` and ``robust``. ``overrides`` are further
    keywords of :func:`orientviz.bundle.bundle_adjust` (``max_iter``, ``precision``,
    ``history_x``, …), e.g. for the viewer's steps and re-solves.

    Returns
    -------
    (BundleResult, str or None)
        The adjustment and the note of a robust run (None without ``robust``).
    """
    from ...bundle import BundleOptions, bundle_adjust  # the solver stack: only when adjusting
    from ...bundle.loop import RobustLoss  # the solver stack: only when adjusting
    from ._robust import robust_note  # the solver stack: only when adjusting

    o = problem.options
    try:  # the robust loss, minimised inside the loop (._robust)
        loss = RobustLoss.named(str(o.get("robust", "none")), o.get("robust_scale"))
    except InputError as exc:
        raise InputError(exc.message, problem.source, "options.robust") from None
    opts = _options(problem)
    damping, ftol = opts.pop("damping", None), opts.pop("ftol", None)
    loop = {}
    if damping is not None or ftol is not None:  # the loop's knobs (SfM models)
        loop.update(damping=str(damping or "fallback"), ftol=float(ftol or 0.0))
    if loss is not None:
        loop.update(loss=loss.kind, loss_scale=loss.scale)
    if loop:
        opts["options"] = BundleOptions(**loop)
    opts.update(overrides)
    run_block = with_check_rays(block) if check_mode(problem) == "rays" else block
    adj = _call(bundle_adjust, run_block, opts)
    return adj, (robust_note(run_block, adj, loss) if loss is not None else None)


def _labels(
    block: Block,
    n: int,
    slices: dict | None = None,
    control: str = "weighted",
    more: dict[str, list[str]] | None = None,
) -> ObservationLabels:
    """A label per residual in the user's ids: ``image/point/x``, ``point/X`` (control
    coordinates), ``image/X0_obs``…, ``image/omega_obs``…, names of the additional
    parameters or auxiliary rows given in ``more`` (never an internal index); the image
    observations' labels are formed when read (:class:`._labels.ObservationLabels`)."""
    obs = block.observations
    im = block.images.ids
    slices = slices or {}
    imgs = block.images
    named = {
        "control": _control_labels(block, control),
        "X0_obs": [f"{im[i]}/{n_}_obs" for i in range(len(im)) for c, n_ in enumerate(("X0", "Y0", "Z0"))
                   if imgs.X0_sigma[i, c] > 0],
        "angles_obs": [f"{im[i]}/{n_}_obs" for i in range(len(im))
                       for c, n_ in enumerate(("omega", "phi", "kappa")) if imgs.angles_sigma[i, c] > 0],
        **(more or {}),
    }  # fmt: skip
    n_img = 2 * obs.image.size  # the image observations' labels: formed when read (None here)
    out: list[str | None] = [None] * min(n, n_img) + [""] * max(n - n_img, 0)
    for name, sl in slices.items():
        if name == "image" or not isinstance(sl, slice):
            continue
        k = sl.stop - sl.start
        mine = named.get(name)
        if mine is None or len(mine) != k:
            words = {"control": "control coordinate", "additional": "additional parameter"}
            mine = [f"{words.get(name, name)} no. {j + 1} of {k}" for j in range(k)]
        out[sl] = mine
    return ObservationLabels(im, block.points.ids, obs.image, obs.point, out)


def _control_labels(block: Block, control: str) -> list[str]:
    """``point/X`` for each coordinate pseudo-observation of the bundle, in its order
    (unknown points in block order, then X, Y, Z; see ``bundle.problem._checks.point_setup``)."""
    from ...bundle.problem import point_setup  # the solver stack: only when adjusting

    setup = point_setup(block, control)
    pt = block.points.ids
    unknown = np.flatnonzero(setup.unknown)
    row, col = np.nonzero(np.isfinite(setup.prior_sigma[unknown]))  # point by point, X Y Z
    return [f"{pt[p]}/{'XYZ'[c]}" for p, c in zip(unknown[row].tolist(), col.tolist())]


#: "The model does not fit the data" when σ0 exceeds this and …
MISFIT_SIGMA0: float = 3.0
#: … at least this share of the image coordinates is flagged (abs(w) > critical).
MISFIT_FLAGGED: float = 0.2


def misfit_warning(
    adj, n_image: int, critical: float, block: Block | None = None, pixels: bool = False
) -> str | None:
    """A warning when σ0 ≫ 1 and a large share of the image coordinates is flagged.

    Such a solve "converges" to the best fit of a model that does not hold. If one
    observation explains the misfit (:func:`single_gross_error`), the warning names it
    as a gross error and its remedy; otherwise it names the likely causes of a model
    that does not fit (lens, units, principal distance, σ). ``pixels``: the file's image
    coordinates are pixels (an imported reconstruction): a pixel size cannot be wrong
    there (c is in pixels too), a lens held at import (``--fix-lens``) can.
    """
    if not adj.sigma0 > MISFIT_SIGMA0:
        return None
    w, basis = misfit_residuals(adj, n_image)
    w = w[np.isfinite(w)]
    if w.size == 0:
        return None
    share = float(np.mean(np.abs(w) > critical))
    if share < MISFIT_FLAGGED:
        return None
    head = (
        f"warning: the model does not fit the data: sigma0 = {adj.sigma0:.4g} with "
        f"{share:.0%} of the image coordinates flagged (|w| > {critical:g}{basis})."
    )
    gross = single_gross_error(adj, n_image, block)
    if gross is not None:
        return f"{head} {gross}"
    if pixels:
        return (
            f"{head} Likely causes: lens distortion or other interior-orientation terms "
            "missing from the model or held at wrong values (an import with --fix-lens holds "
            "them), a wrong principal distance, or σ of the image coordinates far too small. "
            "The estimates are the best fit of a model that does not hold"
        )
    return (
        f"{head} Likely causes: "
        "lens distortion or other interior-orientation terms missing from the model, image "
        "coordinates in the wrong unit or with a wrong pixel size, a wrong principal "
        "distance, or σ of the image coordinates far too small. The estimates are the best "
        "fit of a model that does not hold"
    )


def misfit_residuals(adj, n_image: int) -> tuple[np.ndarray, str]:
    """The image coordinates' normalised residuals w for the misfit verdict, and a note.

    Baarda's w_i = v_i / (σ_i √r_i) where the redundancy numbers r_i exist. Without them
    (the precision failed, e.g. nearly singular reduced normal equations) each r_i is
    replaced by the average redundancy number r̄ = r / n, and the note says so; with no
    redundancy at all the array is empty.

    Returns
    -------
    w : ndarray, shape (2 n_image,) or (0,)
        Dimensionless (a-priori σ0 = 1).
    basis : str
        "" for Baarda's w, else a parenthetical remark for the warning.
    """
    if adj.normalized_residuals is not None:
        return np.asarray(adj.normalized_residuals, dtype=float)[: 2 * n_image], ""
    n, r = adj.n_observations, int(adj.redundancy)
    if n == 0 or r <= 0:
        return np.empty(0), ""
    r_mean = r / n
    v = np.asarray(adj.residuals, dtype=float)[: 2 * n_image]
    s = np.asarray(adj.sigma_obs, dtype=float)[: 2 * n_image]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = v / (s * np.sqrt(r_mean))
    return w, f"; w with the average redundancy number r/n = {r_mean:.2f}: no precision"


#: One observation "explains" a misfit when leaving it out brings σ0 to this or below.
GROSS_SIGMA0: float = 2.0


def single_gross_error(adj, n_image: int, block: Block | None = None) -> str | None:
    """Name the one observation whose removal would make the adjustment fit, if any.

    Leaving out observation i lowers vᵀPv = r σ̂0² by w_i² (Baarda: w_i = v_i /
    (σ_i √r_i), a-priori σ0 = 1), so σ̂0 without it is √((r σ̂0² − w_i²) / (r − 1)).
    When that is at most :data:`GROSS_SIGMA0` for the largest ``|w|``, one gross error
    explains the misfit; observations whose ``|w|`` equals the largest (within 1 %) cannot
    be told apart from it and are named too. A largest ``w_i²`` above ``r σ̂0²`` breaks
    that identity of the linearised model (redundancy numbers of nearly singular normal
    equations): then no observation is named.

    Returns
    -------
    str or None
        One sentence (observation, point and image, σ̂0 without it, the remedy), or
        None when no single observation explains the misfit.
    """
    if adj.normalized_residuals is None:
        return None
    w = np.asarray(adj.normalized_residuals, dtype=float)[: 2 * n_image]
    r = int(adj.redundancy)
    if r < 2 or not np.any(np.isfinite(w)):
        return None
    aw = np.where(np.isfinite(w), np.abs(w), 0.0)
    i = int(np.argmax(aw))
    omega = r * float(adj.sigma0) ** 2
    if aw[i] ** 2 > omega * (1.0 + 1e-6):
        # w_i² ≤ vᵀPv holds for the linearised model; beyond rounding its failure means the
        # redundancy numbers are not reliable here (e.g. nearly singular normal equations)
        return None
    rest = max(omega - aw[i] ** 2, 0.0)
    s0 = float(np.sqrt(rest / (r - 1)))
    if s0 > GROSS_SIGMA0:
        return None
    labels = adj.obs_labels or []
    name = lambda k: labels[k] if k < len(labels) else f"observation no. {k + 1}"  # noqa: E731
    alike = [int(k) for k in np.flatnonzero(aw >= 0.99 * aw[i]) if k != i]
    where = ""
    if block is not None and i < 2 * len(block.observations):
        o = i // 2
        pt = block.points.ids[block.observations.point[o]]
        im = block.images.ids[block.observations.image[o]]
        where = f" (point {pt!r}, {'xy'[i % 2]} in image {im!r})"
    same = ""
    if alike:
        shown = ", ".join(name(k) for k in alike[:5]) + (", …" if len(alike) > 5 else "")
        same = (
            f"; {shown} have the same |w|: which of these rays is wrong cannot be told "
            "from this block"
        )
    return (
        f"One gross error explains it: {name(i)}{where} has the largest |w| = {aw[i]:.1f}, "
        f"and without it sigma0 would be {s0:.2f}{same}. Check or remove that measurement, "
        "or solve with --robust cauchy (options.robust), whose influence falls off for "
        "large residuals"
    )


def solution_from_block_adjustment(problem: Problem, block: Block, adj, method: str) -> Solution:
    """Turn a block adjustment (blocks ``exterior`` (m, 6) and ``points`` (p, 3)) into a report."""
    from ...adjust.result import W_CRITICAL  # a solution's types: only when solving
    from ..solution import Solution  # a solution's types: only when solving

    m, p = block.n_images, block.n_points
    if adj.obs_labels is None or len(adj.obs_labels) != adj.n_observations:
        more = {}
        if "additional" in adj.groups:
            more["additional"] = [f"{nm}_obs" for nm in adj.names[adj.groups["additional"]]]
        if getattr(adj, "auxiliary", None) is not None and adj.auxiliary.labels:
            more["auxiliary"] = list(adj.auxiliary.labels)
        control = str(problem.options.get("control", "weighted"))
        adj.obs_labels = _labels(block, adj.n_observations, adj.obs_slices, control, more)
    std = adj.std()
    ext = adj.x[adj.groups["exterior"]].reshape(m, 6)
    sext = std[adj.groups["exterior"]].reshape(m, 6)
    if "points" in adj.groups:
        xyz = adj.x[adj.groups["points"]].reshape(p, 3)
        sxyz = std[adj.groups["points"]].reshape(p, 3)
    else:
        xyz, sxyz = block.points.xyz, np.full((p, 3), np.nan)
    notes = check_note(problem, block, xyz)
    critical = float(problem.options.get("critical", W_CRITICAL))
    px = problem.units.image == "px"
    misfit = misfit_warning(adj, len(block.observations), critical, block, pixels=px)
    if misfit:
        notes.insert(0, misfit)
        adj.reason = f"{adj.reason}; BUT THE MODEL DOES NOT FIT THE DATA (see the warning)"
    if block.meta.get("alignment"):
        notes.insert(0, block.meta["alignment"])
    moved = divergence_note(block, adj, problem.units.m_per_length, problem.units.length_name)
    if moved:
        notes.insert(0, moved)
    if np.any(block.points.role == CHECK):
        mode = check_mode(problem) if method == "bundle" else "independent"
        notes.insert(0, CHECK_MODES[mode] + f" (options.check_points = {mode!r})")
    notes.append(f"block: {block.summary()} (each 2 image coordinates)")
    notes += camera_notes(block, adj, problem.units)
    if getattr(adj, "reduced_info", {}).get("solver_reason"):
        notes.append(f"reduced system solved {adj.reduced_info['solver_reason']}")
    return Solution(
        kind="block",
        method=method,
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        image_ids=list(block.images.ids),
        X0=ext[:, :3],
        angles=ext[:, 3:],
        X0_sigma=sext[:, :3],
        angles_sigma=sext[:, 3:],
        point_ids=list(block.points.ids),
        xyz=xyz,
        xyz_sigma=sxyz,
        point_roles=[ROLES[r] for r in block.points.role],
        observation_quantity="image",
        critical=float(problem.options.get("critical", W_CRITICAL)),
        notes=notes,
        parameters=camera_parameters(block, adj, problem.units),
    )


def check_note(problem: Problem, block: Block, xyz: np.ndarray) -> list[str]:
    """r.m.s. of estimated minus given coordinates of the check points (file length unit)."""
    chk = np.flatnonzero(block.points.role == CHECK)
    if chk.size == 0:
        return []
    d = xyz[chk] - block.points.xyz_known[chk]
    n = np.sum(np.isfinite(d), axis=0)
    with np.errstate(invalid="ignore"):
        rms = np.sqrt(np.nansum(d**2, axis=0) / np.maximum(n, 1)) / problem.units.m_per_length
    rms = np.where(n > 0, rms, np.nan)
    return [
        f"check points ({chk.size}): r.m.s. of estimated − given X {rms[0]:.4g}, Y {rms[1]:.4g}, "
        f"Z {rms[2]:.4g} {problem.units.length}"
    ]


def solution_from_points(problem: Problem, block: Block, adj, method: str, func) -> Solution:
    """Report of a method that estimates points only (polynomial strip/block adjustment).

    Points come from ``points`` (all block points), their σ from the ``"points"``
    block where the method computed cofactors (else not available); no image orientation.
    """
    from ...adjust.result import W_CRITICAL  # a solution's types: only when solving
    from ..solution import Solution  # a solution's types: only when solving

    p = block.n_points
    xyz_sigma = np.full((p, 3), np.nan)
    if "points" in adj.groups and getattr(adj, "point_index", None) is not None:
        idx = np.asarray(adj.point_index, dtype=np.int64)
        xyz_sigma[idx] = adj.std()[adj.groups["points"]].reshape(-1, 3)[: idx.size]
    passes = inspect.signature(func).parameters.get("iterations")
    return Solution(
        kind="block",
        method=method,
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        point_ids=list(block.points.ids),
        xyz=np.asarray(adj.points, dtype=float),
        xyz_sigma=xyz_sigma,
        point_roles=[ROLES[r] for r in block.points.role],
        observation_quantity="length",
        critical=float(problem.options.get("critical", W_CRITICAL)),
        notes=[
            f"{method}: residuals are strip/model coordinates in the object frame; "
            "image orientations are not estimated by this method"
        ]
        + check_note(problem, block, np.asarray(adj.points, dtype=float)),
        iterations=(
            int(passes.default)
            if adj.iterations == 0 and passes is not None and isinstance(passes.default, int)
            else None
        ),
    )


def solution_from_models(problem: Problem, block: Block, adj) -> Solution:
    """Report of an independent-model adjustment: projection centres and points.

    The models' own orientations are not image orientations, so ω, φ, κ of the images
    are not reported (null); residuals are model coordinates in m.
    """
    from ...adjust.result import W_CRITICAL  # a solution's types: only when solving
    from ..solution import Solution  # a solution's types: only when solving

    m, p = block.n_images, block.n_points
    std = adj.std()
    tie_std = std[adj.groups["points"]].reshape(-1, 3)
    pidx = np.asarray(adj.point_index, dtype=np.int64)
    cidx = np.asarray(adj.centre_image, dtype=np.int64)
    xyz_sigma = np.full((p, 3), np.nan)
    xyz_sigma[pidx] = tie_std[: pidx.size]
    X0_sigma = np.full((m, 3), np.nan)
    X0_sigma[cidx] = tie_std[pidx.size : pidx.size + cidx.size]
    sol = Solution(
        kind="block",
        method=f"models ({adj.method})",
        adjustment=adj,
        units=problem.units,
        sequence=block.sequence,
        image_ids=list(block.images.ids),
        X0=np.asarray(adj.centres, dtype=float),
        angles=np.full((m, 3), np.nan),
        X0_sigma=X0_sigma,
        angles_sigma=np.full((m, 3), np.nan),
        point_ids=list(block.points.ids),
        xyz=np.asarray(adj.points, dtype=float),
        xyz_sigma=xyz_sigma,
        point_roles=[ROLES[r] for r in block.points.role],
        observation_quantity="length",
        critical=float(problem.options.get("critical", W_CRITICAL)),
        notes=[
            f"independent models: {adj.models.n_models} models; residuals are model "
            "coordinates in the object frame; image attitudes are not estimated (null)",
            f"r.m.s. model residual: XY {adj.rms_xy_m / problem.units.m_per_length:.4g}, "
            f"Z {adj.rms_z_m / problem.units.m_per_length:.4g} {problem.units.length}",
        ]
        + check_note(problem, block, np.asarray(adj.points, dtype=float)),
    )
    return sol


KIND = register_kind(
    Kind(
        name="block",
        schema="block.json",
        load=load,
        dump=dump,
        solve=solve,
        description="bundle block: cameras, images, tie/control/check points, image observations",
        methods=METHODS,
    )
)
