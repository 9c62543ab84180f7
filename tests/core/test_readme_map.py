"""README's "What is inside" table names folders and modules that exist."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_what_is_inside_paths_exist():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    table = text.split("## What is inside", 1)[1].split("\n## ", 1)[0]
    rows = [r for r in table.splitlines() if r.startswith("| ") and "---" not in r][1:]
    assert len(rows) >= 10
    missing = []
    for row in rows:
        where = row.split("|")[2]
        paths = [p for p in re.findall(r"`([^`\s]+)`", where) if p.endswith(("/", ".py"))]
        assert paths, f"no path in {row!r}"
        base = ROOT
        for p in paths:
            # the first path is relative to the repository; the others to its folder
            target = ROOT / p if "/" in p.rstrip("/") or base == ROOT else base / p
            if not target.exists():
                missing.append(p)
            if base == ROOT:
                base = (ROOT / p.rstrip("/")).parent
    assert not missing, f"README names paths that do not exist: {missing}"
