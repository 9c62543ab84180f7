"""The verdict of an adjustment: global test, flagged observations and warnings.

One function, :func:`verdict`, reads them off the report's sections (formed as
:func:`build_report` forms them, without the sections that only show numbers), so that
``orientviz solve`` on the terminal, its ``--json`` and the text and HTML reports say
the same: the χ² test of σ̂0 of section "σ0 a posteriori and global test", the count of
normalised residuals above the critical value of section "Largest normalised residuals"
and the list of section "Warnings on geometry and quality".
"""

from __future__ import annotations

import math
from typing import Any

from ..io.problem import Problem
from ..io.solution import Solution
from ._sections import verdict_sections


def verdict(problem: Problem, solution: Solution, alpha: float = 0.05) -> dict[str, Any]:
    """The global test, the number of flagged observations and the warnings.

    Parameters
    ----------
    problem : Problem
        The loaded problem.
    solution : Solution
        Its solution from :func:`orientviz.io.solve.solve_problem`.
    alpha : float
        Significance level of the two-sided χ² test of σ̂0 (as in the report).

    Returns
    -------
    dict
        ``global_test``: ``result`` (``"accepted"``, ``"rejected"`` or
        ``"not possible"``), ``T`` = r σ̂0², its χ²(r) bounds ``lower``/``upper``,
        the bounds ``sigma0_lower``/``sigma0_upper`` of σ̂0 (unit weight), ``alpha``,
        ``r`` and ``reason`` (one phrase); ``flagged``: the number of observations
        with ``|w|`` above the critical value; ``warnings``: the report's list of warnings.
    """
    report = verdict_sections(problem, solution, alpha=alpha)
    t = dict(report.section("sigma0").values["test"])
    accepted = t.pop("accepted")
    sigma0 = float(solution.adjustment.sigma0)
    if accepted is None:
        result, reason = "not possible", "redundancy r = 0 or σ0 not finite"
    elif accepted:
        result, reason = "accepted", "σ0 a posteriori agrees with the a-priori σ0 = 1"
    elif sigma0 > 1:
        result = "rejected"
        reason = "σ0 too large: gross errors, systematic errors or too optimistic a-priori σ"
    else:
        result, reason = "rejected", "σ0 too small: the a-priori σ are too pessimistic"
    test = {
        "result": result,
        "reason": reason,
        **{k: (v if not isinstance(v, float) or math.isfinite(v) else None) for k, v in t.items()},
    }
    residuals = report.section("residuals")
    flagged = int(residuals.values.get("n_flagged", 0)) if residuals is not None else 0
    warnings = list(report.section("warnings").values["messages"])
    return {"global_test": test, "flagged": flagged, "warnings": warnings}
