"""orientviz — learn, teach and visually debug photogrammetric orientation.

``import orientviz as ov`` gives the front door: the names a first script needs,
loaded on first use (``import orientviz`` itself loads neither numpy nor any
solver, plotting or GUI library)::

    import numpy as np
    import orientviz as ov

    sim = ov.simulate_block(2, 6, rng=np.random.default_rng(1))
    adj = ov.bundle_adjust(sim.block)
    print(adj.summary())
    ov.view((sim.block, adj))          # the 3D viewer; viser is imported only here

The face, by task (each name links to where it lives and is documented):

* problem files and data: :func:`~orientviz.io.problem.load_problem`,
  :func:`~orientviz.io.problem.save_problem`, :func:`~orientviz.io.datasets.load_dataset`,
  :func:`~orientviz.io.solve.solve_problem`, :func:`~orientviz.io.colmap.read_colmap`,
  :func:`~orientviz.report.write_report`, :class:`~orientviz.io.problem.Problem`;
* conventions: :func:`~orientviz.units.to_rad`, :func:`~orientviz.units.from_rad`,
  :func:`~orientviz.rotation.matrix_from_opk`, :func:`~orientviz.rotation.opk_from_matrix`,
  :class:`~orientviz.camera.FrameCamera`, :func:`~orientviz.camera.project`;
* the block (the set of images and points): :class:`~orientviz.block.Block`, the point
  roles ``TIE``, ``CONTROL``, ``CHECK`` (``block.points.role``: 0, 1, 2),
  :func:`~orientviz.simulate.simulate_block`;
* single images and pairs: :func:`~orientviz.orientation.relative.relative_orientation`
  (the stereo model), :func:`~orientviz.orientation.absolute.similarity_transform`
  (absolute orientation), :func:`~orientviz.orientation.resection.resection`,
  :func:`~orientviz.orientation.intersection.intersect_points`;
* aerotriangulation: :func:`~orientviz.bundle.bundle_adjust`,
  :func:`~orientviz.bundle.self_calibrate`, :func:`~orientviz.bundle.clean_block` (gross
  errors), :func:`~orientviz.stereo_models.independent_models`;
* results: :class:`~orientviz.adjust.result.Adjustment` (every solver),
  :class:`~orientviz.bundle.BundleResult` (the bundle's, with exterior orientations,
  points and check points), :class:`~orientviz.adjust.result.Iteration` (one step of the
  history), :class:`~orientviz.orientation.intersection.Intersection`;
* the viewer: :func:`view`;
* errors: :class:`~orientviz.errors.OrientvizError`, :class:`~orientviz.errors.InputError`,
  :class:`~orientviz.errors.AdjustmentError`, :class:`~orientviz.errors.NotDeterminableError`.

Everything else lives in the subpackages (:mod:`orientviz.block`, :mod:`orientviz.adjust`,
:mod:`orientviz.orientation`, :mod:`orientviz.bundle`, :mod:`orientviz.stereo_models`,
:mod:`orientviz.polynomial`, :mod:`orientviz.simulate`, :mod:`orientviz.radar`,
:mod:`orientviz.io`, :mod:`orientviz.report`, :mod:`orientviz.plot`,
:mod:`orientviz.widgets`, :mod:`orientviz.viewer`); numbered scripts to copy from are
in ``examples/`` of the repository.

Conventions: object space in m (right-handed, Z up), image coordinates in mm,
angles in rad inside the code (gon/c/cc at the edges), rotations R = R_ω R_φ R_κ by
default. See :mod:`orientviz.units`, :mod:`orientviz.rotation`, :mod:`orientviz.camera`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .errors import AdjustmentError, InputError, NotDeterminableError, OrientvizError
from .faces import lazy_names
from .version import __version__

#: name on the face → the module (relative to this package) that defines it
_FACE: dict[str, str] = {
    # problem files and data
    "Problem": ".io.problem",
    "load_problem": ".io.problem",
    "save_problem": ".io.problem",
    "load_dataset": ".io.datasets",
    "solve_problem": ".io.solve",
    "read_colmap": ".io.colmap",
    "write_report": ".report",
    # conventions
    "to_rad": ".units",
    "from_rad": ".units",
    "matrix_from_opk": ".rotation",
    "opk_from_matrix": ".rotation",
    "FrameCamera": ".camera",
    "project": ".camera",
    # the block
    "Block": ".block",
    "TIE": ".block",
    "CONTROL": ".block",
    "CHECK": ".block",
    "simulate_block": ".simulate",
    # single pairs and images
    "relative_orientation": ".orientation.relative",
    "similarity_transform": ".orientation.absolute",
    "resection": ".orientation.resection",
    "intersect_points": ".orientation.intersection",
    # aerotriangulation
    "bundle_adjust": ".bundle",
    "self_calibrate": ".bundle",
    "clean_block": ".bundle",
    "independent_models": ".stereo_models",
    # results
    "Adjustment": ".adjust.result",
    "Iteration": ".adjust.result",
    "BundleResult": ".bundle",
    "Intersection": ".orientation.intersection",
}

#: the face (a literal list, so that tools see it; tests/core/test_imports.py checks it
#: against _FACE)
__all__ = [
    "Adjustment",
    "AdjustmentError",
    "Block",
    "BundleResult",
    "CHECK",
    "CONTROL",
    "FrameCamera",
    "InputError",
    "Intersection",
    "Iteration",
    "NotDeterminableError",
    "OrientvizError",
    "Problem",
    "TIE",
    "__version__",
    "bundle_adjust",
    "clean_block",
    "from_rad",
    "independent_models",
    "intersect_points",
    "load_dataset",
    "load_problem",
    "matrix_from_opk",
    "opk_from_matrix",
    "project",
    "read_colmap",
    "relative_orientation",
    "resection",
    "save_problem",
    "self_calibrate",
    "similarity_transform",
    "simulate_block",
    "solve_problem",
    "to_rad",
    "view",
    "write_report",
]


def view(
    content: Any = "block", *, host: str = "127.0.0.1", port: int = 8080, **options: Any
) -> Any:
    """Open the 3D viewer (viser) on ``content`` and return the running app.

    viser and the scene code are imported here, on the call, never by ``import
    orientviz``.

    Parameters
    ----------
    content : Block, tuple (Block, Adjustment), str
        A block (drawn at its current values), a block with its adjustment (residuals,
        ellipsoids, the iteration scrubber), a demo name (``"block"``, ``"pair"``,
        ``"radar"``) or the path of a problem file.
    host : str
        Interface to bind; 127.0.0.1 (this computer only) unless asked otherwise.
    port : int
        TCP port; 0 takes any free port (see ``app.url``).
    **options
        Passed to :class:`orientviz.viewer.app.ViewerApp` (e.g. ``verbose=False``).

    Returns
    -------
    orientviz.viewer.app.ViewerApp
        ``app.url`` to open in a browser, ``app.show()`` inline in Jupyter,
        ``app.export_html(path)`` a static snapshot, ``app.stop()`` to end it.
    """
    from .viewer.app import open_viewer  # viser: loaded when ov.view is called, never before

    return open_viewer(content, host=host, port=port, **options)


__getattr__ = lazy_names(__name__, _FACE, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from .adjust.result import Adjustment, Iteration
    from .block import CHECK, CONTROL, TIE, Block
    from .bundle import BundleResult, bundle_adjust, clean_block, self_calibrate
    from .camera import FrameCamera, project
    from .io.colmap import read_colmap
    from .io.datasets import load_dataset
    from .io.problem import Problem, load_problem, save_problem
    from .io.solve import solve_problem
    from .orientation.absolute import similarity_transform
    from .orientation.intersection import Intersection, intersect_points
    from .orientation.relative import relative_orientation
    from .orientation.resection import resection
    from .report import write_report
    from .rotation import matrix_from_opk, opk_from_matrix
    from .simulate import simulate_block
    from .stereo_models import independent_models
    from .units import from_rad, to_rad
