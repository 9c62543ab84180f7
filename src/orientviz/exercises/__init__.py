"""Checkers for the exercises in the lesson notebooks.

Conventions (shared by all lessons; the lint ``tests/notebooks/test_lesson_shape.py``
enforces the notebook side):

* One module per lesson, ``orientviz.exercises.lessonNN`` (NN = the notebook's number).
  A checker is ``check_<what>(answer)``: it calls the student's function on fresh inputs
  from its own seeded generator (:func:`~orientviz.exercises._common.rng_for`), compares
  with an **independent oracle** (a closed form by hand, a paper's table, brute force,
  numerical derivatives, the truth of error-free simulated data — never the library
  function the lesson is about), raises :class:`~orientviz.exercises._common.CheckFailed`
  (an ``AssertionError``) whose message names the plausible mistake ("equals the
  transpose", "off by a factor 0.9: degrees instead of gon?"), answers an empty blank with
  "not written yet", and prints a short "✓ …" on success.
* Each module exposes ``SOLUTIONS = {"check_x": fn}`` and
  ``MUTANTS = {"check_x": {"transpose": fn, ...}}``; ``tests/exercises/test_lessonNN.py``
  asserts that every solution passes and every mutant is rejected by ≥ 100× the tolerance.
* In the notebook an exercise is three cells: a markdown prompt (the signature in a code
  block), a solution cell whose body lies between ``### BEGIN SOLUTION`` and
  ``### END SOLUTION`` (tag ``hide-cell``, metadata ``mystnb.code_prompt_show = "Show the
  solution"`` and ``jupyter.source_hidden = true``), and a visible check cell. A wrong
  answer's message is shown with :func:`~orientviz.exercises._common.show_mistake`, never
  with an error cell.
* Student copies: ``python -m orientviz.exercises.strip notebooks/ OUTDIR`` replaces every
  solution body by ``raise NotImplementedError`` and unhides the cell.

This package is core: it imports numpy only (no matplotlib, no widgets).
"""

from __future__ import annotations

from ._common import CheckFailed, NotWrittenError, show_mistake

__all__ = ["CheckFailed", "NotWrittenError", "show_mistake"]
