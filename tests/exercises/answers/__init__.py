"""Solutions and mutants of the lesson exercises (teacher-side; not in the installed package)."""
