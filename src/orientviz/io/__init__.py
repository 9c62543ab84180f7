"""orientviz.io: problem files (``orientviz/1`` JSON), shipped datasets, BAL and COLMAP.

The common entry points are importable from here (loaded on first use)::

    from orientviz.io import load_problem, save_problem, load_dataset
"""

from __future__ import annotations

from ..faces import lazy_names

#: name → submodule that defines it
_EXPORTS = {
    "Problem": ".problem",
    "Units": ".problem",
    "load_problem": ".problem",
    "loads_problem": ".problem",
    "save_problem": ".problem",
    "write_problem": ".problem",
    "dumps_problem": ".problem",
    "problem_from_block": ".problem",
    "solve_problem": ".solve",
    "list_datasets": ".datasets",
    "load_dataset": ".datasets",
    "dataset_path": ".datasets",
    "dataset_info": ".datasets",
    "available_kinds": ".registry",
}

__all__ = sorted(_EXPORTS)


__getattr__ = lazy_names(__name__, _EXPORTS, globals())
