"""The data model: a :class:`Block` of cameras, images, points and observations.

Everything is a structure of arrays so that thousands of images and hundreds of
thousands of observations are handled without Python loops. String ids are mapped to
integer indices at the edges (:meth:`Block.image_index`, :meth:`Block.point_index`).

Units: object coordinates in m, image coordinates and their σ in mm, angles in rad
(rotation sequence in :attr:`Block.sequence`, see :mod:`orientviz.rotation`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import project
from ..errors import InputError
from ..rotation import check_sequence, matrix_from_opk

F64 = NDArray[np.float64]

#: Point roles. Control points carry known coordinates (fixed or weighted), check points
#: carry known coordinates that are *not* used in the adjustment, tie points none.
ROLES: tuple[str, ...] = ("tie", "control", "check")
TIE, CONTROL, CHECK = 0, 1, 2


# --------------------------------------------------------------------------- validators
def check_array(
    value: ArrayLike, shape: tuple[int | None, ...], name: str, *, finite: bool = True
) -> F64:
    """Return ``value`` as a float array of the given shape or raise ``ValueError``.

    Parameters
    ----------
    value : array_like
        The input.
    shape : tuple of int or None
        Expected shape; ``None`` matches any length along that axis.
    name : str
        Name used in the message.
    finite : bool, default True
        Reject NaN and inf.

    Raises
    ------
    ValueError
        ``"<name>: expected shape (n, 3), got (4, 2)"``.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(value).__name__}") from exc
    ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
    if not ok:
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if finite and not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name}: expected finite numbers, got {arr[tuple(bad)]} at {tuple(bad)}")
    return arr


def check_points(value: ArrayLike, name: str = "points") -> F64:
    """Object points as an (n, 3) float array in m."""
    return check_array(value, (None, 3), name)


def check_image_points(value: ArrayLike, name: str = "image points") -> F64:
    """Image points as an (n, 2) float array in mm."""
    return check_array(value, (None, 2), name)


def index_ids(ids: list[str], what: str) -> dict[str, int]:
    """Map string ids to indices, rejecting duplicates (the first one repeated is named)."""
    keys = list(map(str, ids))
    out = dict(zip(keys, range(len(keys))))
    if len(out) != len(keys):
        seen: set[str] = set()
        for key in keys:
            if key in seen:
                raise InputError(f"duplicate {what} id {key!r}")
            seen.add(key)
    return out


# --------------------------------------------------------------------------- tables
@dataclass
class Cameras:
    """Interior orientations: ``c``, ``x0``, ``y0`` (mm), ``format_mm`` (n, 2)."""

    ids: list[str]
    c: F64
    x0: F64
    y0: F64
    format_mm: F64
    #: name of the additional-parameter set per camera ("" = none)
    ap_set: list[str] = field(default_factory=list)
    #: per camera what a problem file says the bundle estimates of it ({} = nothing):
    #: a lens model or an additional-parameter set (:mod:`orientviz.bundle._block_cameras`)
    model: list[dict] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.ids)


@dataclass
class Images:
    """Exterior orientations: ``camera`` index, ``X0`` (n, 3) m, ``angles`` (n, 3) rad.

    ``strip`` groups images (−1 = none). ``X0_obs``/``X0_sigma`` and
    ``angles_obs``/``angles_sigma`` hold optional observed positions and attitudes
    (NaN = not observed).
    """

    ids: list[str]
    camera: NDArray[np.int64]
    X0: F64
    angles: F64
    strip: NDArray[np.int64]
    X0_obs: F64
    X0_sigma: F64
    angles_obs: F64
    angles_sigma: F64

    def __len__(self) -> int:
        return len(self.ids)


@dataclass
class Points:
    """Object points: ``xyz`` (n, 3) m current values; ``role`` (0 tie, 1 control, 2 check).

    ``xyz_known`` holds the given coordinates of control and check points (NaN where
    unknown); ``sigma`` (n, 3) their a-priori σ in m: 0 = fixed, > 0 = weighted,
    NaN/inf = the coordinate is not given (e.g. a height-only control point).
    """

    ids: list[str]
    xyz: F64
    role: NDArray[np.int8]
    xyz_known: F64
    sigma: F64

    def __len__(self) -> int:
        return len(self.ids)


@dataclass
class Observations:
    """Image observations: ``image`` and ``point`` indices, ``xy`` (n, 2) mm, ``sigma`` (n, 2) mm."""

    image: NDArray[np.int64]
    point: NDArray[np.int64]
    xy: F64
    sigma: F64

    def __len__(self) -> int:
        return int(self.image.shape[0])


@dataclass
class Block:
    """A photogrammetric block: the tables plus the conventions they are expressed in.

    Build one with :meth:`Block.from_arrays` (validated) or the simulators and loaders.

    Attributes
    ----------
    cameras, images, points, observations
        The tables.
    sequence : {"opk", "pok"}
        Rotation sequence of ``images.angles``.
    meta : dict
        Free-form metadata (name, source file, units of the source, …).
    """

    cameras: Cameras
    images: Images
    points: Points
    observations: Observations
    sequence: str = "opk"
    meta: dict[str, Any] = field(default_factory=dict)

    # ---------------------------------------------------------------- construction
    @classmethod
    def from_arrays(
        cls,
        *,
        camera_c: ArrayLike,
        image_camera: ArrayLike,
        X0: ArrayLike,
        angles: ArrayLike,
        xyz: ArrayLike,
        obs_image: ArrayLike,
        obs_point: ArrayLike,
        obs_xy: ArrayLike,
        obs_sigma: ArrayLike = 0.005,
        camera_x0: ArrayLike | None = None,
        camera_y0: ArrayLike | None = None,
        camera_format_mm: ArrayLike = (230.0, 230.0),
        camera_ids: list[str] | None = None,
        image_ids: list[str] | None = None,
        point_ids: list[str] | None = None,
        role: ArrayLike | None = None,
        xyz_known: ArrayLike | None = None,
        point_sigma: ArrayLike | None = None,
        strip: ArrayLike | None = None,
        sequence: str = "opk",
        meta: dict[str, Any] | None = None,
    ) -> Block:
        """Build and validate a block from plain arrays.

        Parameters
        ----------
        camera_c : array_like, shape (k,)
            Principal distances in mm.
        image_camera : array_like of int, shape (m,)
            Camera index per image.
        X0 : array_like, shape (m, 3)
            Projection centres in m (approximate or true).
        angles : array_like, shape (m, 3)
            ω, φ, κ in rad, sequence ``sequence``.
        xyz : array_like, shape (p, 3)
            Object points in m (approximations for tie points).
        obs_image, obs_point : array_like of int, shape (n,)
            Image and point index per observation.
        obs_xy : array_like, shape (n, 2)
            Observed image coordinates in mm.
        obs_sigma : float or array_like, shape (n,) or (n, 2)
            A-priori σ of the image coordinates in mm (default 5 µm).
        role : array_like of int or str, shape (p,), optional
            0/"tie", 1/"control", 2/"check"; default all tie.
        xyz_known : array_like, shape (p, 3), optional
            Given coordinates of control/check points in m; default ``xyz`` for them.
        point_sigma : float or array_like, shape (p, 3), optional
            A-priori σ of control coordinates in m (0 = fixed; default 0).
        """
        sequence = check_sequence(sequence)
        c = np.atleast_1d(check_array(camera_c, (None,), "camera c"))
        k = c.shape[0]
        x0 = np.zeros(k) if camera_x0 is None else check_array(camera_x0, (k,), "camera x0")
        y0 = np.zeros(k) if camera_y0 is None else check_array(camera_y0, (k,), "camera y0")
        fmt = np.broadcast_to(np.asarray(camera_format_mm, dtype=float), (k, 2)).copy()
        X0 = check_points(X0, "images X0")
        m = X0.shape[0]
        angles = check_array(angles, (m, 3), "images angles")
        cam = np.asarray(image_camera, dtype=np.int64).reshape(-1)
        if cam.shape != (m,):
            raise ValueError(f"image camera: expected shape ({m},), got {cam.shape}")
        if m and (cam.min() < 0 or cam.max() >= k):
            raise ValueError(
                f"image camera: expected indices in [0, {k}), got {cam.min()}..{cam.max()}"
            )
        xyz = check_points(xyz, "points xyz")
        p = xyz.shape[0]
        if role is None:
            role_arr = np.zeros(p, dtype=np.int8)
        else:
            codes = np.asarray(role)
            if codes.dtype.kind in "iu":  # integer codes: no per-point Python loop
                codes = codes.reshape(-1).astype(np.int64)
            else:
                codes = np.array(
                    [ROLES.index(r) if isinstance(r, str) else int(r) for r in codes.ravel()],
                    dtype=np.int64,
                )
            if codes.shape != (p,) or (p and (codes.min() < 0 or codes.max() > 2)):
                raise ValueError(f"point role: expected {p} roles out of {ROLES}, got {role}")
            role_arr = codes.astype(np.int8)
        if xyz_known is None:
            known = np.where((role_arr > 0)[:, None], xyz, np.nan)
        else:
            known = check_array(xyz_known, (p, 3), "points xyz_known", finite=False)
        sig = np.broadcast_to(
            np.asarray(0.0 if point_sigma is None else point_sigma, dtype=float), (p, 3)
        ).copy()
        oi = np.asarray(obs_image, dtype=np.int64).reshape(-1)
        op = np.asarray(obs_point, dtype=np.int64).reshape(-1)
        n = oi.shape[0]
        oxy = check_array(obs_xy, (n, 2), "observations xy")
        if op.shape != (n,):
            raise ValueError(f"observations point: expected shape ({n},), got {op.shape}")
        if n and (oi.min() < 0 or oi.max() >= m):
            raise ValueError(
                f"observations image: expected indices in [0, {m}), got {oi.min()}..{oi.max()}"
            )
        if n and (op.min() < 0 or op.max() >= p):
            raise ValueError(
                f"observations point: expected indices in [0, {p}), got {op.min()}..{op.max()}"
            )
        osig = np.asarray(obs_sigma, dtype=float)
        osig = np.broadcast_to(osig[:, None] if osig.ndim == 1 else osig, (n, 2)).copy()
        if not np.all(np.isfinite(osig)) or np.any(osig <= 0):
            raise ValueError("observations sigma: expected positive finite σ in mm")
        strip_arr = (
            np.full(m, -1, dtype=np.int64) if strip is None else np.asarray(strip, dtype=np.int64)
        )
        ids = lambda given, count, prefix: (
            list(map(str, given)) if given is not None else [f"{prefix}{i}" for i in range(count)]
        )
        block = cls(
            cameras=Cameras(ids(camera_ids, k, "cam"), c, x0, y0, fmt, [""] * k),
            images=Images(
                ids(image_ids, m, "img"),
                cam,
                X0,
                angles,
                strip_arr,
                np.full((m, 3), np.nan),
                np.full((m, 3), np.nan),
                np.full((m, 3), np.nan),
                np.full((m, 3), np.nan),
            ),
            points=Points(ids(point_ids, p, "pt"), xyz, role_arr, known, sig),
            observations=Observations(oi, op, oxy, osig),
            sequence=sequence,
            meta=dict(meta or {}),
        )
        # ids numbered here are distinct: only given ones are checked for repeats
        given = (camera_ids is not None, image_ids is not None, point_ids is not None)
        return block._validate(given)

    def validate(self) -> Block:
        """Check ids for duplicates and array shapes for consistency; return ``self``."""
        return self._validate((True, True, True))

    def _validate(self, check_ids: tuple[bool, bool, bool]) -> Block:
        """:meth:`validate`, the ids of cameras, images, points checked where asked."""
        for ids, what, check in zip(
            (self.cameras.ids, self.images.ids, self.points.ids), ("camera", "image", "point"),
            check_ids,
        ):  # fmt: skip
            if check and len(set(map(str, ids))) != len(ids):
                index_ids(ids, what)  # names the first repeated id
        m, p, n = len(self.images), len(self.points), len(self.observations)
        for name, arr, shape in (
            ("images.X0", self.images.X0, (m, 3)),
            ("images.angles", self.images.angles, (m, 3)),
            ("points.xyz", self.points.xyz, (p, 3)),
            ("points.sigma", self.points.sigma, (p, 3)),
            ("observations.xy", self.observations.xy, (n, 2)),
            ("observations.sigma", self.observations.sigma, (n, 2)),
        ):
            if arr.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {arr.shape}")
        return self

    # ---------------------------------------------------------------- id mapping
    def image_index(self, ids: str | list[str]) -> int | NDArray[np.int64]:
        """Index (or indices) of image id(s); ``KeyError`` names an unknown id."""
        return _lookup(self.images.ids, ids, "image")

    def point_index(self, ids: str | list[str]) -> int | NDArray[np.int64]:
        """Index (or indices) of point id(s)."""
        return _lookup(self.points.ids, ids, "point")

    # ---------------------------------------------------------------- derived data
    @property
    def n_images(self) -> int:
        return len(self.images)

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_observations(self) -> int:
        return len(self.observations)

    def rotations(self) -> F64:
        """Rotation matrices (m, 3, 3) of all images (image → object)."""
        a = self.images.angles
        return matrix_from_opk(a[:, 0], a[:, 1], a[:, 2], self.sequence)

    def rays_per_point(self) -> NDArray[np.int64]:
        """Number of image observations of each point."""
        return np.bincount(self.observations.point, minlength=self.n_points)

    def points_per_image(self) -> NDArray[np.int64]:
        """Number of observed points in each image."""
        return np.bincount(self.observations.image, minlength=self.n_images)

    def project(self) -> F64:
        """Image coordinates (n, 2) mm computed from the current orientations and points."""
        obs = self.observations
        cam = self.images.camera[obs.image]
        R = self.rotations()[obs.image]
        return project(
            self.points.xyz[obs.point],
            self.images.X0[obs.image],
            R,
            self.cameras.c[cam],
            self.cameras.x0[cam],
            self.cameras.y0[cam],
        )

    def residuals(self) -> F64:
        """Observed minus computed image coordinates (n, 2) in mm, v = l − f(x).

        Note: the engine reports residuals with the adjustment sign convention
        v = f(x̂) − l (corrections to the observations); this helper is the plain
        misclosure of the current state.
        """
        return self.observations.xy - self.project()

    def copy(self) -> Block:
        """Deep copy of all tables."""
        import copy

        # lists of ids copied as lists (their str items are immutable: what deepcopy
        # gives, without its per-item dispatch)
        memo: dict[int, Any] = {}
        for ids in (self.cameras.ids, self.images.ids, self.points.ids):
            if type(ids) is list and set(map(type, ids)) <= {str}:
                memo[id(ids)] = list(ids)
        return copy.deepcopy(self, memo)

    def with_(self, **changes: Any) -> Block:
        """Shallow copy with some tables replaced (``dataclasses.replace``)."""
        return replace(self, **changes)

    def take(
        self,
        images: ArrayLike | None = None,
        points: ArrayLike | None = None,
        observations: ArrayLike | None = None,
    ) -> Block:
        """The sub-block of some rows of the tables, renumbered (copies; cameras kept).

        Parameters
        ----------
        images, points, observations : array_like of int, optional
            Row indices into this block's tables (None = all rows). Every kept observation
            must refer to a kept image and a kept point.
        """
        idx = {
            name: np.arange(len(getattr(self, name)))
            if rows is None
            else np.asarray(rows, np.int64)
            for name, rows in (
                ("images", images),
                ("points", points),
                ("observations", observations),
            )
        }
        O = _take_rows(self.observations, idx["observations"])
        for name, col in (("images", "image"), ("points", "point")):
            new = np.full(len(getattr(self, name)), -1, np.int64)
            new[idx[name]] = np.arange(idx[name].size)
            setattr(O, col, new[getattr(O, col)])
        return self.with_(
            images=_take_rows(self.images, idx["images"]),
            points=_take_rows(self.points, idx["points"]),
            observations=O,
        )

    def summary(self) -> str:
        """One line: counts of cameras, images, points by role and image points (rays)."""
        r = np.bincount(self.points.role, minlength=3)
        return (
            f"{len(self.cameras)} camera(s), {self.n_images} images, {self.n_points} points "
            f"({r[0]} tie, {r[1]} control, {r[2]} check), {self.n_observations} image points"
        )


def _take_rows(table: Any, idx: NDArray[np.int64]) -> Any:
    """Rows ``idx`` of a structure-of-arrays table (lists by index, arrays by fancy index)."""
    out = {}
    for f in fields(table):
        v = getattr(table, f.name)
        if isinstance(v, list):
            out[f.name] = [v[i] for i in idx] if len(v) == len(table) else list(v)
        else:
            out[f.name] = np.asarray(v)[idx].copy()
    return replace(table, **out)


def _lookup(table: list[str], ids: str | list[str], what: str):
    mapping = {k: i for i, k in enumerate(table)}
    if isinstance(ids, str):
        if ids not in mapping:
            raise KeyError(f"unknown {what} id {ids!r}")
        return mapping[ids]
    missing = [i for i in ids if i not in mapping]
    if missing:
        raise KeyError(f"unknown {what} id(s) {missing[:5]!r}")
    return np.array([mapping[i] for i in ids], dtype=np.int64)
