"""The studio's setting of glibc's allocator: large arrays come from the heap afterwards
(checked in a fresh process by glibc's own count of memory in mmapped blocks)."""

from __future__ import annotations

import ctypes
import ctypes.util
import subprocess
import sys

import pytest

CHILD = """
import ctypes, sys
import numpy as np

class Info(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
        "fordblks", "keepcost")]

libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = Info
if sys.argv[1] == "on":
    from orientviz.viewer.studio_memory import keep_large_arrays_on_heap
    assert keep_large_arrays_on_heap()
before = libc.mallinfo2().hblkhd
x = np.ones(20 << 17)  # 20 MB
print(libc.mallinfo2().hblkhd - before)
"""


def _glibc_mallinfo2() -> bool:
    try:
        return hasattr(ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6"), "mallinfo2")
    except OSError:
        return False


@pytest.mark.skipif(not _glibc_mallinfo2(), reason="glibc ≥ 2.33 (mallinfo2) only")
def test_large_arrays_come_from_the_heap_after_the_setting():
    def mmapped(setting: str) -> int:
        out = subprocess.run(
            [sys.executable, "-c", CHILD, setting], capture_output=True, text=True, check=True
        )
        return int(out.stdout.strip())

    assert mmapped("off") >= 20 << 20  # glibc's start: a 20 MB array is an mmapped block
    assert mmapped("on") == 0  # with the studio's setting it comes from the heap
