"""orientviz.viewer — the viser 3D viewer: scene builders, the app, demos, HTML export.

Pure geometry lives in :mod:`~orientviz.viewer.geometry` and
:mod:`~orientviz.viewer.block_geometry` (no viser import); :mod:`~orientviz.viewer.scene`
and :mod:`~orientviz.viewer.app` talk to viser, which is imported only when a viewer
starts. ``from orientviz.viewer import open_viewer`` works without importing viser.
"""

from .app import ViewerApp, export_html, open_viewer

__all__ = ["ViewerApp", "export_html", "open_viewer"]
