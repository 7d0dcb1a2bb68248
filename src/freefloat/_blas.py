"""BLAS on one thread while freefloat works.

freefloat's linear algebra is many tiny products and solves (a few joints, a few dozen rows):
threaded BLAS only adds thread wake-ups, and on a busy machine waits for a free core (an
SLSQP run took 2 to 20 times longer on a loaded 2-core machine). :func:`one_blas_thread` limits
the process's BLAS pools to one thread for the duration of a call and restores them after
(threadpoolctl); the sweep's worker processes get the same through their environment.
"""

from __future__ import annotations

from typing import Any

__all__ = ["one_blas_thread"]


def one_blas_thread() -> Any:
    """A context in which BLAS runs on one thread (the pools found when it is entered)."""
    from threadpoolctl import threadpool_limits  # imported when first used

    return threadpool_limits(limits=1, user_api="blas")
