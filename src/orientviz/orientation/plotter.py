"""A simulated analog stereo plotter for the numerical relative orientation of a pair.

The plotter holds two projectors. The left one is fixed in the true orientation of the
left photograph (a dependent pair); the right one has the counters ``by, bz`` (mm) and
``ω, φ, κ`` (radians inside; centesimal minutes on the dials), turned through the
instrument's own axes: ``sequence="pok"`` (φ primary, then ω, then κ, as in Wild
instruments: R = R_φ R_ω R_κ) by default. The frame and the sign of p_y are those of
:mod:`orientviz.orientation.relative` (X along the base, Y left, Z up, model points at
Z < 0, p_y = Y_left − Y_right = the *by reading* that clears the parallax).

A *pass* (Kovarik 1968) reads ``by`` and ``z`` at the points of a scheme, computes the
corrections with a chosen formula and applies them through the counters; every pass is
kept in :attr:`AnalogPlotter.history`. Formulas (:data:`FORMULAS`):

* ``"exact"``: least squares of the linearised equation with the read heights z_i and
  the plan positions of the points (the exact linearisation);
* ``"kovarik9"``: Kovarik's closed form for 9 points in mountainous terrain, with his
  constant k = ordinate / c (edge points assumed at Y/Z = ∓k);
* ``"flat"``: the same least squares with one common height (Hallert's flat terrain);
* ``"preorient"``: the simple pre-orientation formulas with round constants
  (:mod:`orientviz.orientation.preorient`).

The true pair (two images' orientation, terrain points, image coordinates) comes from
:func:`true_pair` (module :mod:`orientviz.orientation.pairsim`, re-exported here);
:meth:`TruePair.scene` gives everything a 3D viewer needs. :func:`preorientation_error`
measures the errors of the round pre-orientation formulas as the rotations grow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..rotation import matrix_from_opk, matrix_from_rotvec, opk_from_matrix
from ..units import RHO_C
from .pairsim import PlotterConfig, TruePair, config_with, true_pair
from .preorient import preorientation_corrections
from .relative import DEPENDENT, PairState, design_dependent, y_parallax
from .schemes import Scheme, get_scheme, kovarik_nine_point, least_squares_elements

F64 = NDArray[np.float64]

FORMULAS: tuple[str, ...] = ("exact", "kovarik9", "flat", "preorient")


@dataclass
class Readings:
    """by and z read at the scheme points (machine mm; plan positions X, Y nominal)."""

    scheme: Scheme
    X: F64
    Y: F64
    by: F64
    z: F64
    parallax: F64


@dataclass
class PassRecord:
    """One pass: readings, computed corrections, the dials and the true errors after it.

    Attributes
    ----------
    index : int
        1, 2, … in the order of the passes.
    formula : str
    readings : Readings
    corrections : ndarray, shape (5,)
        dby, dbz (mm), dω, dφ, dκ (rad), orientviz senses.
    settings_after : ndarray, shape (5,)
        Dials after applying them (by, bz mm; ω, φ, κ rad in the instrument's sequence).
    error_after : ndarray, shape (5,)
        Dials minus the truth after the pass.
    """

    index: int
    formula: str
    readings: Readings
    corrections: F64
    settings_after: F64
    error_after: F64

    @property
    def max_rotation_c(self) -> float:
        """Largest absolute rotation correction in centesimal minutes."""
        return float(np.abs(self.corrections[2:]).max() * RHO_C)

    @property
    def max_base_mm(self) -> float:
        """Largest abs(dby), abs(dbz) in machine mm."""
        return float(np.abs(self.corrections[:2]).max())

    @property
    def rms_parallax(self) -> float:
        """RMS of the parallaxes read in this pass (machine mm)."""
        return float(np.sqrt(np.mean(self.readings.parallax**2)))


@dataclass
class OrientationRun:
    """The passes of one relative orientation and whether (when) it converged."""

    passes: list[PassRecord]
    converged: bool
    tol_c: float
    tol_mm: float

    @property
    def n_passes(self) -> int:
        """Passes read and computed, the last one (with negligible corrections) included."""
        return len(self.passes)

    def corrections_c(self) -> F64:
        """Largest rotation correction per pass, centesimal minutes."""
        return np.array([p.max_rotation_c for p in self.passes])


class AnalogPlotter:
    """The instrument: dials, readings at scheme points, passes.

    Parameters
    ----------
    pair : TruePair
        The photographs (their true orientation and terrain).
    scheme : Scheme or str
        Point scheme read in each pass (default Kovarik's nine points).
    settings : array_like, shape (5,), optional
        Initial dials by, bz (mm), ω, φ, κ (rad); default all zero (no pre-orientation).
    rng : numpy.random.Generator, optional
        Source of the reading noise; required if the configured noise is not zero.
    """

    def __init__(
        self,
        pair: TruePair,
        scheme: Scheme | str = "kovarik9",
        settings: ArrayLike | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        self.pair = pair
        self.config = pair.config.check()
        self.scheme = get_scheme(scheme)
        self.settings = (
            np.zeros(5) if settings is None else np.asarray(settings, float).reshape(5).copy()
        )
        if rng is None and (self.config.sigma_by > 0 or self.config.sigma_z > 0):
            raise InputError("reading noise is configured: pass rng=np.random.default_rng(seed)")
        self.rng = rng
        self.history: list[PassRecord] = []
        self._cache: dict = {}

    # -------------------------------------------------------------- state
    @property
    def state(self) -> PairState:
        return PairState.from_elements(
            self.settings, self.config.model_base, "dependent", self.config.sequence
        )

    @property
    def error(self) -> F64:
        """Dials minus the truth (by, bz mm; ω, φ, κ rad)."""
        return self.settings - self.pair.elements

    def scheme_points(self, scheme: Scheme | str | None = None) -> tuple[F64, F64, F64]:
        """Nominal plan positions and true terrain heights of the scheme points (machine mm)."""
        sch = self.scheme if scheme is None else get_scheme(scheme)
        cfg = self.config
        H = cfg.projection_distance
        X, Y, _ = sch.model_points(cfg.model_base, cfg.k * H, -H, placement="plan")
        if cfg.placement == "ratio":
            # along the ray of constant image ordinate: Y/Z = ∓k at the terrain height
            Z = -H * np.ones_like(X)
            for _ in range(20):
                Z = self.pair.height(X, Y)
                Y = sch.v * cfg.k * np.abs(Z)
        return X, Y, self.pair.height(X, Y)

    def parallax_at(self, points: ArrayLike) -> tuple[F64, F64]:
        """Noise-free y-parallaxes (mm) and model points at true terrain points (n, 3)."""
        xy1, xy2 = self.pair.images(points)
        return y_parallax(xy1, xy2, self.config.c, self.state)

    def _scheme_images(self, sch: Scheme):
        """Plan positions, heights and true image coordinates of a scheme (cached)."""
        key = (sch.name, self.config, id(self.pair), self.pair.elements.tobytes())
        hit = self._cache.get(sch.name)
        if hit is None or hit[0] != key:
            X, Y, Z = self.scheme_points(sch)
            xy1, xy2 = self.pair.images(np.column_stack([X, Y, Z]))
            hit = (key, X, Y, Z, xy1, xy2)
            self._cache[sch.name] = hit
        return hit[1:]

    def _field_images(self, nx: int, ny: int):
        """Plan grid and true image coordinates of its terrain points (cached per grid)."""
        key = ("field", nx, ny, self.config, id(self.pair), self.pair.elements.tobytes())
        hit = self._cache.get(("field", nx, ny))
        if hit is None or hit[0] != key:
            cfg = self.config
            d = cfg.k * cfg.projection_distance
            X, Y = np.meshgrid(np.linspace(0, cfg.model_base, nx), np.linspace(-d, d, ny))
            P = np.column_stack([X.ravel(), Y.ravel(), self.pair.height(X, Y).ravel()])
            xy1, xy2 = self.pair.images(P)
            hit = (key, X, Y, xy1, xy2)
            self._cache[("field", nx, ny)] = hit
        return hit[1:]

    def parallax_field(self, nx: int = 11, ny: int = 9) -> tuple[F64, F64, F64]:
        """Noise-free y-parallaxes over the model area (for arrows in a figure).

        The grid, its terrain heights and image coordinates are computed once per grid
        size and pair; a call only intersects the rays under the current dials.

        Returns
        -------
        X, Y, p : ndarray, shape (ny, nx)
            Plan grid over X ∈ [0, b], Y ∈ [−d, d] (machine mm) and the parallax p_y
            (mm) of the terrain point there under the current dials.
        """
        X, Y, xy1, xy2 = self._field_images(int(nx), int(ny))
        p, _ = y_parallax(xy1, xy2, self.config.c, self.state)
        return X, Y, p.reshape(X.shape)

    def read(self, scheme: Scheme | str | None = None, *, noise: bool = True) -> Readings:
        """Read by and z at every point of the scheme (with the configured noise).

        ``noise=False`` gives the exact readings (for display) and draws nothing from rng.
        """
        sch = self.scheme if scheme is None else get_scheme(scheme)
        X, Y, _, xy1, xy2 = self._scheme_images(sch)
        p, pts = y_parallax(xy1, xy2, self.config.c, self.state)
        z = pts[:, 2].copy()
        cfg = self.config
        if noise and self.rng is not None:
            if cfg.sigma_by:
                p = p + self.rng.normal(0.0, cfg.sigma_by, p.shape)
            if cfg.sigma_z:
                z = z + self.rng.normal(0.0, cfg.sigma_z, z.shape)
        return Readings(sch, X, Y, self.settings[0] + p, z, p)

    # -------------------------------------------------------------- formulas
    def corrections(
        self, readings: Readings, formula: str = "exact", k: float | None = None
    ) -> F64:
        """Corrections dby, dbz (mm), dω, dφ, dκ (rad, orientviz senses) from readings.

        Parameters
        ----------
        readings : Readings
        formula : {"exact", "kovarik9", "flat", "preorient"}
        k : float, optional
            The k = ordinate/c the formula's constants were computed with (default the
            configured one; Kovarik's wrong-ordinate experiment uses another).
        """
        cfg = self.config
        b, H = cfg.model_base, cfg.projection_distance
        kk = cfg.k if k is None else float(k)
        p = readings.by - self.settings[0]
        if formula == "exact":
            return least_squares_elements(
                design_dependent(readings.X, readings.Y, readings.z, b), p
            )
        if formula == "flat":
            Y = readings.scheme.v * kk * H
            return least_squares_elements(design_dependent(readings.X, Y, -H, b), p)
        if formula == "kovarik9":
            if readings.scheme.name != "kovarik9":
                raise InputError(
                    f"Kovarik's formula needs the 9-point scheme, not {readings.scheme.name}"
                )
            return kovarik_nine_point(p, readings.z, b, kk)
        if formula == "preorient":
            return preorientation_corrections(p, readings.z, readings.scheme, b)
        raise InputError(f"unknown formula {formula!r}; known: {', '.join(FORMULAS)}")

    def apply(self, d: ArrayLike) -> None:
        """Apply corrections (dby, dbz mm, dω, dφ, dκ rad about the model axes) to the dials."""
        d = np.asarray(d, dtype=float).reshape(5)
        self.settings[:2] += d[:2]
        if self.config.apply == "counters":
            self.settings[2:] += d[2:]
            return
        seq = self.config.sequence
        R = matrix_from_opk(*self.settings[2:], sequence=seq)
        R_new = matrix_from_rotvec(d[2:]) @ R
        self.settings[2:] = np.array(opk_from_matrix(R_new, seq), dtype=float)

    def run_pass(
        self, formula: str = "exact", k: float | None = None, *, z: ArrayLike | None = None
    ) -> PassRecord:
        """Read, compute, apply; append and return the :class:`PassRecord`.

        Parameters
        ----------
        formula : str
            One of :data:`FORMULAS`.
        k : float, optional
            k of the formula's constants (default the configured one).
        z : array_like, optional
            Heights to use instead of reading them in this pass (machine mm, one per
            scheme point): Kovarik's operator read z only in the first two passes and
            re-used them afterwards.
        """
        r = self.read()
        if z is not None:
            zz = np.asarray(z, dtype=float).reshape(-1)
            if zz.shape != r.z.shape:
                raise InputError(f"z: expected {r.z.size} heights, got {zz.size}")
            r = Readings(r.scheme, r.X, r.Y, r.by, zz, r.parallax)
        d = self.corrections(r, formula, k)
        self.apply(d)
        rec = PassRecord(
            len(self.history) + 1, formula, r, d, self.settings.copy(), self.error.copy()
        )
        self.history.append(rec)
        return rec

    def orient(
        self,
        formula: str = "exact",
        *,
        k: float | None = None,
        max_passes: int = 30,
        tol_c: float = 1.0,
        tol_mm: float = 0.05,
        z_reads: int | None = None,
    ) -> OrientationRun:
        """Repeat passes until one yields negligible corrections.

        Converged (Kovarik's practice) means: a pass computes rotations all below
        ``tol_c`` centesimal minutes and base corrections below ``tol_mm`` — what single
        by readings with the configured noise can no longer resolve. That pass is
        counted (it had to be read to know); its small corrections are applied too.

        Parameters
        ----------
        formula, k
            As in :meth:`corrections`.
        max_passes : int
            Give up (``converged=False``) after this many passes.
        tol_c, tol_mm : float
            Convergence thresholds: rotations in centesimal minutes, base in mm.
        z_reads : int, optional
            Read z only in the first ``z_reads`` passes and re-use the last read
            heights afterwards (Kovarik: z read in the first pass and its first
            repetition, so 2). Default: z read in every pass.
        """
        start = len(self.history)
        z_last = None
        for i in range(int(max_passes)):
            stale = z_reads is not None and i >= int(z_reads) and z_last is not None
            rec = self.run_pass(formula, k, z=z_last if stale else None)
            z_last = rec.readings.z
            if rec.max_rotation_c < tol_c and rec.max_base_mm < tol_mm:
                return OrientationRun(self.history[start:], True, tol_c, tol_mm)
        return OrientationRun(self.history[start:], False, tol_c, tol_mm)


__all__ = [
    "FORMULAS",
    "DEPENDENT",
    "PlotterConfig",
    "TruePair",
    "true_pair",
    "Readings",
    "PassRecord",
    "OrientationRun",
    "AnalogPlotter",
    "config_with",
]


def preorientation_error(
    magnitudes_c: ArrayLike,
    *,
    element: str = "all",
    ordinate: float = 110.0,
    relief: float = 0.0,
    rng: np.random.Generator | None = None,
) -> dict[str, F64]:
    """Error of the round formulas (and of the exact linearisation) as rotations grow.

    For each magnitude α the true pair is rotated by α (in ``element``, or in ω, φ and κ
    together for ``"all"``), the plotter stands at zero, and one noise-free pass of
    readings at Kovarik's nine points is evaluated by the round-constant formulas and by
    the exact linearisation (least squares with the read heights).

    Parameters
    ----------
    magnitudes_c : array_like, shape (m,)
        True rotation sizes α, centesimal minutes.
    element : {"omega", "phi", "all"}
    ordinate : float
        Image ordinate of the scheme's edge rows, mm (Kovarik: 110-117).
    relief : float
        Relative relief of the terrain.
    rng : numpy.random.Generator, optional
        Only needed for ``relief > 0`` (the terrain).

    Returns
    -------
    dict
        ``"alpha_c"``; ``"round"`` and ``"exact"``: arrays (m, 3) of the errors
        (computed − true) of Δω, Δφ (c) and Δbz (mm) — the true corrections being the
        true elements, since the plotter starts at zero.
    """
    alpha = np.atleast_1d(np.asarray(magnitudes_c, dtype=float))
    which = {"omega": [1, 0, 0], "phi": [0, 1, 0], "all": [1, 1, 1]}
    if element not in which:
        raise InputError(f"expected element 'omega', 'phi' or 'all', got {element!r}")
    cfg = config_with(ordinate=ordinate, relief=relief, sigma_by=0.0, sigma_z=0.0)
    if relief > 0 and rng is None:
        raise InputError("a terrain with relief needs rng=np.random.default_rng(seed)")
    base = true_pair(cfg, rng=rng or np.random.default_rng(0), elements=np.zeros(5))
    out_round = np.empty((alpha.size, 3))
    out_exact = np.empty((alpha.size, 3))
    for i, a in enumerate(alpha):
        e = np.zeros(5)
        e[2:] = np.array(which[element]) * np.array([1.0, -0.8, 0.6]) * a / RHO_C
        base.elements = e
        plotter = AnalogPlotter(base, "kovarik9")
        r = plotter.read()
        d = preorientation_corrections(r.by, r.z, r.scheme, cfg.model_base)
        ex = plotter.corrections(r, "exact")
        rnd = np.array([d[2] * RHO_C, d[3] * RHO_C, d[1]])
        exa = np.array([ex[2] * RHO_C, ex[3] * RHO_C, ex[1]])
        true = np.array([e[2] * RHO_C, e[3] * RHO_C, e[1]])
        out_round[i] = rnd - true
        out_exact[i] = exa - true
    return {"alpha_c": alpha, "round": out_round, "exact": out_exact}
