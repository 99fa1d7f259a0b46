"""Thread settings for the package's small dense linear algebra.

The fits of the package solve tall, narrow least-squares problems (about 1,500 residuals
and at most a dozen variables): ``scipy.optimize.least_squares`` takes an SVD of that
Jacobian at every iteration. A multi-threaded BLAS gains nothing on such shapes and loses
much when the cores are shared (several records diagnosed at once, or any other load): its
threads spin while waiting for each other. Measured on this project's 2-core test machine
under load, ``scipy.linalg.svd`` of a 1,500 x 8 matrix: 0.08 ms with one BLAS thread,
0.33 ms with two; a whole diagnosis of the ARTS damper record ``ds1_1Hz_22lb``: 9.2 s of
CPU with one thread against 16.3 s with two (``benchmarks/bench_real_damper.py``).

:func:`one_blas_thread` limits the BLAS thread pools for the duration of a fit, through
threadpoolctl (the library scikit-learn uses for the same purpose), and restores them after.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Context manager: at most one BLAS thread inside, the previous limits restored after."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
