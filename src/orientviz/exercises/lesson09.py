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

from ..adjust.datum import datum_solve
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


def _jacobian(x, pairs, h=1e-5):
    J = np.empty((len(pairs), x.size))
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = h
        J[:, k] = (_distances(x + e, pairs) - _distances(x - e, pairs)) / (2 * h)
    return J


# --------------------------------------------------------------------- null space


def check_helmert_columns(fn) -> None:
    """``fn(xy) -> G`` (2p, 3): columns that move a planar distance network (unknowns x1,
    y1, x2, …) without changing any distance; together they must span the whole defect."""
    for salt in range(2):
        xy, pairs = _network(rng_for("lesson09.check_helmert_columns", salt))
        G = np.asarray(call(fn, xy.copy(), what="helmert_columns"), dtype=float)
        if G.shape != (xy.size, 3):
            raise CheckFailed(
                f"G: expected shape ({xy.size}, 3) — two shifts and one rotation — got {G.shape}"
            )
        J = _jacobian(xy.reshape(-1), pairs)
        Gn = G / np.maximum(np.linalg.norm(G, axis=0), 1e-300)
        change = np.abs(J @ Gn).max(axis=0)  # distance change per unit move, each column
        bad = int(np.argmax(change))
        if change[bad] > 1e-8:
            err = float(change[bad])
            hint = ""
            if bad == 2 or np.linalg.matrix_rank(G) == 3:
                hint = (
                    " — a rotation moves point (x, y) by (−y, x) (about the centroid or the origin);"
                    " (x, y) itself is a change of scale, which the distances see"
                )
            raise CheckFailed(
                f"G: column {bad + 1} changes the distances by {err:.3g} per unit{hint}", err, 1e-8
            )
        sv = np.linalg.svd(Gn, compute_uv=False)
        if sv[-1] < 1e-6 * sv[0]:
            raise CheckFailed("G: the three columns are not independent (rank < 3): the defect is not covered",
                              1.0 / max(sv[-1] / sv[0], 1e-300) * 1e-6, 1e-6)  # fmt: skip
    success("J G = 0 with a numerical Jacobian of all distances, rank 3")


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


def _s_transform(x, Q, G, pts, mode):
    """The S-transformation with one plausible mistake (mode "all", "no_St", "x_only")."""
    e = _sel(len(x) // 2, pts) if mode != "all" else np.ones(len(x))
    S = _s_matrix(G, e)
    if mode == "no_St":
        return S @ x, S @ Q
    if mode == "x_only":
        return S @ x, Q
    return S @ x, S @ Q @ S.T  # mode "all": the right formula with the wrong E


def check_s_transform(fn) -> None:
    """``fn(x, Q, G, datum_points) -> (x_new, Q_new)``: corrections and cofactors of a free
    network moved from the inner-constraint datum into the datum of ``datum_points``."""
    rng = rng_for("lesson09.check_s_transform")
    xy, N, b, G = _problem(rng)
    p = len(xy)
    xA, QA = _bordered(N, b, G, np.ones(2 * p))
    pts = [1, 4]
    xB, QB = _bordered(N, b, G, _sel(p, pts))
    got = call(fn, xA.copy(), QA.copy(), G.copy(), list(pts), what="s_transform")
    if not isinstance(got, tuple) or len(got) != 2:
        raise CheckFailed("s_transform: return the pair (x_new, Q_new)")
    x_new, Q_new = (np.asarray(g, dtype=float) for g in got)
    compare("x_new [m]", x_new, xB, rtol=1e-8, wrong=[
        ("E selects all points: the datum points are only " + str(pts), _s_transform(xA, QA, G, pts, "all")[0]),
    ])  # fmt: skip
    compare("Q_new", Q_new, QB, rtol=1e-8, wrong=[
        ("Q_new = S Q Sᵀ, not S Q", _s_transform(xA, QA, G, pts, "no_St")[1]),
        ("Q must be transformed too: Q_new = S Q Sᵀ", QA),
        ("E selects all points: the datum points are only " + str(pts), _s_transform(xA, QA, G, pts, "all")[1]),
    ])  # fmt: skip
    success("S-transformed x and Q equal a new adjustment with the datum on points 2 and 5")


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
