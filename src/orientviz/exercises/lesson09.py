"""Checkers for lesson 09 (the datum: free networks, S-transformation, estimable quantities).

Oracles: a numerical Jacobian of the distances (central differences) for the null space;
the bordered normal equations solved directly with the new datum's constraints for the
S-transformation; for what is estimable, numerical gradients of five quantities against the
null space of a distance and of a direction network; for the datum defect of a
normal matrix, one built with a known null space (and eigenvalues spread over 13 orders of
magnitude, as when m and rad are mixed); for the datum dropdowns, every pair of datum points
S-transformed here.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg import null_space as scipy_null_space  # forbidden (own_work), no oracle

from ..adjust.datum import datum_solve, helmert_basis, s_transformation
from ..adjust.rank import null_space_of_normal  # forbidden (own_work), no oracle
from ._common import CheckFailed, call, compare, own_work, rng_for, success
from .sliders import check_slider_answer


def _network(rng):
    p = 6
    xy = np.column_stack([rng.uniform(0, 900, p), rng.uniform(0, 800, p)])
    i, j = np.triu_indices(p, 1)
    pairs = np.column_stack([i, j])
    return xy, pairs


def _distances(x, pairs):
    xy = x.reshape(-1, 2)
    return np.linalg.norm(xy[pairs[:, 1]] - xy[pairs[:, 0]], axis=1)


# --------------------------------------------------------------------- null space


def _angles(x, triples):
    """The angles (rad) at point j between the points i and k, for rows (i, j, k)."""
    xy = x.reshape(-1, 2)
    a, b = xy[triples[:, 0]] - xy[triples[:, 1]], xy[triples[:, 2]] - xy[triples[:, 1]]
    return np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], np.sum(a * b, axis=1))


def _angle_jacobian(x, triples, h=1e-4):
    J = np.empty((len(triples), x.size))
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = h
        J[:, k] = (_angles(x + e, triples) - _angles(x - e, triples)) / (2 * h)
    return J


def similarity_basis_library(xy: np.ndarray) -> np.ndarray:
    """The lesson's stand-in for ``similarity_columns`` while its blank is empty: the library's
    null-space basis with the scale column, (2p, 4). :func:`check_similarity_columns` refuses it.
    """
    return helmert_basis(np.asarray(xy, float), scale=True)


def best_datum_library(Q: np.ndarray, G: np.ndarray) -> tuple[int, int]:
    """The lesson's stand-in for ``best_datum`` while its blank is empty: every pair tried with
    the library's S-transformation (0-based indices). :func:`check_best_datum` refuses it."""
    p = Q.shape[0] // 2
    pairs = [(i, j) for i in range(p) for j in range(i + 1, p)]

    def worst(pair: tuple[int, int]) -> float:
        S = s_transformation(G, datum_points=list(pair))
        return _largest_point_sigma(S @ Q @ S.T)

    return min(pairs, key=worst)


@own_work(
    "helmert_basis (with scale=True) and the stand-in give the answer; write the four columns "
    "yourself",
    helmert_basis=helmert_basis,
    similarity_basis_library=similarity_basis_library,
)
def check_similarity_columns(fn) -> None:
    """``fn(xy) -> G`` (2p, 4): columns that move a planar network of measured ANGLES (unknowns
    x1, y1, x2, …) without changing any angle; together they must span the whole defect
    (two shifts, a rotation and a change of scale).

    Oracle: a numerical Jacobian of all angles between the points of a network the lesson does
    not use; any basis of the null space passes (centred or not, scaled or not).
    """
    for salt in range(2):
        xy, _ = _network(rng_for("lesson09.check_similarity_columns", salt))
        p = len(xy)
        triples = np.array([(i, j, k) for j in range(p) for i in range(p) for k in range(i + 1, p)
                            if len({i, j, k}) == 3])  # fmt: skip
        G = np.asarray(call(fn, xy.copy(), what="similarity_columns"), dtype=float)
        if G.ndim != 2 or G.shape[0] != xy.size:
            raise CheckFailed(f"G: expected {xy.size} rows (x1, y1, x2, …), got shape {G.shape}")
        if G.shape[1] == 3:
            raise CheckFailed(
                "G: 3 columns are the defect of a DISTANCE network; angles keep no length "
                "either, so a change of scale is free too: 4 columns",
                error=np.inf,
            )
        if G.shape[1] != 4:
            raise CheckFailed(
                f"G: expected 4 columns — two shifts, a rotation, a scale — got {G.shape[1]}"
            )
        J = _angle_jacobian(xy.reshape(-1), triples)
        Gn = G / np.maximum(np.linalg.norm(G, axis=0), 1e-300)
        change = np.abs(J @ Gn).max(axis=0) * np.linalg.norm(xy - xy.mean(axis=0), axis=1).max()
        bad = int(np.argmax(change))
        if change[bad] > 1e-6:
            c = xy - xy.mean(axis=0)
            swapped = np.column_stack([c[:, 1], c[:, 0]]).reshape(-1)
            if abs(Gn[:, bad] @ swapped) > 0.999 * np.linalg.norm(swapped):
                hint = (
                    " — (y, x) is a shear: a change of scale moves point (x, y) by ε(x, y), "
                    "a rotation by ε(−y, x)"
                )
            else:
                hint = (
                    " — a scale moves (x, y) by ε(x, y), a rotation by ε(−y, x) (about the "
                    "centroid or the origin), a shift by the same vector for all points"
                )
            raise CheckFailed(
                f"G: column {bad + 1} changes the angles by {change[bad]:.3g} rad per unit{hint}",
                float(change[bad]),
                1e-6,
            )
        sv = np.linalg.svd(Gn, compute_uv=False)
        if sv[-1] < 1e-6 * sv[0]:
            raise CheckFailed(
                "G: the four columns are not independent (rank < 4): one motion is missing or "
                "repeated",
                1.0 / max(sv[-1] / sv[0], 1e-300) * 1e-6,
                1e-6,
            )
    success("J G = 0 with a numerical Jacobian of all angles, rank 4 (shifts, rotation, scale)")


# --------------------------------------------------------------------- S-transformation


def _problem(rng):
    xy, pairs = _network(rng)
    x0 = xy.reshape(-1)
    sig = 0.004
    l = _distances(x0, pairs) + rng.normal(0, sig, len(pairs))
    d = xy[pairs[:, 1]] - xy[pairs[:, 0]]
    u = d / np.linalg.norm(d, axis=1)[:, None]
    J = np.zeros((len(pairs), x0.size))
    r = np.arange(len(pairs))
    for k in range(2):
        J[r, 2 * pairs[:, 1] + k], J[r, 2 * pairs[:, 0] + k] = u[:, k], -u[:, k]
    N, b = J.T @ J / sig**2, J.T @ (l - _distances(x0, pairs)) / sig**2
    # the datum defect's basis: the null space of the distances' Jacobian (SVD)
    G = np.linalg.svd(J)[2][-3:].T
    return xy, N, b, G


def _bordered(N, b, G, e):
    u, d = G.shape
    EG = G * e[:, None] * np.sqrt(np.trace(N) / u)
    M = np.block([[N, EG], [EG.T, np.zeros((d, d))]])
    Mi = np.linalg.inv(M)
    return Mi[:u, :u] @ b, Mi[:u, :u]


def _sel(p, pts):
    e = np.zeros(p)
    e[list(pts)] = 1.0
    return np.repeat(e, 2)


def _s_matrix(G, e):
    GtE = G.T * e
    return np.eye(len(e)) - G @ np.linalg.solve(GtE @ G, GtE)


def _largest_point_sigma(Q: np.ndarray) -> float:
    """The largest point error √(σx² + σy²) of a cofactor matrix (σ0 = 1), m."""
    return float(np.sqrt(np.diag(Q).reshape(-1, 2).sum(axis=1)).max())


@own_work(
    "that is the stand-in; the exercise is your own search over the pairs",
    best_datum_library=best_datum_library,
)
def check_best_datum(fn) -> None:
    """``fn(Q, G) -> (i, j)``: the two datum points (0-based) that make the largest point error
    √(σx² + σy²) of the network smallest, from the cofactors Q of any datum.

    Oracle: a new bordered adjustment in every pair's datum (no S-transformation), brute force
    over all pairs; ties within 1e-9 are accepted.
    """
    for salt in range(2):
        rng = rng_for("lesson09.check_best_datum", salt)
        xy, N, b, G = _problem(rng)
        p = len(xy)
        _, Q_inner = _bordered(N, b, G, np.ones(2 * p))
        pairs = [(i, j) for i in range(p) for j in range(i + 1, p)]
        worst = {pr: _largest_point_sigma(_bordered(N, b, G, _sel(p, pr))[1]) for pr in pairs}
        best = min(worst.values())
        got = call(fn, Q_inner.copy(), G.copy(), what="best_datum")
        try:
            pr = tuple(sorted(int(k) for k in got))
        except (TypeError, ValueError):
            raise CheckFailed(f"best_datum: expected two point indices, got {got!r}") from None
        if pr not in worst:
            raise CheckFailed(
                f"best_datum: {got!r} is not a pair of two of the {p} points (0-based)"
            )
        if worst[pr] <= best * (1 + 1e-9):
            continue
        far = max(pairs, key=lambda q: np.linalg.norm(xy[q[0]] - xy[q[1]]))
        sig_inner = np.sqrt(np.diag(Q_inner).reshape(-1, 2).sum(axis=1))
        centre = tuple(sorted(np.argsort(sig_inner)[:2].tolist()))
        if pr == far:
            why = (
                "the pair farthest apart — close, but the network's shape matters too: compare "
                "the largest point error of every pair"
            )
        elif pr == centre:
            why = (
                "the two best points of the inner datum lie in the middle: as datum points they "
                "let the network swing about them, and the outer points get worse"
            )
        else:
            why = "move Q into each pair's datum (S Q Sᵀ) and compare the largest point error"
        raise CheckFailed(
            f"best_datum: points {pr} give a largest point error of {worst[pr] * 1000:.2f} mm, "
            f"the best pair {min(worst, key=worst.get)} {best * 1000:.2f} mm — {why}",
            error=np.inf,
            tolerance=0.0,
        )
    success("the datum pair with the smallest largest point error, in two networks")


# --------------------------------------------------------------------- estimable or not

#: The quantities of the exercise "estimable or not?" (points numbered from 1).
ESTIMABLE_QUANTITIES = (
    "coordinate x of point 1",
    "distance 1–4",
    "angle at point 5 between points 1 and 6",
    "azimuth of the line 1–2",
    "ratio of the distances 1–4 and 2–3",
)


def _quantity(name: str, x: np.ndarray) -> float:
    """The value of one quantity of ESTIMABLE_QUANTITIES for coordinates x = (x1, y1, x2, …)."""
    P = x.reshape(-1, 2)

    def dist(i: int, j: int) -> float:
        return float(np.linalg.norm(P[j - 1] - P[i - 1]))

    if name.startswith("coordinate"):
        return float(P[0, 0])
    if name.startswith("distance"):
        return dist(1, 4)
    if name.startswith("angle"):
        a, b = P[0] - P[4], P[5] - P[4]
        return float(np.arctan2(a[0] * b[1] - a[1] * b[0], a @ b))
    if name.startswith("azimuth"):
        d = P[1] - P[0]
        return float(np.arctan2(d[0], d[1]))
    return dist(1, 4) / dist(2, 3)


def _estimable(name: str, x: np.ndarray, G: np.ndarray) -> bool:
    """fᵀG = 0 with f the numerical gradient of the quantity (central differences)."""
    f = np.zeros(x.size)
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = 1e-4
        f[k] = (_quantity(name, x + e) - _quantity(name, x - e)) / 2e-4
    Gn = G / np.linalg.norm(G, axis=0)
    return bool(np.max(np.abs(f @ Gn)) < 1e-6 * np.linalg.norm(f))


def check_estimable(fn) -> None:
    """``fn() -> {quantity: (in a distance network, in a network of directions only)}``: for
    each of :data:`ESTIMABLE_QUANTITIES`, True if it is estimable (the same in every datum).

    Oracle: on a network of six points the checker differentiates each quantity numerically
    and tests fᵀG = 0 with G the shifts and the rotation (distances measured: defect 3) and
    with the scale added (directions only: defect 4).
    """
    rng = rng_for("lesson09.check_estimable")
    xy = np.column_stack([rng.uniform(0, 900, 6), rng.uniform(0, 800, 6)])
    x = xy.reshape(-1)
    c = xy - xy.mean(axis=0)
    G3 = np.zeros((x.size, 3))
    G3[0::2, 0], G3[1::2, 1] = 1.0, 1.0
    G3[0::2, 2], G3[1::2, 2] = -c[:, 1], c[:, 0]
    G4 = np.column_stack([G3, c.reshape(-1)])  # + the change of scale
    got = call(fn, what="estimable")
    if not isinstance(got, dict) or set(got) != set(ESTIMABLE_QUANTITIES):
        raise CheckFailed(
            "estimable: return a dict with exactly these keys: " + "; ".join(ESTIMABLE_QUANTITIES)
        )
    why = {
        ("coordinate", 0): "a shift of the whole network moves every coordinate",
        ("azimuth", 0): "a rotation of the whole network turns every azimuth",
        ("distance", 0): "in a network of distances the scale is measured: a distance is estimable",
        ("distance", 1): "without a measured length the scale is free: a distance is not estimable",
        ("angle", 0): "an angle does not change under shift, rotation or scale: estimable in both",
        ("angle", 1): "an angle does not change under shift, rotation or scale: estimable in both",
        ("ratio", 0): "a ratio of two distances survives even a change of scale: estimable in both",
        ("ratio", 1): "a ratio of two distances survives even a change of scale: estimable in both",
        ("coordinate", 1): "a shift of the whole network moves every coordinate",
        ("azimuth", 1): "a rotation of the whole network turns every azimuth",
    }
    wrong = []
    for name in ESTIMABLE_QUANTITIES:
        want = (_estimable(name, x, G3), _estimable(name, x, G4))
        try:
            ans = tuple(bool(v) for v in got[name])
        except TypeError:
            raise CheckFailed(
                f"estimable: {name!r} needs two booleans (distances, directions)"
            ) from None
        if len(ans) != 2:
            raise CheckFailed(f"estimable: {name!r} needs two booleans (distances, directions)")
        for k in (0, 1):
            if ans[k] != want[k]:
                net = ("the distance network", "the network of directions")[k]
                wrong.append(f"{name} in {net}: {why[(name.split()[0], k)]}")
    if wrong:
        raise CheckFailed("estimable: " + "; ".join(wrong), error=np.inf, tolerance=0.0)
    success("all five right: fᵀG = 0 decides, not whether the quantity was measured")


# --------------------------------------------------------------------- inner constraints


def check_inner_solve(fn) -> None:
    """``fn(N, b, G) -> (dx, Q)``: the inner-constraint solution of N dx = b bordered with G
    (all points), and Q the u × u block of the bordered inverse."""
    rng = rng_for("lesson09.check_inner_solve")
    xy, N, b, G = _problem(rng)
    u = N.shape[0]
    # G scaled, not unit: the student's function must not depend on the columns' length
    Gs = G * rng.uniform(0.5, 40.0, 3)
    with own_work(datum_solve=datum_solve):
        got = call(fn, N.copy(), b.copy(), Gs.copy(), what="inner_solve")
    if not isinstance(got, tuple) or len(got) != 2:
        raise CheckFailed("inner_solve: return the pair (dx, Q)")
    dx, Q = (np.asarray(g, dtype=float) for g in got)
    if Q.shape == (u + 3, u + 3):
        raise CheckFailed(
            f"Q: this is the whole bordered inverse ({u + 3} × {u + 3}); return its u × u block "
            f"({u} × {u})",
            tolerance=1e-8,
        )
    # oracle: with E = I the inner-constraint solution is the pseudo-inverse's
    Np = np.linalg.pinv(N, rcond=1e-10)
    GGt = Gs @ Gs.T
    compare("Q [m²]", Q, Np, rtol=1e-7, wrong=[
        ("N + G Gᵀ regularises N, it is not the bordered system", np.linalg.inv(N + GGt)),
    ])  # fmt: skip
    compare("dx [m]", dx, Np @ b, rtol=1e-7, wrong=[
        ("the sign of dx is wrong: N dx = b", -(Np @ b)),
        ("N + G Gᵀ regularises N, it is not the bordered system", np.linalg.solve(N + GGt, b)),
    ])  # fmt: skip
    success("dx and Q equal the pseudo-inverse solution N⁺ b, N⁺ (E = I, any scaling of G)")


def _defect_case(
    rng: np.random.Generator, d: int, clusters: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """A normal matrix with a known null space of dimension d, round-off of 1e-6 in it, and
    eigenvalues from 5e-2 to 2e9 (m and rad mixed); with ``clusters`` the real eigenvalues
    form two groups 8 orders of magnitude apart (a larger jump than the one at the defect)."""
    u = 40
    G0 = np.linalg.qr(rng.normal(size=(u, d)))[0]
    rest = rng.normal(size=(u, u))
    rest = rest - G0 @ (G0.T @ rest)
    W = np.linalg.svd(rest, full_matrices=False)[0][:, : u - d]  # orthonormal, orthogonal to G0
    if clusters:
        half = (u - d) // 2
        lam = np.r_[
            10.0 ** rng.uniform(-0.5, 0.5, half), 10.0 ** rng.uniform(8.5, 9.3, u - d - half)
        ]
    else:
        lam = 10.0 ** rng.uniform(-1, 9, u - d)
        lam[:4] = [0.05, 0.08, 0.5, 2e9]  # small but real eigenvalues (weak, not a defect)
    N = (W * lam) @ W.T + (G0 * rng.uniform(-1e-6, 1e-6, d)) @ G0.T
    return (N + N.T) / 2, G0


@own_work(
    "the exercise is your own rule for which eigenvalues of eigh are zero; scipy's "
    "null_space (the stand-in above) applies its own",
    **{"scipy.linalg.null_space": scipy_null_space},
    null_space_of_normal=null_space_of_normal,
)
def check_null_space(null_space) -> None:
    """``null_space(N)`` must return G (u, d): a basis of the null space of the symmetric normal
    matrix N, d its datum defect: the eigenvalues that are zero to round-off (about u·ε·λ_max),
    not those below a fixed tolerance nor those below the largest jump of the spectrum.
    The answer may not call scipy's ``null_space`` or the library's ``null_space_of_normal``."""
    rng = rng_for("lesson09.check_null_space")
    for d, clusters in ((7, False), (4, False), (7, True)):
        N, G0 = _defect_case(rng, d, clusters)
        G = np.asarray(call(null_space, N.copy(), what="null_space"), dtype=float)
        if G.ndim != 2 or G.shape[0] != len(N):
            hint = " (columns are the basis vectors: eigh returns them as columns, V[:, :d])"
            raise CheckFailed(
                f"null_space: expected an array of shape ({len(N)}, d), got {G.shape}{hint}."
            )
        if G.shape[1] != d:
            w = np.linalg.eigvalsh(N)
            why = (
                "more than the defect: small but real eigenvalues "
                f"({w[d]:.1e} …, the largest is {w[-1]:.1e}) were taken for zero — a tolerance "
                "too large, or the largest jump of the spectrum, which here lies between two "
                "groups of real eigenvalues; round-off is about u·ε·λ_max"
                if G.shape[1] > d
                else "fewer than the defect: the zero eigenvalues are zero only to round-off "
                f"(up to {np.abs(w[:d]).max():.0e} here): a tolerance that small misses them"
            )
            raise CheckFailed(
                f"null_space: {G.shape[1]} columns, but the defect of this N is {d} — {why}.",
                error=abs(G.shape[1] - d),
                tolerance=0.0,
            )
        try:
            proj = G @ np.linalg.pinv(G)
        except np.linalg.LinAlgError:  # pragma: no cover - pinv of finite input converges
            raise CheckFailed("null_space: the columns of G are not independent.") from None
        compare(
            f"the projector onto span(G), defect {d}",
            proj,
            G0 @ G0.T,
            rtol=1e-4,
            wrong=[("these columns are eigenvectors of the LARGEST eigenvalues, not the smallest",
                    (lambda V: V @ V.T)(np.linalg.eigh(N)[1][:, -d:]))],
        )  # fmt: skip
    success(
        "null_space: the defect and its directions — the eigenvalues that are zero to round-off"
    )


# ---------------------------------------------------------------- the datum dropdowns


def _a_of_point(G: np.ndarray, Q: np.ndarray, pts: Sequence[int], k: int) -> float:
    """Semi-major axis (cofactor units) of point k's ellipse in the datum of the points pts."""
    S = _s_matrix(G, _sel(G.shape[0] // 2, pts))
    Qk = (S @ Q @ S.T)[2 * k : 2 * k + 2, 2 * k : 2 * k + 2]
    return float(np.sqrt(np.linalg.eigvalsh(Qk)[-1]))


def check_largest_ellipse(
    answer: object, G: np.ndarray, Q: np.ndarray, sigma0: float, point: int = 5
) -> None:
    """The largest semi-major axis (mm) that the ellipse of ``point`` (1-based) takes among
    all datums of two points (the lesson's dropdowns), σ̂0 applied.

    Oracle: every pair of datum points, the S-transformation of ``Q`` (any datum's cofactors,
    m², unknowns x1, y1, x2, …) written out here and the largest eigenvalue of the point's
    2 × 2 block — not the library's ``s_transformation`` or ``error_ellipse``.
    """
    p, k = G.shape[0] // 2, point - 1
    a = {
        (i, j): sigma0 * _a_of_point(G, Q, (i, j), k) * 1000.0
        for i in range(p)
        for j in range(i + 1, p)
    }
    worst = max(a, key=a.get)
    S = _s_matrix(G, np.ones(2 * p))
    inner = sigma0 * float(np.sqrt(np.linalg.eigvalsh((S @ Q @ S.T)[2 * k : 2 * k + 2,
                                                                   2 * k : 2 * k + 2])[-1])) * 1000.0  # fmt: skip
    wrong = [
        ("the SMALLEST ellipse of the point (a datum next to it), not the largest",
         min(a.values())),
        ("without σ̂0: that is √(largest eigenvalue) of the cofactor block; a = σ̂0 √λ",
         a[worst] / sigma0),
        ("the inner datum's value, which the dropdowns do not give", inner),
        ("in m, not mm", a[worst] / 1000.0),
    ]  # fmt: skip
    check_slider_answer(f"largest a of point {point}", answer, a[worst], 0.01, "mm", wrong)
    print(f"  (datum points {worst[0] + 1} and {worst[1] + 1})")
