"""Data shipped with orientviz: example problem files (``examples/``, see MANIFEST.json)."""
