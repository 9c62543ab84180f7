"""Scene content of a block, as plain arrays: what the viewer draws, without viser.

:class:`BlockGeometry` turns a :class:`~orientviz.viewer.state.BlockState` into the
arrays of the scene nodes (frustum poses, points by role, rays, residual vectors,
strips, model footprints, error ellipsoids), all in the scene frame
(object coordinates − :attr:`SceneFrame.origin`, m). :mod:`orientviz.viewer.scene`
only hands these arrays to viser.

Residual vectors: each observation draws a segment from its object point towards the
place where the *observed* ray passes at the point's depth
(:func:`~orientviz.viewer.geometry.residual_offsets`), multiplied by the exaggeration.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, TIE
from ..plausibility import is_aerial
from . import block_scale as bs
from . import geometry as g
from . import precision_view as pv
from .state import BlockState

F64 = NDArray[np.float64]

#: RGB colours (0-255) readable on viser's light background.
COLORS: dict[str, tuple[int, int, int]] = {
    "tie": (70, 80, 100),
    "control": (220, 40, 40),
    "check": (20, 150, 60),
    "frustum": (40, 70, 160),
    "selected": (0, 230, 230),
    "ray": (120, 150, 200),
    "ray_selected": (0, 230, 230),
    "strip": (110, 60, 160),
    "model": (150, 150, 150),
    "ellipsoid": (230, 80, 200),
    "station": (40, 150, 210),
    "deformation": (0, 140, 170),
    "scale_bar": (30, 30, 30),
}

#: Point-cloud node name per role.
ROLE_NODES = {TIE: "tie", CONTROL: "control", CHECK: "check"}

#: ``|w|`` (or ``|v|/σ``) at which the residual colour ramp saturates (red).
SCORE_RED: float = 4.0

#: The smallest frustum depth of a non-aerial block, as a share of the scene's size.
FRUSTUM_MIN: float = 0.015

#: Level of detail of large blocks: at most this many residual vectors are drawn (those
#: with the largest scores; thick lines cost a renderer without GPU most of a frame) ...
RESIDUAL_LIMIT: int = 5_000
#: ... and at most this many rays when all rays are shown (every k-th ray).
RAY_LIMIT: int = 20_000
#: ... and at most this many rays of the selected image (every k-th of its rays): the
#: thousands of rays of one image of a dense reconstruction would paint a solid fan
#: over its points.
SELECTED_RAY_LIMIT: int = 300


class BlockGeometry:
    """Arrays for the scene of a block, in the scene frame.

    Parameters
    ----------
    state : BlockState
        The block being shown.
    frame : SceneFrame, optional
        Scene frame; by default centred on the block's points and projection centres.

    Attributes
    ----------
    frame : SceneFrame
    aerial : bool
        The block is aerial (a real length unit, images looking down,
        :func:`orientviz.plausibility.is_aerial`).
    spacing : float
        Typical distance between neighbouring object points (m); sets point sizes.
    height : float
        Typical distance from the cameras to the points (m): an aerial block's height
        above the points, else the median depth of the observed points along the
        cameras' axes (:func:`~orientviz.viewer.block_scale.viewing_depth`); sets the
        frustum depth, the sliders' range and the scale bar's image scale.
    up, view : ndarray, shape (3,)
        The scene's up direction and the first view's direction (unit vectors; Z and an
        oblique view from the south for an aerial block,
        :mod:`orientviz.viewer.block_scale`).
    frustum_depth : float
        Drawn depth of the frustums (m).
    point_size : float
        Point size in scene units (m).
    """

    def __init__(self, state: BlockState, frame: g.SceneFrame | None = None) -> None:
        self.state = state
        b = state.block
        R = b.rotations()
        #: an aerial block (real unit, images looking down): Z up, heights above ground
        self.aerial = is_aerial(b, state.units.length)
        both = np.vstack([b.points.xyz, b.images.X0]) if b.n_points else b.images.X0
        self.frame = frame or g.SceneFrame.around(both)
        self.spacing = g.typical_spacing(b.points.xyz) if b.n_points > 1 else self.frame.size / 10
        #: the scene's up (3,) and the first view's direction (3,), unit vectors
        self.up = bs.up_direction(R, self.aerial)
        self.view = np.array([0.3, 0.85, -0.65]) if self.aerial else bs.view_direction(self.up, R)
        if self.aerial:
            h = float(np.median(b.images.X0[:, 2]) - np.median(b.points.xyz[:, 2]))
            cam_sp = g.typical_spacing(b.images.X0) if b.n_images > 1 else h
        else:  # any frame: the depth of the points along the cameras' axes
            h = bs.viewing_depth(b, R) if b.n_points and b.n_images else float("nan")
            cam_sp = bs.camera_spacing(b.images.X0)
        self.height = h if h > 0 else self.frame.size / 5
        cam_sp = cam_sp if cam_sp > 0 else self.height
        # about a quarter of the base between neighbouring cameras, never larger than H/4;
        # a reconstruction's cameras close together (a walk, a drive): at least 1.5 % of
        # the scene, so that the first view shows frustums, not dots
        depth = min(0.25 * self.height, 0.6 * cam_sp)
        if not self.aerial:
            depth = min(max(depth, FRUSTUM_MIN * self.frame.size), 0.25 * self.height)
        self.frustum_depth = float(depth)
        self.point_size = float(np.clip(0.12 * self.spacing, 1e-6, None))
        n = b.n_observations
        #: (drawn, all) residual vectors and rays of "all rays" (level of detail)
        self.residuals_drawn = (min(n, RESIDUAL_LIMIT), n)
        self.ray_step = max(1, int(np.ceil(n / RAY_LIMIT)))

    # ------------------------------------------------------------------ cameras
    def strip_of_images(self) -> NDArray[np.int64]:
        """Strip index of each image (−1 = none)."""
        return self.state.block.images.strip

    def frustum_poses(self) -> tuple[F64, F64]:
        """Positions (m, 3) in the scene frame and viser quaternions (m, 4) of the frustums.

        The quaternion is that of R·diag(1, −1, −1): viser's camera frame (OpenCV: x
        right, y down, z forward) from orientviz's image frame (x, y, looking along −z).
        """
        b = self.state.block
        return self.frame.to_scene(b.images.X0), g.wxyz_from_matrix(b.rotations() @ g.FLIP)

    def frustum_corners(self, images: NDArray[np.int64] | None = None) -> F64:
        """Apex and corners (k, 5, 3) of the frustums of ``images`` (default all), scene frame."""
        b = self.state.block
        idx = np.arange(b.n_images) if images is None else np.asarray(images).reshape(-1)
        cam = b.images.camera[idx]
        C = g.frustum_corners(
            b.images.X0[idx],
            b.rotations()[idx],
            b.cameras.c[cam],
            b.cameras.format_mm[cam],
            self.frustum_depth,
        )
        return self.frame.to_scene(C)

    def viser_frustum_args(
        self, camera: int = 0
    ) -> tuple[float, float, tuple[float, float, float]]:
        """(fov, aspect, scale) for viser's frustum of camera ``camera`` at :attr:`frustum_depth`."""
        cams = self.state.block.cameras
        return g.viser_frustum(cams.c[camera], cams.format_mm[camera], self.frustum_depth)

    # ------------------------------------------------------------------ points
    def points_by_role(self) -> dict[str, F64]:
        """Scene coordinates (k, 3) of tie, control and check points."""
        b = self.state.block
        P = self.frame.to_scene(b.points.xyz)
        return {name: P[b.points.role == r] for r, name in ROLE_NODES.items()}

    # ------------------------------------------------------------------ rays
    def selected_ray_step(self, image: int) -> tuple[int, int]:
        """(k, n): every k-th of the n rays of ``image`` is drawn (at most
        :data:`SELECTED_RAY_LIMIT`)."""
        n = int(np.count_nonzero(self.state.block.observations.image == image))
        return max(1, int(np.ceil(n / SELECTED_RAY_LIMIT))), n

    def rays(self, image: int | None = None) -> F64:
        """Ray segments projection centre → point (k, 2, 3), of one image or all (every
        :attr:`ray_step`-th ray of a block with more than :data:`RAY_LIMIT` rays; every
        :meth:`selected_ray_step`-th ray of an image with more than
        :data:`SELECTED_RAY_LIMIT`)."""
        b = self.state.block
        o = b.observations
        if image is None:
            sel = slice(None, None, self.ray_step)
        else:
            sel = np.flatnonzero(o.image == image)[:: self.selected_ray_step(image)[0]]
        return self.frame.to_scene(
            g.ray_segments(b.images.X0[o.image[sel]], b.points.xyz[o.point[sel]])
        )

    # ------------------------------------------------------------------ residuals
    def residual_offsets(self, misclosure: F64 | None = None, keep: object = slice(None)) -> F64:
        """Object-space offsets (k, 3) in m of the observed rays from their points (the
        observations ``keep``, default all; ``misclosure`` (k, 2) mm of those).

        An aerial block: at each point's depth. Other blocks, whose points lie at depths
        that differ by orders (a reconstruction's far points): at the typical depth
        :attr:`height` for every point, so that a vector's length is its image residual
        at one scale, as the scale bar says.
        """
        b = self.state.block
        o = b.observations
        e = self.state.misclosure()[keep] if misclosure is None else misclosure
        im = o.image[keep]
        P, X0, R = b.points.xyz[o.point[keep]], b.images.X0[im], b.rotations()[im]
        off = g.residual_offsets(P, X0, R, b.cameras.c[b.images.camera[im]], e)
        if self.aerial:
            return off
        depth = -np.einsum("ni,ni->n", P - X0, R[:, :, 2])  # along the camera's axis
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(depth > 0, self.height / depth, 1.0)
        return off * f[:, None]

    def residuals(
        self, exaggeration: float, misclosure: F64 | None = None, scores: F64 | None = None
    ) -> tuple[F64, NDArray[np.uint8]]:
        """Residual vectors (k, 2, 3) in the scene frame, and their colours (k, 2, 3) uint8.

        All n observations' vectors, or above :data:`RESIDUAL_LIMIT` the ``RESIDUAL_LIMIT``
        with the largest scores (:attr:`residuals_drawn`).

        Parameters
        ----------
        exaggeration : float
            Factor applied to the object-space offsets.
        misclosure : ndarray, shape (n, 2), optional
            Precomputed misclosures in mm (default: computed from the state).
        scores : ndarray, shape (n,), optional
            Precomputed scores (default: :meth:`BlockState.scores`) for the colours.
        """
        b = self.state.block
        e = self.state.misclosure() if misclosure is None else misclosure
        s = self.state.scores(e)[0] if scores is None else scores
        keep = slice(None)
        if s.shape[0] > RESIDUAL_LIMIT:  # level of detail: the largest scores
            keep = np.argpartition(-np.nan_to_num(s, nan=-1.0), RESIDUAL_LIMIT - 1)[:RESIDUAL_LIMIT]
            keep.sort()
            e, s = e[keep], s[keep]
        off = self.residual_offsets(e, keep) * exaggeration
        # a vector longer than the scene is drawn as long as the scene (far from the
        # solution, e.g. the approximations replayed at the adjusted state's scale)
        length = np.linalg.norm(off, axis=1)
        cap = self.frame.size
        off = np.where(
            (length > cap)[:, None], off * (cap / np.maximum(length, 1e-300))[:, None], off
        )
        seg = g.vector_segments(self.frame.to_scene(b.points.xyz[b.observations.point[keep]]), off)
        col = g.ramp(s, SCORE_RED)
        return seg, np.repeat(col[:, None, :], 2, axis=1)

    def auto_exaggeration(self, misclosure: F64 | None = None) -> float:
        """An exaggeration that draws the median residual about a third of a point spacing."""
        off = np.linalg.norm(self.residual_offsets(misclosure), axis=1)
        med = float(np.median(off)) if off.size else 0.0
        if med <= 0:
            return 1.0
        k = float(np.clip(0.33 * self.spacing / med, 1.0, 1e6))  # exact data: at most 10⁶
        return float(10 ** (np.round(np.log10(k) * 4) / 4))

    def scale_bar(self, exaggeration: float) -> tuple[F64, F64, str]:
        """The residuals' scale bar: segments (k, 2, 3), label position (3,) and text.

        The bar stands for a round object-space offset (1, 2 or 5 × 10ⁿ m, or model
        units) drawn at ``exaggeration``, about two point spacings long, in front of the
        points (scene frame); the label also gives the offset in the image at the median
        image scale (µm, or px for a pixel file: :class:`~orientviz.viewer.view_units.
        ViewUnits`).
        """
        b = self.state.block
        target = 2.0 * self.spacing / max(float(exaggeration), 1e-300)
        e = np.floor(np.log10(target))
        m = target / 10**e
        value = float((5 if m >= 5 else 2 if m >= 2 else 1) * 10**e)
        length = value * exaggeration
        P = self.frame.to_scene(b.points.xyz) if b.n_points else np.zeros((1, 3))
        lo, hi = P.min(axis=0), P.max(axis=0)
        mid = 0.5 * (lo[0] + hi[0]) - 0.5 * length  # centred in front of the points
        start = np.array([mid, lo[1] - 0.08 * (hi[1] - lo[1] + self.spacing), lo[2]])
        end = start + [length, 0.0, 0.0]
        tick = np.array([0.0, 0.0, 0.25 * self.spacing])
        seg = np.array([[start, end], [start - tick, start + tick], [end - tick, end + tick]])
        depth = self.height if b.n_images else 1.0
        c = float(np.median(b.cameras.c)) if b.cameras.c.size else 1.0
        u = self.state.units
        image = u.image_text(value * c / depth)  # object length → mm → µm or px in the image
        text = (
            f"residuals ×{exaggeration:.3g}: bar = {u.length_text(value)} at the object "
            f"≈ {image} in the image"
        )
        return seg, (start + end) / 2 - 2 * tick, text

    # ------------------------------------------------------------------ strips, models
    def strip_lines(self) -> F64:
        """Segments joining consecutive projection centres of each strip (k, 2, 3)."""
        b = self.state.block
        return self.frame.to_scene(g.polyline_segments(b.images.X0, b.images.strip))

    def model_outlines(self) -> F64:
        """Ground outlines of the models (consecutive images of a strip) as segments.

        A model's outline is the overlap of its two image footprints on the plane of the
        median point height, approximated by the axis-aligned intersection of the two
        footprints' bounding rectangles (exact for vertical images flown along X or Y).
        """
        b = self.state.block
        if b.n_points == 0:
            return np.zeros((0, 2, 3))
        z = float(np.median(b.points.xyz[:, 2]))
        cam = b.images.camera
        fp = g.footprints(b.images.X0, b.rotations(), b.cameras.c[cam], b.cameras.format_mm[cam], z)
        strip = b.images.strip
        order = np.argsort(strip, kind="stable")
        left, right = order[:-1], order[1:]
        keep = (strip[left] == strip[right]) & (strip[left] >= 0)
        left, right = left[keep], right[keep]
        lo = np.maximum(np.nanmin(fp[left, :, :2], axis=1), np.nanmin(fp[right, :, :2], axis=1))
        hi = np.minimum(np.nanmax(fp[left, :, :2], axis=1), np.nanmax(fp[right, :, :2], axis=1))
        ok = np.all(hi > lo, axis=1)
        lo, hi = lo[ok], hi[ok]
        quad = np.empty((lo.shape[0], 4, 3))
        quad[:, :, 2] = z
        quad[:, 0, :2] = lo
        quad[:, 1, 0], quad[:, 1, 1] = hi[:, 0], lo[:, 1]
        quad[:, 2, :2] = hi
        quad[:, 3, 0], quad[:, 3, 1] = lo[:, 0], hi[:, 1]
        # shrink slightly so neighbouring models stay apart
        centre = quad.mean(axis=1, keepdims=True)
        quad = centre + 0.97 * (quad - centre)
        return self.frame.to_scene(g.loop_segments(quad))

    # ------------------------------------------------------------------ precision
    def shown_points(self, mode: str, image: int) -> NDArray[np.int64]:
        """Points whose ellipsoids are drawn: ``"all"``, ``"selected image"`` or ``"none"``."""
        b = self.state.block
        if mode == "all":
            return np.arange(b.n_points)
        if mode == "selected image":
            return np.unique(b.observations.point[b.observations.image == image])
        return np.zeros(0, np.int64)

    def ellipsoid_gain(self, k: float) -> float:
        """Exaggeration of the ellipsoids for the whole adjustment (see :func:`pv.auto_gain`).

        From up to 2 000 points spread over the block, so that it does not change when
        another image is selected.
        """
        p = self.state.block.n_points
        sample = np.linspace(0, p - 1, min(p, 2000)).astype(np.int64) if p else np.zeros(0, int)
        idx, cov = pv.point_covariances(self.state.result, sample)
        if idx.size == 0:
            idx, cov = pv.station_covariances(
                self.state.result, np.arange(self.state.block.n_images)
            )
        return pv.auto_gain(cov, k, self.spacing)

    def station_gain(self, k: float) -> float:
        """Exaggeration of the projection centres' ellipsoids: the median drawn a third of
        the frustum depth (their own scale: stations and points differ by orders)."""
        idx, cov = pv.station_covariances(self.state.result, np.arange(self.state.block.n_images))
        return pv.auto_gain(cov, k, self.frustum_depth)

    def ellipsoids(
        self, points: NDArray[np.int64], k: float, gain: float, subdivisions: int = 1
    ) -> tuple[F64, NDArray[np.int32]] | None:
        """One mesh (vertices, faces) of the confidence ellipsoids of ``points``.

        Scale k (:func:`~orientviz.viewer.precision_view.confidence_factor`) × ``gain``;
        at most :data:`~orientviz.viewer.precision_view.ELLIPSOID_LIMIT` (the largest).
        None if none of them has a covariance.
        """
        idx, S = pv.largest_first(*pv.point_covariances(self.state.result, points))
        if idx.size == 0:
            return None
        centers = self.frame.to_scene(self.state.block.points.xyz[idx])
        return g.ellipsoid_mesh(centers, S, k * gain, subdivisions)

    def station_ellipsoids(
        self, images: NDArray[np.int64], k: float, gain: float
    ) -> tuple[F64, NDArray[np.int32]] | None:
        """One mesh of the confidence ellipsoids of the projection centres of ``images``."""
        idx, S = pv.station_covariances(self.state.result, images)
        if idx.size == 0:
            return None
        centers = self.frame.to_scene(self.state.block.images.X0[idx])
        return g.ellipsoid_mesh(centers, S, k * gain, 2)

    # ------------------------------------------------------------------ camera
    def default_camera(self) -> tuple[F64, F64]:
        """(position, look_at) in the scene frame: an oblique view that frames the points
        and the cameras left of the GUI panel (:func:`~orientviz.viewer.geometry.framing`)."""
        b = self.state.block
        if self.aerial:
            P = self.frame.to_scene(np.vstack([b.points.xyz, b.images.X0]))
            return g.framing(P)
        # the points without far strays and every camera (few, and what is debugged)
        P = np.vstack([g.core_points(b.points.xyz), g.core_points(b.images.X0)])
        return g.framing(self.frame.to_scene(P), self.view, up=self.up, strays=False)
