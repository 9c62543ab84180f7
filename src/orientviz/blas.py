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


@functools.cache
def _controller() -> ThreadpoolController:
    """The thread pools of the loaded BLAS libraries, found once per process (the scan
    walks every loaded shared library)."""
    import scipy.linalg  # noqa: F401  loads SciPy's own BLAS before the scan, so it is held too

    return ThreadpoolController()
