"""The hostile-input corpus: every case is generated here (no files committed).

Grouped by what is attacked: command-line numbers, special and oversized files, output
targets, text fields, CSV, COLMAP, BAL, problem-file numbers and geometry. Each group is
a function returning :class:`~tests.hostile.harness.Case` objects; :data:`CASES` is all
of them. Add a case for every bug found.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from . import inputs as I
from .harness import Case

# --------------------------------------------------------------------------- helpers
#: (command, input file relative to the folder, the argv around it)
INPUT_SLOTS = {
    "solve": (I.BLOCK, lambda f, p: ["solve", p]),
    "export": (I.BLOCK, lambda f, p: ["export", p, "-d", str(f / "out")]),
    "view": (I.BLOCK, lambda f, p: ["view", p, "--export", str(f / "v.html")]),
    "view-server": (I.BLOCK, lambda f, p: ["view", p, "--port", "0"]),  # must not serve
    "import-bal": (I.BAL, lambda f, p: ["import-bal", p, "-o", str(f / "o.json")]),
    "import-csv": (
        I.MARKS,
        lambda f, p: ["import-csv", p, "--units", "mm", "--c", "152", "-o", str(f / "o.json")],
    ),
    "import-bal/control": (
        I.CONTROL,
        lambda f, p: ["import-bal", str(f / I.BAL), "--control", p, "-o", str(f / "o.json")],
    ),
    "import-colmap/control": (
        I.CONTROL,
        lambda f, p: [
            "import-colmap",
            str(f / "sparse"),
            "--control",
            p,
            "-o",
            str(f / "o.json"),
        ],
    ),  # fmt: skip
}
for _folder, _files in (("sparse", ("cameras.txt", "images.txt", "points3D.txt")),
                        ("sparse_bin", ("cameras.bin", "points3D.bin"))):  # fmt: skip
    for _file in _files:
        _slot = "import-colmap" + ("-bin" if _folder.endswith("bin") else "")
        INPUT_SLOTS[f"{_slot}/{_file.split('.')[0].removesuffix('3D')}"] = (
            f"{_folder}/{_file}",
            lambda f, p, d=_folder: ["import-colmap", str(f / d), "-o", str(f / "o.json")],
        )


def _all_inputs(folder: Path) -> None:
    I.write(folder, I.BLOCK, I.BAL, I.COLMAP, I.CONTROL, I.MARKS)
    I.write_binary(folder)


def _replace_with(kind: str):
    """A function that turns ``folder/rel`` into a special file of ``kind``."""

    def make(path: Path) -> None:
        if path.exists():
            path.unlink()
        if kind == "directory":
            path.mkdir()
        elif kind == "fifo":
            os.mkfifo(path)
        elif kind in ("zero", "urandom"):
            path.symlink_to(f"/dev/{kind}")
        elif kind == "missing":
            pass
        elif kind == "dangling-link":
            path.symlink_to(path.parent / "nowhere")
        elif kind == "symlink-loop":
            path.symlink_to(path)
        elif kind == "empty":
            path.write_bytes(b"")
        elif kind == "binary":
            path.write_bytes(bytes(range(256)) * 8)
        elif kind == "latin-1":
            path.write_bytes("Gebäude 1 2 3\n".encode("latin-1"))
        elif kind == "nul":
            path.write_bytes(b"\x00" * 64)

    return make


SPECIAL = {
    "directory": "is a directory",
    "fifo": "is a named pipe",
    "zero": "is a device",
    "urandom": "is a device",
    "missing": "no such file",
    "dangling-link": "no such file",
    "symlink-loop": "cannot open",
}


def special_files() -> list[Case]:
    """Every input slot × a folder, a FIFO, /dev/zero, /dev/urandom, missing, dangling."""
    out = []
    for slot, (rel, argv) in INPUT_SLOTS.items():
        for kind, says in SPECIAL.items():

            def make(f: Path, rel=rel, argv=argv, kind=kind) -> list[str]:
                _all_inputs(f)
                _replace_with(kind)(f / rel)
                return argv(f, str(f / rel))

            out.append(Case(f"{slot}/special/{kind}", make, 2, (says,), rel))
    return out


def garbage_files() -> list[Case]:
    """Every input slot × empty, binary, Latin-1, NUL bytes, and over ``--max-size``."""
    out = []
    for slot, (rel, argv) in INPUT_SLOTS.items():
        for kind in ("empty", "binary", "latin-1", "nul"):

            def make(f: Path, rel=rel, argv=argv, kind=kind) -> list[str]:
                _all_inputs(f)
                _replace_with(kind)(f / rel)
                return argv(f, str(f / rel))

            colmap = slot.startswith(("import-colmap/", "import-colmap-bin/"))
            names = rel.split("/")[0] if colmap and "control" not in slot else rel
            out.append(Case(f"{slot}/garbage/{kind}", make, 2, (), names))

        if slot in ("import-colmap/images", "import-colmap/points", "import-colmap-bin/points") or (
            "control" in slot
        ):
            continue  # another file is read first

        def big(f: Path, rel=rel, argv=argv) -> list[str]:
            _all_inputs(f)
            return [*argv(f, str(f / rel)), "--max-size", "100"]

        names = "sparse_bin" if slot.startswith("import-colmap-bin") else rel
        out.append(Case(f"{slot}/size/over-max-size", big, 2, ("--max-size",), names))
    return out


# --------------------------------------------------------------------------- arguments
def long_names() -> list[Case]:
    """A path longer than the system allows, for every input slot."""
    out = []
    for slot, (_rel, argv) in INPUT_SLOTS.items():
        if "/" in slot:
            continue

        def make(f: Path, argv=argv) -> list[str]:
            _all_inputs(f)
            return argv(f, str(f / ("n" * 300) / ("m" * 300) / "x.json"))

        out.append(Case(f"{slot}/special/name-too-long", make, 2, (), None))
    return out


def arguments() -> list[Case]:
    """Numbers and choices on the command line, refused by the parser (exit 2)."""
    out = []
    bad_numbers = ["-0.01", "0", "nan", "inf", "-inf", "1e999", "abc", "1e-320", "1e300"]
    for cmd, rel in (("import-bal", I.BAL), ("import-colmap", "sparse")):
        for opt, values in (
            ("--pixel-size", bad_numbers),
            ("--sigma-px", ["-1", "0", "nan", "1e-320"]),
        ):
            for v in values:

                def make(f: Path, cmd=cmd, rel=rel, opt=opt, v=v) -> list[str]:
                    _all_inputs(f)
                    return [cmd, str(f / rel), "-o", str(f / "o.json"), f"{opt}={v}"]

                out.append(Case(f"{cmd}/argument/{opt[2:]}={v}", make, 2, (v,), opt))
    for v in ("-1", "70000", "http"):
        out.append(
            Case(
                f"view/argument/port={v}",
                lambda f, v=v: ["view", "pair", f"--port={v}"],
                2,
                (v,),
                "--port",
            )  # fmt: skip
        )
    for v in ("0", "-5M", "lots"):

        def make(f: Path, v=v) -> list[str]:
            _all_inputs(f)
            return ["solve", str(f / I.BLOCK), f"--max-size={v}"]

        out.append(Case(f"solve/argument/max-size={v}", make, 2, (v,), "--max-size"))
    for what, name in (("unknown", "nosuchpaper"), ("surrogate", "\udc80"),
                       ("long", "x" * 5000), ("mathtext", "$\\a$")):  # fmt: skip
        out.append(Case(f"reproduce/argument/{what}", lambda f, n=name: ["reproduce", n], 2,
                        (), None))  # fmt: skip
    out.append(Case("orientviz/argument/unknown-command", lambda f: ["frobnicate"], 2,
                    ("frobnicate",), None))  # fmt: skip
    out.append(
        Case(
            "solve/argument/method",
            lambda f: ["solve", "x.json", "--method", "magic"],
            2,
            ("magic",),
            "--method",
        )  # fmt: skip
    )
    return out


# --------------------------------------------------------------------------- outputs
def _solve_to(target: str, extra: tuple[str, ...] = ()):
    def make(f: Path) -> list[str]:
        _all_inputs(f)
        (f / "adir").mkdir()
        return ["solve", str(f / I.BLOCK), *extra, str(f / target)]

    return make


def outputs() -> list[Case]:
    """Output targets that must be refused without touching anything."""
    c = []
    c.append(Case("solve/output/onto-input", _solve_to(I.BLOCK, ("-o",)), 2,
                  ("refusing to overwrite",), I.BLOCK))  # fmt: skip
    c.append(Case("solve/output/missing-folder", _solve_to("no/out.json", ("-o",)), 2,
                  ("does not exist",), "no/out.json"))  # fmt: skip
    c.append(Case("solve/output/a-directory", _solve_to("adir", ("-o",)), 2,
                  ("is a directory",), "adir"))  # fmt: skip
    c.append(Case("solve/report/a-directory", _solve_to("adir", ("--report",)), 2, (), "adir"))
    c.append(Case("solve/report/onto-input", _solve_to(I.BLOCK, ("--report",)), 2, (), I.BLOCK))
    c.append(Case("solve/report/suffix", _solve_to("r.pdf", ("--report",)), 2, (), "r.pdf"))

    def export_onto_file(f: Path) -> list[str]:
        _all_inputs(f)
        (f / "taken").write_text("mine")
        return ["export", str(f / I.BLOCK), "-d", str(f / "taken")]

    c.append(Case("export/directory/an-existing-file", export_onto_file, 2,
                  ("not a directory",), "taken"))  # fmt: skip

    def export_onto_input(f: Path) -> list[str]:
        _all_inputs(f)
        return ["export", str(f / I.BLOCK), "-d", str(f / I.BLOCK)]

    c.append(Case("export/directory/the-input", export_onto_input, 2, (), I.BLOCK))

    def export_over_input(f: Path) -> list[str]:  # the input is DIR/adjusted.json itself
        (f / "res").mkdir()
        I.write(f / "res", I.BLOCK)
        (f / "res" / I.BLOCK).rename(f / "res" / "adjusted.json")
        return ["export", str(f / "res" / "adjusted.json"), "-d", str(f / "res"), "--format",
                "json"]  # fmt: skip

    c.append(Case("export/directory/holds-the-input", export_over_input, 2, ("refusing",),
                  "res/adjusted.json"))  # fmt: skip

    def import_onto(cmd: str, rel: str, target: str):
        def make(f: Path) -> list[str]:
            _all_inputs(f)
            (f / "adir").mkdir()
            return [cmd, str(f / rel), "-o", str(f / target)]

        return make

    c.append(Case("import-bal/output/onto-input", import_onto("import-bal", I.BAL, I.BAL), 2,
                  ("refusing",), I.BAL))  # fmt: skip
    c.append(Case("import-bal/output/a-directory", import_onto("import-bal", I.BAL, "adir"), 2,
                  ("is a directory",), "adir"))  # fmt: skip
    c.append(Case("import-colmap/output/missing-folder",
                  import_onto("import-colmap", "sparse", "no/o.json"), 2, (), "no/o.json"))  # fmt: skip
    c.append(Case("import-colmap/output/onto-cameras",
                  import_onto("import-colmap", "sparse", "sparse/cameras.txt"), 2, ("refusing",),
                  "sparse/cameras.txt"))  # fmt: skip

    def view_to_dir(f: Path) -> list[str]:
        (f / "adir").mkdir()
        return ["view", "pair", "--export", str(f / "adir")]

    c.append(Case("view/export/a-directory", view_to_dir, 2, ("is a directory",), "adir"))
    return c


# --------------------------------------------------------------------------- problem files
def _problem(name: str, mutate, *, raw: str | None = None):
    """A case maker writing base problem ``name`` mutated by ``mutate(doc)``."""

    def make(f: Path) -> list[str]:
        if raw is not None:
            text = raw
        else:
            d = I.doc(name)
            mutate(d)
            text = json.dumps(d)
        (f / name).write_text(text, encoding="utf-8")
        return ["solve", str(f / name)]

    return make


def _set(path, value):
    def mutate(d):
        node = d
        for p in path[:-1]:
            node = node[p]
        node[path[-1]] = value

    return mutate


def problem_files() -> list[Case]:
    """Text and numbers inside problem files of every kind."""
    c = []
    kinds = {
        "block": (I.BLOCK, ("images", 0, "id"), ("observations", 0, "x")),
        "resection": ("resection_example.json", ("points", 0, "id"), ("observations", 0, "x")),
        "intersection": (
            "intersection_example.json",
            ("points", 0, "id"),
            ("observations", 0, "x"),
        ),  # fmt: skip
        "similarity": (
            "similarity_example.json",
            ("source", "points", 0, "id"),
            ("source", "points", 0, "X"),
        ),  # fmt: skip
        "pair": ("pair_example.json", ("points", 0, "id"), ("points", 0, "xl")),
    }
    for kind, (name, id_path, num_path) in kinds.items():
        for what, value, says in (
            ("lone-surrogate-id", "\ud800", "surrogate"),
            ("megabyte-id", "x" * 2**20, "characters"),
            ("empty-id", "", ""),
        ):
            c.append(Case(f"solve/{kind}/{what}", _problem(name, _set(id_path, value)), 2,
                          (says,), name))  # fmt: skip
        for what, value in (("minus-1e308", -1e308), ("string-number", "12.5"),
                            ("huge-int", 10**400)):  # fmt: skip
            c.append(Case(f"solve/{kind}/{what}", _problem(name, _set(num_path, value)), 2,
                          (), name))  # fmt: skip
        deep = "[" * 100_000 + "]" * 100_000
        c.append(Case(f"solve/{kind}/nested-deeply", _problem(name, None, raw=deep), 2, (), name))

    def similarity_report(f: Path) -> list[str]:  # found by test_properties
        d = I.doc("similarity_example.json")
        d["target"]["points"][0]["X"] = 1e308
        (f / "s.json").write_text(json.dumps(d), encoding="utf-8")
        return ["solve", str(f / "s.json"), "--report", str(f / "r.html")]

    c.append(Case("solve/similarity/1e308-with-report", similarity_report, 2, ("beyond",),
                  "s.json"))  # fmt: skip
    empties = "[" + "{}," * 700_000 + "{}]"
    c.append(Case("solve/block/dense-structure", _problem(I.BLOCK, None, raw=empties), 2,
                  ("structure",), I.BLOCK))  # fmt: skip

    def export_far(f: Path) -> list[str]:
        d = I.doc(I.BLOCK)
        d["observations"][5]["x"] = -1e308
        (f / I.BLOCK).write_text(json.dumps(d), encoding="utf-8")
        return ["export", str(f / I.BLOCK), "-d", str(f / "out")]

    c.append(Case("export/geometry/x-minus-1e308", export_far, 2, ("observations[5]",),
                  I.BLOCK))  # fmt: skip
    big_description = _set(("description",), "d" * 200_000)
    c.append(Case("solve/block/long-description", _problem(I.BLOCK, big_description), 2,
                  ("characters",), I.BLOCK))  # fmt: skip

    def key_surrogate(d):
        d.setdefault("options", {})["\udc80"] = 1

    c.append(Case("solve/block/surrogate-key", _problem(I.BLOCK, key_surrogate), 2,
                  ("surrogate",), I.BLOCK))  # fmt: skip
    return c


# --------------------------------------------------------------------------- CSV
def _control(text: str, cmd: str = "import-bal"):
    def make(f: Path) -> list[str]:
        _all_inputs(f)
        (f / I.CONTROL).write_text(text, encoding="utf-8")
        src = str(f / (I.BAL if cmd == "import-bal" else "sparse"))
        return [cmd, src, "--control", str(f / I.CONTROL), "-o", str(f / "o.json")]

    return make


def csv_files() -> list[Case]:
    """Control CSVs: field limit, NUL, quotes, ids, numbers, roles."""
    good = I.base()[I.CONTROL].splitlines()
    head, row = good[0], good[1]
    rid = row.split(",")[0]
    cells = row.split(",")
    cases = {
        "cell-over-field-limit": (f"{head}\n" + "9" * 200_000 + ",1,2,3,0,0,0,control\n", "line 2"),
        "nul-byte": (f"{head}\n{rid},1\x00,2,3,0,0,0,control\n", "line 2"),
        "open-quote": (f'{head}\n"{rid},1,2,3,0,0,0,control\n', ""),
        "unknown-id-minus-1": (f"{head}\n-1,1,2,3,0,0,0,control\n", "line 2"),
        "megabyte-id": (f"{head}\n{'7' * 100_000},1,2,3,0,0,0,control\n", "line 2"),
        "nan-coordinate": (f"{head}\n{rid},nan,2,3,0,0,0,control\n", "line 2"),
        "1e999": (f"{head}\n{rid},1e999,2,3,0,0,0,control\n", "line 2"),
        "negative-sigma": (f"{head}\n{rid},1,2,3,-1,0,0,control\n", "line 2"),
        "bad-role": (f"{head}\n{rid},1,2,3,0,0,0,tie\n", "line 2"),
        "ragged": (f"{head}\n{rid},1,2\n", "line 2"),
        "no-header": (",".join(cells) + "\n", "line 1"),
        "duplicate": (f"{head}\n{row}\n{row}\n", "line 3"),
    }
    out = []
    for cmd in ("import-bal", "import-colmap"):
        for what, (text, says) in cases.items():
            out.append(Case(f"{cmd}/csv/{what}", _control(text, cmd), 2, (says,), I.CONTROL))
    return out


# --------------------------------------------------------------------------- COLMAP
def _colmap(file: str, edit):
    def make(f: Path) -> list[str]:
        _all_inputs(f)
        p = f / "sparse" / file
        p.write_text(edit(p.read_text()), encoding="utf-8")
        return ["import-colmap", str(f / "sparse"), "-o", str(f / "o.json")]

    return make


def _data_lines(text: str) -> tuple[list[str], list[int]]:
    lines = text.splitlines()
    return lines, [i for i, s in enumerate(lines) if s.strip() and not s.startswith("#")]


def _field(file_line: int, field: int, value: str):
    """Replace field ``field`` of the ``file_line``-th data line."""

    def edit(text: str) -> str:
        lines, data = _data_lines(text)
        words = lines[data[file_line]].split()
        words[field] = value
        lines[data[file_line]] = " ".join(words)
        return "\n".join(lines) + "\n"

    return edit


def colmap_models() -> list[Case]:
    """COLMAP text models with values that are legal text but not a usable model."""
    c = []
    cam = "sparse/cameras.txt"
    img = "sparse/images.txt"
    pts = "sparse/points3D.txt"
    for what, field, value in (("focal-zero", 4, "0"), ("focal-negative", 4, "-800"),
                               ("width-zero", 2, "0"), ("focal-1e308", 4, "1e308"),
                               ("unknown-model", 1, "FISHEYE"), ("cx-nan", 5, "nan")):  # fmt: skip
        c.append(Case(f"import-colmap/cameras/{what}", _colmap("cameras.txt", _field(0, field,
                      value)), 2, ("line",), cam))  # fmt: skip
    for what, field, value in (("tx-1e308", 5, "1e308"), ("quaternion-zero", 1, "0"),
                               ("name-100k", 9, "n" * 100_000),
                               ("camera-unknown", 8, "99"), ("image-id-text", 0, "one")):  # fmt: skip

        def edit(text, field=field, value=value, what=what):
            text = _field(0, field, value)(text)
            if what == "tx-1e308":  # with ty, tz large too: the centre overflows
                text = _field(0, 6, "1e308")(_field(0, 7, "1e308")(text))
            if what == "quaternion-zero":
                text = _field(0, 2, "0")(_field(0, 3, "0")(_field(0, 4, "0")(text)))
            return text

        c.append(Case(f"import-colmap/images/{what}", _colmap("images.txt", edit), 2,
                      ("line",), img))  # fmt: skip

    def uv_huge(text):
        lines, data = _data_lines(text)
        words = lines[data[1]].split()
        words[0] = "-1e308"
        lines[data[1]] = " ".join(words)
        return "\n".join(lines) + "\n"

    c.append(Case("import-colmap/images/u-minus-1e308", _colmap("images.txt", uv_huge), 2,
                  ("line",), img))  # fmt: skip

    def broken_triplet(text):
        lines, data = _data_lines(text)
        lines[data[1]] += " 5.0"
        return "\n".join(lines) + "\n"

    c.append(Case("import-colmap/images/broken-triplet", _colmap("images.txt", broken_triplet),
                  2, ("line",), img))  # fmt: skip
    for what, field, value in (("point-id-minus-1", 0, "-1"), ("x-inf", 1, "inf"),
                               ("track-unknown-image", 8, "999")):  # fmt: skip
        c.append(Case(f"import-colmap/points/{what}", _colmap("points3D.txt", _field(0, field,
                      value)), 2, ("line",), pts))  # fmt: skip

    def not_a_dir(f: Path) -> list[str]:
        _all_inputs(f)
        return ["import-colmap", str(f / I.BAL), "-o", str(f / "o.json")]

    c.append(Case("import-colmap/directory/a-file", not_a_dir, 2, ("directory",), I.BAL))
    return c


# --------------------------------------------------------------------------- BAL
def _bal(edit):
    def make(f: Path) -> list[str]:
        _all_inputs(f)
        p = f / I.BAL
        p.write_text(edit(p.read_text()))
        return ["import-bal", str(p), "-o", str(f / "o.json")]

    return make


def bal_files() -> list[Case]:
    """BAL files: headers, counts, numbers."""

    def line(k: int, value: str):
        def edit(text: str) -> str:
            lines = text.splitlines()
            lines[k] = value
            return "\n".join(lines) + "\n"

        return edit

    cases = {
        "header-negative": line(0, "-1 5 5"),
        "header-huge-counts": line(0, "1000000000 1000000000 1000000000"),
        "header-text": line(0, "cameras points observations"),
        "header-400-digits": line(0, "9" * 400 + " 1 1"),
        "observation-minus-1e308": lambda t: (
            "\n".join(
                [
                    t.splitlines()[0],
                    " ".join(t.splitlines()[1].split()[:2] + ["-1e308", "1"]),
                    *t.splitlines()[2:],
                ]
            )
            + "\n"
        ),  # fmt: skip
        "observation-camera-minus-1": lambda t: (
            "\n".join(
                [
                    t.splitlines()[0],
                    " ".join(["-1"] + t.splitlines()[1].split()[1:]),
                    *t.splitlines()[2:],
                ]
            )
            + "\n"
        ),  # fmt: skip
        "truncated": lambda t: "\n".join(t.splitlines()[:-5]) + "\n",
        "extra-numbers": lambda t: t + "1\n2\n",
    }
    out = [Case(f"import-bal/bal/{k}", _bal(e), 2, ("line",), I.BAL) for k, e in cases.items()]

    def focal_zero(t: str) -> str:
        lines = t.splitlines()
        n_obs = int(lines[0].split()[2])
        lines[1 + n_obs + 6] = "0"
        return "\n".join(lines) + "\n"

    out.append(Case("import-bal/bal/focal-zero", _bal(focal_zero), 2, ("f > 0",), I.BAL))
    return out


# --------------------------------------------------------------------------- geometry
def _block_edit(edit, extra: tuple[str, ...] = ()):
    def make(f: Path) -> list[str]:
        d = I.doc(I.BLOCK)
        edit(d)
        (f / I.BLOCK).write_text(json.dumps(d), encoding="utf-8")
        return ["solve", str(f / I.BLOCK), *extra]

    return make


def geometry() -> list[Case]:
    """Numbers that are legal JSON but a geometry that cannot be right."""
    c = []

    def check_point_far(d):
        ids = {p["id"] for p in d["points"] if p.get("role") == "check"}
        if not ids:
            d["points"][1]["role"] = "check"
            ids = {d["points"][1]["id"]}
        obs = next(o for o in d["observations"] if o["point"] in ids)
        obs["x"] = -1e308

    c.append(Case("solve/geometry/check-point-x-minus-1e308", _block_edit(check_point_far), 2,
                  ("outside",), I.BLOCK))  # fmt: skip

    def tie_far(d):
        d["observations"][3]["y"] = 1e6

    c.append(Case("solve/geometry/image-y-1e6", _block_edit(tie_far), 2, ("outside",),
                  I.BLOCK))  # fmt: skip

    def above_cameras(d):  # every point 5 km above the cameras: all behind them
        for p in d["points"]:
            p["Z"] = p.get("Z", 0) + 5000.0

    c.append(Case("solve/geometry/points-behind-cameras", _block_edit(above_cameras), 3,
                  ("behind",), I.BLOCK))  # fmt: skip

    def two_points(d):  # an extra image that sees only two control points
        img = dict(d["images"][-1], id="extra")
        d["images"].append(img)
        ctl = [p["id"] for p in d["points"] if p.get("role") == "control"][:2]
        for pid in ctl:
            o = next(o for o in d["observations"] if o["point"] == pid)
            d["observations"].append(dict(o, image="extra"))

    c.append(Case("solve/geometry/image-with-two-points", _block_edit(two_points), 3,
                  ("fewer",), I.BLOCK))  # fmt: skip

    def check_far(d):  # a check point's given X a thousand km off: warned, still solved
        p = next((p for p in d["points"] if p.get("role") == "check"), None)
        if p is None:
            p = d["points"][1]
            p["role"] = "check"
        p["X"] = p.get("X", 0.0) + 1e6

    def warned_in_report(folder: Path) -> None:
        text = " ".join((folder / "r.txt").read_text(encoding="utf-8").split())  # lines wrap
        assert "far outside its extent" in text and "in the file's values: point" in text

    c.append(Case("solve/geometry/check-point-far-away",
                  _block_edit(check_far, ("--report", "r.txt")), 0, warns=True,
                  outputs=("r.txt",), post=warned_in_report))  # fmt: skip

    def pair_points(edit):
        def make(f: Path) -> list[str]:
            d = I.doc("pair_example.json")
            edit(d)
            (f / "pair.json").write_text(json.dumps(d), encoding="utf-8")
            return ["solve", str(f / "pair.json")]

        return make

    def same_point(d):  # every point the same: no relative orientation
        for p in d["points"][1:]:
            p.update({k: d["points"][0][k] for k in ("xl", "yl", "xr", "yr")})

    def four_points(d):
        d["points"] = d["points"][:4]

    def by(method, edit=None):  # the same file solved by another estimator
        def change(d):
            d.setdefault("options", {})["method"] = method
            if edit:
                edit(d)

        return change

    for what, edit, code, says in (("all-points-equal", same_point, 3, "not determinable"),
                                   ("four-points", four_points, 2, "at least 5"),
                                   ("coplanarity-all-points-equal", by("coplanarity", same_point),
                                    3, "not determinable"),
                                   ("coplanarity-four-points", by("coplanarity", four_points), 2,
                                    "at least 5"),
                                   ("unknown-method", by("epipolar"), 2,
                                    '"coplanarity", got "epipolar"')):  # fmt: skip
        c.append(Case(f"solve/pair/{what}", pair_points(edit), code, (says,), "pair.json"))

    def lost_tie(d):  # the last image's rays removed: tie points left with one ray
        img = d["images"][-1]["id"]
        d["observations"] = [o for o in d["observations"] if o["image"] != img]

    c.append(Case("solve/geometry/tie-points-with-one-ray", _block_edit(lost_tie), 2,
                  ("needs at least 2 ray",), I.BLOCK))  # fmt: skip
    return c


# --------------------------------------------------------------------------- successes
def _rename(d: dict, table: str, ref: str, k: int, value: str) -> None:
    """Rename row ``k`` of ``table`` (images/points) and its observations."""
    old = d[table][k]["id"]
    d[table][k]["id"] = value
    for o in d["observations"]:
        if o[ref] == old:
            o[ref] = value


def _no_raw(text: str, name: str):
    def post(folder: Path) -> None:
        html = (folder / name).read_text(encoding="utf-8")
        assert text not in html, f"{text!r} reached the HTML unescaped"

    return post


def accepted() -> list[Case]:
    """Hostile-looking but legal input: must succeed (exit 0) and write only its outputs."""
    c = []

    def ids(table: str, value: str, extra=()):
        def make(f: Path) -> list[str]:
            d = I.doc(I.BLOCK)
            _rename(d, table, "point" if table == "points" else "image", 0, value)
            (f / I.BLOCK).write_text(json.dumps(d), encoding="utf-8")
            return ["solve", str(f / I.BLOCK), *[str(f / e) if "." in e else e for e in extra]]

        return make

    kinds = {  # figures draw image ids; point ids reach the tables (HTML escaping)
        "images": ("mathtext", "mathtext-frac", "html", "newline"),
        "points": ("mathtext", "html"),
    }
    values = {"mathtext": r"$\undefinedmacro$", "html": "<script>x</script>&",
              "newline": "a\nb", "mathtext-frac": r"$\frac{$"}  # fmt: skip
    for table, whats in kinds.items():
        for what in whats:
            post = _no_raw("<script>x</script>", "r.html") if what == "html" else None
            c.append(Case(f"solve/accepted/{table}-id-{what}",
                          ids(table, values[what], ("--report", "r.html")), 0,
                          outputs=("r.html",), post=post))  # fmt: skip
    for what, value in (("dollar", "$"), ("percent-braces", "%s{0}")):
        c.append(Case(f"solve/accepted/images-id-{what}-txt", ids("images", value,
                      ("--report", "r.txt")), 0, outputs=("r.txt",)))  # fmt: skip
    c.append(Case("solve/accepted/id-mathtext-txt", ids("images", r"$\frac{$",
                  ("--report", "r.txt")), 0, outputs=("r.txt",)))  # fmt: skip
    models = ids("images", r"$\undefinedmacro$", ("--method", "models", "--report", "r.html"))
    c.append(Case("solve/accepted/models-report-with-control", models, 0, outputs=("r.html",)))

    def shipped(f: Path) -> list[str]:
        return ["export", "block_strip", "-d", str(f / "out"), "--no-adjust"]

    c.append(Case("export/accepted/shipped-example", shipped, 0, outputs=("out",)))

    def bal_ok(f: Path) -> list[str]:
        _all_inputs(f)
        lines = (f / I.CONTROL).read_text().splitlines()
        rows = [f"pt{int(r.split(',', 1)[0]) - 1},{r.split(',', 1)[1]}" for r in lines[1:]]
        (f / I.CONTROL).write_text("\n".join([lines[0], *rows]) + "\n")
        return ["import-bal", str(f / I.BAL), "--control", str(f / I.CONTROL), "-o",
                str(f / "o.json")]  # fmt: skip

    c.append(Case("import-bal/accepted/with-control", bal_ok, 0, outputs=("o.json",)))

    def colmap_ok(f: Path) -> list[str]:
        _all_inputs(f)
        return ["import-colmap", str(f / "sparse"), "--control", str(f / I.CONTROL), "-o",
                str(f / "o.json")]  # fmt: skip

    c.append(Case("import-colmap/accepted/with-control", colmap_ok, 0, outputs=("o.json",)))
    return c


# --------------------------------------------------------------------------- binary COLMAP
def _binary(file: str, edit):
    def make(f: Path) -> list[str]:
        _all_inputs(f)
        p = f / "sparse_bin" / file
        p.write_bytes(edit(p.read_bytes()))
        return ["import-colmap", str(f / "sparse_bin"), "-o", str(f / "o.json")]

    return make


def _put(offset: int, fmt: str, *values):
    import struct

    def edit(data: bytes) -> bytes:
        packed = struct.pack(fmt, *values)
        return data[:offset] + packed + data[offset + len(packed) :]

    return edit


def binary_models() -> list[Case]:
    """COLMAP binary models: counts, sizes, ids, non-finite and overflowing values, cuts.

    Offsets: cameras.bin ``n`` 0, id 8, model 12, width 16, height 24, params 32;
    points3D.bin ``n`` 0, id 8, X 16; images.bin ``n`` 0, id 8, qvec 12, tvec 44.
    """
    edits = {
        "cameras.bin": {
            "count-2^62": _put(0, "<Q", 2**62), "model-99": _put(12, "<i", 99),
            "width-0": _put(16, "<Q", 0), "focal-nan": _put(32, "<d", float("nan")),
            "focal-negative": _put(32, "<d", -800.0), "cut-20": lambda d: d[:20],
        },
        "points3D.bin": {
            "count-2^62": _put(0, "<Q", 2**62), "x-nan": _put(16, "<d", float("nan")),
            "x-1e308": _put(16, "<d", 1e308), "id-minus-1": _put(8, "<Q", 2**64 - 1),
            "cut-half": lambda d: d[: len(d) // 2],
        },
        "images.bin": {
            "count-2^62": _put(0, "<Q", 2**62), "quaternion-zero": _put(12, "<4d", 0, 0, 0, 0),
            "t-1e308": _put(44, "<3d", 1e308, 1e308, 1e308), "cut-30": lambda d: d[:30],
            "cut-half": lambda d: d[: len(d) // 2],
            "no-nul": lambda d: d[:68] + b"x" * (len(d) - 68),
        },
    }  # fmt: skip
    out = []
    for file, cases in edits.items():
        for what, edit in cases.items():
            out.append(Case(f"import-colmap-bin/{file.split('.')[0]}/{what}", _binary(file, edit),
                            2, (), "sparse_bin"))  # fmt: skip
    return out


# --------------------------------------------------------------------------- measurement CSV
def measurement_csv() -> list[Case]:
    """``import-csv`` tables: cells, numbers, ids, options."""
    good = I.base()[I.MARKS].splitlines()
    head, row = good[0], good[1]
    img, pt = row.split(",")[:2]
    bodies = {
        "cell-over-field-limit": f"{head}\n{img},{pt},{'9' * 200_000},1\n",
        "nul-byte": f"{head}\n{img},{pt},1\x00,2\n",
        "x-nan": f"{head}\n{img},{pt},nan,2\n",
        "x-1e308": "\n".join([head, f"{img},{pt},1e308,2", *good[2:]]) + "\n",
        "megabyte-id": f"{head}\n{'i' * 100_000},{pt},1,2\n",
        "ragged": f"{head}\n{img},{pt},1\n",
        "no-header": "\n".join(good[1:]) + "\n",
        "duplicate": "\n".join([head, row, row, *good[2:]]) + "\n",
        "sigma-negative": "image,point,x,y,sigma\n" + f"{row},-1\n",
    }
    out = []
    for what, text in bodies.items():

        def make(f: Path, text=text) -> list[str]:
            (f / I.MARKS).write_text(text, encoding="utf-8")
            return ["import-csv", str(f / I.MARKS), "--units", "mm", "--c", "152", "-o",
                    str(f / "o.json")]  # fmt: skip

        out.append(Case(f"import-csv/csv/{what}", make, 2, ("line",), I.MARKS))
    for what, extra in (("c-zero", ["--c", "0"]), ("c-nan", ["--c", "nan"]),
                        ("format-negative", ["--format", "-1", "2"]),
                        ("principal-point-inf", ["--principal-point", "inf", "0"])):  # fmt: skip

        def make_opt(f: Path, extra=extra) -> list[str]:
            I.write(f, I.MARKS)
            return ["import-csv", str(f / I.MARKS), "--units", "mm", "--c", "152", "-o",
                    str(f / "o.json"), *extra]  # fmt: skip

        out.append(Case(f"import-csv/argument/{what}", make_opt, 2, (), extra[0]))
    return out


def camera_models() -> list[Case]:
    """cameras[] lens models and image units in pixels (issue #20): one line naming the field."""
    cam = ("cameras", 0)
    out = []
    for what, mutate, says in (
        ("K1-without-model", _set(cam + ("K1",), 1e-3), ('cameras[0].K1', 'needs "model"')),
        ("K1-in-forward-model", lambda d: d["cameras"][0].update(model="forward", K1=1e-3),
         ("cameras[0].K1", "not a term of the forward model")),
        ("free-unknown-name", lambda d: d["cameras"][0].update(model="backward", free=["K4"]),
         ("cameras[0].free",)),
        ("model-and-additional", lambda d: d["cameras"][0].update(model="backward", additional="ebner12"),
         ("cameras[0].additional", "not both")),
        ("sigma-and-free", lambda d: d["cameras"][0].update(model="backward", free=["c"], sigma={"c": 0.1}),
         ("cameras[0].sigma", "give one")),
        ("negative-prior", lambda d: d["cameras"][0].update(model="backward", sigma={"c": -1}),
         ("cameras[0].sigma.c",)),
        ("model-fisheye", _set(cam + ("model",), "fisheye"), ("cameras[0].model",)),
        ("px-without-pixel-size", _set(("units", "image"), "px"), ("units.pixel_size", "mm")),
        ("pixel-size-with-mm", _set(("units", "pixel_size"), 0.005), ("units.pixel_size", '"px" only')),
        ("pixel-size-zero", lambda d: d["units"].update(image="px", pixel_size=0), ("units.pixel_size",)),
    ):  # fmt: skip
        out.append(Case(f"solve/cameras/{what}", _problem(I.BLOCK, mutate), 2, says, I.BLOCK))
    res = "resection_example.json"
    out.append(Case("solve/cameras/model-in-resection",
                    _problem(res, _set(("cameras", 0, "model"), "backward")), 2,
                    ("cameras[0].model", "kind block only"), res))  # fmt: skip
    return out


def degenerate() -> list[Case]:
    """Files that are valid JSON but leave nothing to adjust, or one blunder that spoils all."""
    c = []

    def emptied(*tables: str, cmd: tuple[str, ...] = ("solve",), extra: tuple[str, ...] = ()):
        def make(f: Path) -> list[str]:
            d = I.doc(I.COLUMNAR)
            for t in tables:
                d[t] = {k: [] for k in d[t]}
            (f / I.COLUMNAR).write_text(json.dumps(d), encoding="utf-8")
            return [*cmd, str(f / I.COLUMNAR), *extra]

        return make

    every = ("images", "points", "observations")
    c.append(Case("solve/empty/columnar-no-rows", emptied(*every), 2,
                  ("nothing to adjust", "no images"), I.COLUMNAR))  # fmt: skip
    c.append(Case("solve/empty/columnar-no-rows-models", emptied(*every, extra=("--method", "models")),
                  2, ("nothing to adjust", "no images"), I.COLUMNAR))  # fmt: skip
    c.append(Case("solve/empty/no-points-no-observations", emptied("points", "observations"), 2,
                  ("nothing to adjust", "no points and no observations"), I.COLUMNAR))  # fmt: skip
    c.append(Case("export/empty/columnar-no-rows",
                  emptied(*every, cmd=("export",), extra=("-d", "out")), 2,
                  ("nothing to adjust",), I.COLUMNAR))  # fmt: skip

    def one_blunder(f: Path) -> list[str]:
        from orientviz.io.datasets import dataset_path

        d = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
        o = d["observations"][5]  # image s00_000, tie point g02_001 (three rays)
        o["x"] += 100 * o["sigma"]  # one 100 σ blunder in a block of redundancy 8
        (f / "strip.json").write_text(json.dumps(d), encoding="utf-8")
        return ["solve", str(f / "strip.json")]

    c.append(Case("solve/gross/one-blunder-small-block", one_blunder, 4,
                  ("One gross error explains it", "'g02_001'", "--robust cauchy"),
                  "strip.json"))  # fmt: skip
    return c


def all_cases() -> list[Case]:
    return [
        *special_files(), *garbage_files(), *long_names(), *arguments(), *outputs(), *problem_files(),
        *csv_files(), *colmap_models(), *bal_files(), *geometry(), *accepted(),
        *binary_models(), *measurement_csv(), *camera_models(), *degenerate(),
    ]  # fmt: skip


CASES = all_cases()
