"""Large temporary arrays of the studio kept on the C heap (glibc's ``mallopt``).

Every new design of a 1 000-image block allocates and frees arrays of 1–30 MB (the band
of the inverse, its index arrays, the rays' terms). glibc serves an allocation above its
*mmap threshold* with fresh pages from the kernel, which are zeroed at their first touch,
and gives freed memory above the *trim threshold* back at once. The threshold adapts to
what the process freed before, so how long a design takes depends on what ran before it
in the same process (the measurements are in benchmarks/README.md, the design studio).
:func:`keep_large_arrays_on_heap` fixes both thresholds for the process: arrays up to
32 MB come from the heap, and up to :data:`TRIM_BYTES` of freed heap stay with the
process for the next design. ``orientviz view design`` sets it when the studio's view is
built (:class:`orientviz.viewer.studio_panel.StudioView`); it is a setting of the whole
process (a Jupyter kernel that shows the studio keeps it too).
"""

from __future__ import annotations

import ctypes
import ctypes.util

#: glibc's mallopt parameters (malloc.h)
M_TRIM_THRESHOLD: int = -1
M_MMAP_THRESHOLD: int = -3
#: Allocations up to this size come from the heap (glibc's largest allowed value, 64-bit).
MMAP_BYTES: int = 32 << 20
#: Freed heap kept by the process before it is returned to the kernel.
TRIM_BYTES: int = 128 << 20

_done: bool | None = None


def keep_large_arrays_on_heap() -> bool:
    """Set glibc's mmap threshold to :data:`MMAP_BYTES` and its trim threshold to
    :data:`TRIM_BYTES` for this process (once).

    Returns
    -------
    bool
        True if glibc took both settings; False where there is no ``mallopt`` (not glibc:
        macOS, Windows, musl) — then nothing changes.
    """
    global _done
    if _done is None:
        try:
            libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
            mallopt = libc.mallopt
            mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
            mallopt.restype = ctypes.c_int
            _done = bool(mallopt(M_MMAP_THRESHOLD, MMAP_BYTES)) and bool(
                mallopt(M_TRIM_THRESHOLD, TRIM_BYTES)
            )
        except (OSError, AttributeError):
            _done = False
    return _done
