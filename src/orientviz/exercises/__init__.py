"""Checkers of the lessons' exercises: ``lessonNN.check_<what>(answer_or_function)``.

Each checker calls the student's function on fresh inputs, compares with an independent
oracle (a closed form, brute force, a paper's table, error-free simulated truth) and
raises ``AssertionError`` with a diagnosis of the plausible mistake. Each module has
``SOLUTIONS`` and ``MUTANTS`` (plausible wrong answers) for the tests.
"""
