"""BLAS on one thread while freefloat works.

freefloat's linear algebra is many tiny products and solves (a few joints, a few dozen rows):
threaded BLAS only adds thread wake-ups, and on a busy machine waits for a free core (an
SLSQP run took 2 to 20 times longer on a loaded 2-core machine). :func:`one_blas_thread` limits
the process's BLAS pools to one thread for the duration of a call and restores them after
(threadpoolctl); the sweep's worker processes get the same through their environment. The
limit is process-wide: calls made concurrently from several threads share it.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

__all__ = ["one_blas_thread"]


@lru_cache(maxsize=1)
def _pools() -> Any:
    """The process's thread pools, found once.

    NumPy's and SciPy's BLAS are loaded with freefloat; looking them up again would cost
    about a millisecond per call.
    """
    from threadpoolctl import ThreadpoolController  # imported when first used

    return ThreadpoolController()


def one_blas_thread() -> Any:
    """A context in which BLAS runs on one thread."""
    return _pools().limit(limits=1, user_api="blas")
