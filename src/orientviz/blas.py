"""BLAS thread limits for work made of many small matrix products.

OpenBLAS starts one worker thread per core. In a bundle's iteration, its precision pass, a
design update or the radar figure's hundreds of tiny adjustments the products are small
(blocks of 3 … a few hundred rows), and the worker threads mostly wait for each other: on a
busy machine they multiply the CPU time without shortening the wall time
(benchmarks/README.md). :func:`blas_threads` holds BLAS to a given number of threads for a
block of code and restores the previous limits afterwards.
"""

from __future__ import annotations

import contextlib
import functools
import os

import threadpoolctl as _threadpoolctl
from threadpoolctl import ThreadpoolController

__all__ = ["blas_threads"]


def blas_threads(n: int | None = 1) -> contextlib.AbstractContextManager:
    """A context running BLAS on at most ``n`` threads.

    Parameters
    ----------
    n : int or None, optional
        Thread limit (default 1); None leaves BLAS as it is.

    Returns
    -------
    contextlib.AbstractContextManager
        Restores the previous limits on exit. It does nothing when ``n`` is None, or when
        ``n`` is 1 and the environment already holds BLAS to one thread
        (``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` set to 1).

    Examples
    --------
    >>> import numpy as np
    >>> with blas_threads(1):
    ...     _ = np.ones((3, 3)) @ np.ones((3, 3))
    """
    one_already = "1" in (os.environ.get("OPENBLAS_NUM_THREADS"), os.environ.get("OMP_NUM_THREADS"))
    if n is None or (n == 1 and one_already):
        return contextlib.nullcontext()
    return _controller().limit(limits=n, user_api="blas")


class _BlasController(ThreadpoolController):
    """A :class:`~threadpoolctl.ThreadpoolController` that inspects, among the loaded
    libraries, only those whose file name is a BLAS library's (threadpoolctl's own
    prefixes): its scan resolves the path of every loaded library (about 80 in a solve,
    each by file-system calls) before it looks at the name. On other platforms, or a
    threadpoolctl without this hook, the full scan runs."""

    def _find_libraries_with_linux(self) -> None:
        prefixes = tuple(
            p
            for c in _threadpoolctl._ALL_CONTROLLERS
            if c.user_api == "blas"
            for p in c.filename_prefixes
        )
        with open("/proc/self/maps", "rb") as f:
            maps = f.read()
        for path in set(self._PATH_RE.findall(maps)):
            path = path.decode("utf-8")
            if os.path.basename(path).lower().startswith(prefixes):
                self._make_controller_from_path(path)


@functools.cache
def _controller() -> ThreadpoolController:
    """The thread pools of the loaded BLAS libraries, found once per process."""
    import scipy.linalg  # noqa: F401  loads SciPy's own BLAS before the scan, so it is held too

    try:
        return _BlasController()
    except (AttributeError, OSError):  # a threadpoolctl whose internals differ
        return ThreadpoolController()
