"""The simulated photographs of a stereo pair: instrument set-up, terrain, true orientation.

:class:`PlotterConfig` describes the camera (c = 152.7 mm, 23 × 23 cm), the model base and
scale of the analog plotter, the scheme ordinate, the relative relief, the instrument axes
and the reading noise; :func:`true_pair` draws a random smooth terrain and a random true
relative orientation; :class:`TruePair` projects model points into both photographs and
gives a 3D scene (:meth:`TruePair.scene`) — the data a viewer's ``pair`` demo needs.
Frame and conventions: :mod:`orientviz.orientation.relative` (machine mm, radians).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import project
from ..errors import InputError
from ..rotation import check_sequence, matrix_from_opk
from ..units import RHO_C
from .relative import PairState

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class PlotterConfig:
    """Geometry of the simulated instrument and photographs.

    Attributes
    ----------
    c : float
        Principal distance, mm (wide angle 152.7).
    format_mm : float
        Side of the square image format, mm (230).
    image_base : float
        Base in the image, mm (about 92 at 60 % forward overlap).
    model_base : float
        Model base b in machine mm (Kovarik's constant 220.7). Together with
        ``image_base`` it sets the model scale and the projection distance
        abs(Z) = model_base / image_base × c (366 mm by default; Kovarik: 350-400 mm).
    ordinate : float
        Image ordinate of the scheme's edge rows, mm; k = ordinate / c.
    relief : float
        Relative relief: (highest − lowest terrain point) / projection distance.
    sequence : str
        Instrument axes: ``"pok"`` (φ primary, Wild) or ``"opk"``.
    sigma_by, sigma_z : float
        Reading noise of the by and z counters, machine mm.
    placement : str
        ``"plan"`` (points set by the X, Y counters) or ``"ratio"`` (at Y/Z = ∓k).
    apply : str
        ``"counters"``: corrections are added to the dials (the instrument's axes are
        ignored, as at the desk); ``"axes"``: they are converted to dial values through
        the instrument's axes (Bernhard's correction, exact).
    """

    c: float = 152.7
    format_mm: float = 230.0
    image_base: float = 92.0
    model_base: float = 220.7
    ordinate: float = 100.0
    relief: float = 0.10
    sequence: str = "pok"
    sigma_by: float = 0.005
    sigma_z: float = 0.02
    placement: str = "plan"
    apply: str = "counters"

    @property
    def scale(self) -> float:
        """Machine mm per image mm (model base / image base)."""
        return self.model_base / self.image_base

    @property
    def projection_distance(self) -> float:
        """abs(Z) of the reference plane in machine mm (scale × c)."""
        return self.scale * self.c

    @property
    def k(self) -> float:
        """Kovarik's k = abs(y)/abs(z) of the edge rows (ordinate / c)."""
        return self.ordinate / self.c

    def check(self) -> PlotterConfig:
        for name in ("c", "format_mm", "image_base", "model_base", "ordinate"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise InputError(f"expected a positive {name} in mm, got {v}")
        if not 0 <= self.relief < 1:
            raise InputError(f"expected a relative relief in [0, 1), got {self.relief}")
        if self.sigma_by < 0 or self.sigma_z < 0:
            raise InputError("expected non-negative reading noise")
        check_sequence(self.sequence)
        if self.placement not in ("plan", "ratio"):
            raise InputError(f"expected placement 'plan' or 'ratio', got {self.placement!r}")
        if self.apply not in ("counters", "axes"):
            raise InputError(f"expected apply 'counters' or 'axes', got {self.apply!r}")
        return self


@dataclass
class TruePair:
    """The photographed truth: terrain and the true relative orientation.

    Attributes
    ----------
    config : PlotterConfig
    elements : ndarray, shape (5,)
        True by, bz (machine mm) and ω, φ, κ (radians, ``config.sequence``) of the right
        image relative to the left one (left: R = I at the origin).
    terrain : dict
        Parameters of the smooth terrain: ``"centres"`` (m, 2), ``"widths"`` (m,),
        ``"weights"`` (m,), ``"offset"``, ``"gain"``.
    """

    config: PlotterConfig
    elements: F64
    terrain: dict = field(repr=False)

    def height(self, X: ArrayLike, Y: ArrayLike) -> F64:
        """Terrain height Z (machine mm, negative) at plan positions X, Y."""
        X, Y = np.broadcast_arrays(np.asarray(X, float), np.asarray(Y, float))
        t = self.terrain
        dx = X[..., None] - t["centres"][:, 0]
        dy = Y[..., None] - t["centres"][:, 1]
        f = np.sum(t["weights"] * np.exp(-(dx**2 + dy**2) / t["widths"] ** 2), axis=-1)
        H = self.config.projection_distance
        return -H + self.config.relief * H * (f - t["offset"]) * t["gain"]

    @property
    def state(self) -> PairState:
        """The true orientation as a :class:`PairState`."""
        return PairState.from_elements(
            self.elements, self.config.model_base, "dependent", self.config.sequence
        )

    def images(self, points: ArrayLike) -> tuple[F64, F64]:
        """Image coordinates (mm) of model points (n, 3) in the left and right photograph."""
        st, c = self.state, self.config.c
        xy1 = project(points, np.zeros(3), np.eye(3), c)
        xy2 = project(points, st.base, matrix_from_opk(*st.angles_right, sequence=st.sequence), c)
        return xy1, xy2

    def scene(self, n_grid: int = 21) -> dict:
        """Everything a 3D view of the pair needs (machine mm, radians).

        Returns
        -------
        dict
            ``"centres"`` (2, 3) projection centres; ``"rotations"`` (2, 3, 3), image →
            model; ``"c"``; ``"format_mm"``; ``"terrain"`` (n_grid², 3) grid points over
            the model area; ``"xy_left"``, ``"xy_right"`` their image coordinates (mm);
            ``"elements"`` the true by, bz, ω, φ, κ and ``"sequence"``.
        """
        cfg = self.config
        b, d = cfg.model_base, cfg.ordinate * cfg.scale
        X, Y = np.meshgrid(np.linspace(-0.1 * b, 1.1 * b, n_grid), np.linspace(-d, d, n_grid))
        P = np.column_stack([X.ravel(), Y.ravel(), self.height(X, Y).ravel()])
        xy1, xy2 = self.images(P)
        st = self.state
        R2 = matrix_from_opk(*st.angles_right, sequence=st.sequence)
        return {
            "centres": np.array([np.zeros(3), st.base]),
            "rotations": np.array([np.eye(3), R2]),
            "c": cfg.c,
            "format_mm": cfg.format_mm,
            "terrain": P,
            "xy_left": xy1,
            "xy_right": xy2,
            "elements": self.elements.copy(),
            "sequence": st.sequence,
        }


def true_pair(
    config: PlotterConfig | None = None,
    *,
    rng: np.random.Generator,
    start_c: tuple[float, float] = (100.0, 150.0),
    start_mm: tuple[float, float] = (1.0, 3.0),
    elements: ArrayLike | None = None,
    n_hills: int = 6,
) -> TruePair:
    """A random true pair over smooth terrain of the configured relative relief.

    Parameters
    ----------
    config : PlotterConfig, optional
    rng : numpy.random.Generator
        Source of the terrain and of the true elements.
    start_c : (float, float)
        Range of abs(ω), abs(φ), abs(κ) of the right image, centesimal minutes (random signs):
        with the plotter at zero these are the first corrections (Kovarik: 100–150 c).
    start_mm : (float, float)
        Range of abs(by), abs(bz), machine mm.
    elements : array_like, shape (5,), optional
        True by, bz (mm), ω, φ, κ (rad) instead of random ones.
    n_hills : int
        Number of Gaussian hills making up the terrain.

    Returns
    -------
    TruePair
    """
    cfg = (config or PlotterConfig()).check()
    b, d = cfg.model_base, cfg.ordinate * cfg.scale
    m = max(int(n_hills), 1)
    centres = np.column_stack(
        [rng.uniform(-0.2 * b, 1.2 * b, m), rng.uniform(-1.2 * d, 1.2 * d, m)]
    )
    widths = rng.uniform(0.3, 0.8, m) * b
    weights = rng.uniform(-1, 1, m)
    terrain = {"centres": centres, "widths": widths, "weights": weights, "offset": 0.0, "gain": 1.0}
    pair = TruePair(cfg, np.zeros(5), terrain)
    # normalise: heights span exactly relief × H over the model area
    X, Y = np.meshgrid(np.linspace(0, b, 41), np.linspace(-d, d, 41))
    H = cfg.projection_distance
    f = (pair.height(X, Y) + H) / (cfg.relief * H) if cfg.relief > 0 else np.zeros(1)
    span = float(f.max() - f.min())
    if cfg.relief > 0 and span > 0:
        terrain["offset"] = float(0.5 * (f.max() + f.min()))
        terrain["gain"] = 1.0 / span
    if elements is None:
        s = rng.choice([-1.0, 1.0], 5)
        e = np.empty(5)
        e[:2] = s[:2] * rng.uniform(*start_mm, 2)
        e[2:] = s[2:] * rng.uniform(*start_c, 3) / RHO_C
    else:
        e = np.asarray(elements, dtype=float).reshape(5)
    pair.elements = e
    return pair


def config_with(config: PlotterConfig | None = None, **changes) -> PlotterConfig:
    """A checked copy of ``config`` with some fields changed."""
    return replace(config or PlotterConfig(), **changes).check()
