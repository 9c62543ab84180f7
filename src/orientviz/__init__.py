"""orientviz — learn, teach and visually debug photogrammetric orientation.

The core (this package without :mod:`orientviz.plot`, :mod:`orientviz.widgets` and
:mod:`orientviz.viewer`) depends on numpy and scipy only; importing it stays fast.

Conventions: object space in m (right-handed, Z up), image coordinates in mm,
angles in rad inside the code (gon/c/cc at the edges), rotations R = R_ω R_φ R_κ by
default. See :mod:`orientviz.units`, :mod:`orientviz.rotation`, :mod:`orientviz.camera`.
"""

from __future__ import annotations

__version__ = "0.1.0"

from .errors import AdjustmentError, InputError, NotDeterminableError, OrientvizError

__all__ = ["AdjustmentError", "InputError", "NotDeterminableError", "OrientvizError", "__version__"]
