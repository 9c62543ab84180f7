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
* The package ships the checks only, never the solutions: those are in the lesson
  notebooks (between the markers below) and in the repository's
  ``tests/exercises/answers/lessonNN.py`` (``SOLUTIONS`` and ``MUTANTS``), where
  ``tests/exercises/test_lessonNN.py`` asserts that every solution passes and every mutant is
  rejected by ≥ 100× the tolerance; ``tests/exercises/test_no_solutions.py`` that no function
  of a checker module passes a check.
* In the notebook an exercise is three cells: a markdown prompt (the signature in a code
  block), a solution cell whose body lies between ``### BEGIN SOLUTION`` and
  ``### END SOLUTION`` (tag ``hide-cell``, metadata ``mystnb.code_prompt_show = "Show the
  solution"`` and ``jupyter.source_hidden = true``), and a visible check cell. A wrong
  answer's message is shown with :func:`~orientviz.exercises._common.show_mistake`, never
  with an error cell.
* Student copies: ``python tools/make_student_release.py notebooks/ OUTDIR`` (in the
  repository) replaces every solution body by ``raise NotImplementedError``, drops hidden
  tests, unhides the cell and tags the check after it ``raises-exception``; its first code cell
  calls :func:`release_check`, which stops a copy made from another orientviz at once.
* A lesson decorates a "your version" function that later cells use with
  :func:`stand_in` (the library's equivalent): while the blank is empty, those cells get
  the library's result and say so; the checks unwrap it and answer "not written yet".
* A "find the mistake" exercise shows a colleague's function in a visible cell that begins
  with ``# A colleague's version: one line is wrong.``; the student writes the corrected
  function, which the usual check judges. ``tests/notebooks/test_planted_mistakes.py`` runs
  every such cell and demands that its checker rejects it with the named diagnosis.
* A failed check raises a message that begins with "✗" (a passed one prints "✓ …").
* A slider question ("move the slider until …") is checked by
  :mod:`orientviz.exercises.sliders`; its check cell may end with hidden tests (between
  ``### BEGIN HIDDEN TESTS`` and ``### END HIDDEN TESTS``, run in the teacher's copy, dropped
  from the student's) that demand :func:`~orientviz.exercises._common.rejection` names each
  plausible misreading.
* A numpy error raised inside the student's function (a transposed matrix, a wrong shape)
  is turned by :func:`~orientviz.exercises._common.call` into a :class:`CheckFailed` that names
  the shapes of the inputs.

This package is core: it imports numpy and scipy only (no matplotlib, no widgets).
"""

from __future__ import annotations

from ._common import CheckFailed, NotWrittenError, rejection, show_mistake
from ._release import release_check
from ._standin import stand_in

__all__ = [
    "CheckFailed",
    "NotWrittenError",
    "rejection",
    "release_check",
    "show_mistake",
    "stand_in",
]
