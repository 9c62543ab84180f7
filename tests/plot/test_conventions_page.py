"""The numbers printed on docs/conventions.md agree with the library."""

from __future__ import annotations

import pathlib
import re

import numpy as np

from orientviz.rotation import convert_sequence, matrix_from_opk
from orientviz.units import RHO_C, RHO_CC, RHO_GON, to_rad

PAGE = pathlib.Path(__file__).parents[2] / "docs" / "conventions.md"


def test_same_matrix_example():
    text = PAGE.read_text(encoding="utf-8")
    m = re.search(r"R=\\begin\{pmatrix\}(.*?)\\end\{pmatrix\}", text, re.S)
    printed = np.array([[float(v) for v in row.split("&")] for row in m.group(1).split(r"\\")])
    a = to_rad(np.array([10.0, 20.0, 30.0]), "gon")
    np.testing.assert_allclose(printed, matrix_from_opk(*a), atol=5e-7)  # printed to 6 decimals
    pok = re.search(r"ω = ([\d.]+), φ = ([\d.]+), κ = ([\d.]+) gon in φ-ω-κ", text)
    want = np.degrees(np.array(convert_sequence(*a, "opk", "pok"))) * 400 / 360
    np.testing.assert_allclose([float(g) for g in pok.groups()], want, atol=5e-5)  # 4 decimals


def test_rho_table():
    text = PAGE.read_text(encoding="utf-8")
    assert f"{RHO_GON:.4f} gon" in text
    assert f"{RHO_C:.2f} c" in text
    assert f"{RHO_CC:,.1f} cc".replace(",", " ") in text
    assert (PAGE.parent / "figures" / "conventions.png").is_file()
