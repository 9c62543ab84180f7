"""Package faces load a name's module on first use and keep the name."""

import subprocess
import sys

import pytest

from orientviz.faces import lazy_names


def test_a_name_loads_its_module_once_and_is_kept():
    code = (
        "import sys, orientviz.report as r\n"
        "assert 'orientviz.report._html' not in sys.modules\n"
        "f = r.html_report\n"
        "assert 'orientviz.report._html' in sys.modules and vars(r)['html_report'] is f\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_an_unknown_name_is_an_attribute_error():
    space: dict = {}
    get = lazy_names("orientviz", {"Block": ".block"}, space)
    assert get("Block").__name__ == "Block" and "Block" in space
    with pytest.raises(AttributeError, match="'orientviz' has no attribute 'Blok'"):
        get("Blok")
