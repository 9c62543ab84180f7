"""Radar panorama (PPI) images with approximate horizontal ranges, after Geier (1973).

Modules (import them directly; nothing heavy is imported here):

* :mod:`~orientviz.radar.ppi` — the image: mapping (4a), spheres (4b), planes (4c),
  :class:`~orientviz.radar.ppi.RadarImage` with its ten parameters, Jacobians;
* :mod:`~orientviz.radar.orientation` — single-image tasks: calibration, trilateration,
  rotations, exterior orientation, all ten parameters;
* :mod:`~orientviz.radar.trilateration` — the closed-form three-sphere intersection;
* :mod:`~orientviz.radar.pair` — intersection, relative and absolute orientation;
* :mod:`~orientviz.radar.diagnostics` — weak pair geometry, weakest parameter direction;
* :mod:`~orientviz.radar.stopping` — a stopping rule reconstructed from Fig. 8 (fitted);
* :mod:`~orientviz.radar.rounding` — Fig. 8 against the spread of many roundings;
* :mod:`~orientviz.radar.geier1973`, :mod:`~orientviz.radar.data`,
  :mod:`~orientviz.radar.fig8` — the paper's test data, the shipped dataset, Fig. 8;
* :mod:`~orientviz.radar.scene` — plain scene data for the viewer.

Conventions: metres, radians inside, R = R_φ R_ω R_κ (image → object), κ = α0.
"""
