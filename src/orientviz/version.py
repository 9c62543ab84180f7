"""orientviz's version string (the front door re-exports it as ``orientviz.__version__``).

A module of its own at the bottom of the package, so that what writes the version into
its output (the reports) need not import the front door, which stands above everything.
"""

__version__ = "0.1.0"
