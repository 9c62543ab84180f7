"""``tools/make_student_release.py`` loaded as a module (tools/ is not a package)."""

from __future__ import annotations

import importlib.util
import pathlib

ROOT = pathlib.Path(__file__).parents[2]
_spec = importlib.util.spec_from_file_location(
    "make_student_release", ROOT / "tools" / "make_student_release.py"
)
release = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(release)
