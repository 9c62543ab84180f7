"""Count what a student has to read and write in each lesson, and estimate the time.

    python tools/lesson_workload.py                       # table in Markdown
    python tools/lesson_workload.py --times times.json    # with measured run times

Counted from the teacher's notebooks (``notebooks/*.ipynb``):

* words of prose (markdown cells, solutions removed, LaTeX counted as words) and display
  equations (``$$ … $$``);
* blanks: code blocks between ``### BEGIN SOLUTION`` and ``### END SOLUTION`` (what the
  student release empties) and their non-comment lines; prose answers
  (``<!-- BEGIN SOLUTION -->``); interactive widgets (``interact``/``*_app(`` calls); live
  3D viewers (``show_live(``);
* what the lesson imports beyond numpy/scipy/matplotlib (ipywidgets, the viewer's viser).

The estimate is a model, not a measurement on students: reading at 80–150 words per
minute (technical prose with formulas), 2–5 minutes per line of solution code (writing,
running the check, correcting), 4–8 minutes per prose answer and per widget question, plus
the machine's run time of the released lesson (``--times``: the JSON written by a timing
run, ``{lesson: {"wall": s, "cpu": s}}``). The low end assumes a student who knows the
mathematics from the lecture; the high end one who meets it here first.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
CODE_SOL = re.compile(r"### BEGIN SOLUTION\n(.*?)### END SOLUTION", re.S)
MD_SOL = re.compile(r"<!-- BEGIN SOLUTION -->.*?<!-- END SOLUTION -->", re.S)
WIDGET = re.compile(r"\binteract\(|\w+_app\(")
#: (low, high) per unit: words per minute, minutes per solution line, per prose answer/widget
READ_WPM = (150.0, 80.0)
MIN_PER_LINE = (2.0, 5.0)
MIN_PER_ANSWER = (4.0, 8.0)


def count(path: pathlib.Path) -> dict:
    """Counts of one lesson (see the module docstring)."""
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    words = equations = blanks = lines = answers = widgets = viewers = 0
    needs: set[str] = set()
    for cell in cells:
        src = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            answers += len(MD_SOL.findall(src))
            text = MD_SOL.sub("", src)
            words += len(text.split())
            equations += text.count("$$") // 2
            continue
        for block in CODE_SOL.findall(src):
            blanks += 1
            lines += sum(
                1 for ln in block.splitlines() if ln.strip() and not ln.strip().startswith("#")
            )
        widgets += len(WIDGET.findall(src))
        viewers += src.count("show_live(")
        if "ipywidgets" in src or "orientviz.widgets" in src or WIDGET.search(src):
            needs.add("ipywidgets")
        if re.search(r"show_live\(|show_inline\(|open_viewer\(|ViewerApp\(", src):
            needs.add("viser")  # a live viewer (scene_figure alone is matplotlib)
    return dict(words=words, equations=equations, blanks=blanks, lines=lines,
                answers=answers, widgets=widgets, viewers=viewers, needs=sorted(needs))  # fmt: skip


def estimate(c: dict, run_s: float = 0.0) -> tuple[float, float]:
    """(low, high) student time in minutes for the counts ``c`` and a run time in s."""
    out = []
    for k in range(2):
        minutes = (
            c["words"] / READ_WPM[k]
            + c["lines"] * MIN_PER_LINE[k]
            + (c["answers"] + c["widgets"]) * MIN_PER_ANSWER[k]
            + run_s / 60.0
        )
        out.append(minutes)
    return out[0], out[1]


def table(times: dict | None = None) -> str:
    """The Markdown table of every lesson."""
    rows = [
        "| lesson | words | display equations | blanks (solution lines) | prose answers | "
        "widgets | live 3D viewer | released run, wall (CPU) [s] | student time, estimated [h] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    total = [0.0, 0.0]
    lessons = sorted((ROOT / "notebooks").glob("*.ipynb"))
    for nb in lessons:
        c = count(nb)
        t = (times or {}).get(nb.name, {})
        wall = float(t.get("wall", 0.0))
        lo, hi = estimate(c, wall)
        total[0] += lo
        total[1] += hi
        run = f"{wall:.0f} (CPU {t['cpu']:.0f})" if t else "–"
        rows.append(
            f"| {nb.stem} | {c['words']} | {c['equations']} | {c['blanks']} ({c['lines']}) | "
            f"{c['answers']} | {c['widgets']} | {'yes' if c['viewers'] else '–'} | {run} | "
            f"{lo / 60:.1f}–{hi / 60:.1f} |"
        )
    rows.append(f"| all {len(lessons)} | | | | | | | | {total[0] / 60:.0f}–{total[1] / 60:.0f} |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--times", type=pathlib.Path, help="JSON of measured run times per lesson")
    args = p.parse_args(argv)
    times = json.loads(args.times.read_text()) if args.times else None
    print(table(times))


if __name__ == "__main__":
    main()
