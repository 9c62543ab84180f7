"""Data shipped with orientviz, each folder with its MANIFEST.json (source, units, frame, licence).

Problem files (``examples/``, ``pair/``, ``geier1973/``, ``dbat/``; :mod:`orientviz.io.datasets`),
real structure-from-motion models in their programs' own formats (``axe/``, a COLMAP
model, CC BY 4.0; ``bal/``, the BAL problem Ladybug; :mod:`orientviz.datasets.sfm`) and the
scripts that wrote them (``make_*.py``).
"""
