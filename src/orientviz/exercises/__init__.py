"""Checkers for the exercises of the lesson notebooks (one module per lesson).

A checker ``check_<what>(answer_or_function)`` calls the student's function on fresh
inputs, compares with an independent oracle and raises ``AssertionError`` with a
diagnosis of the likely mistake; ``MUTANTS`` and ``SOLUTIONS`` per module let the tests
prove that each checker passes the solution and rejects the plausible wrong answers.
"""
