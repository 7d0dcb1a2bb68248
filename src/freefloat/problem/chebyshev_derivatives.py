"""Linear maps from Chebyshev coefficients to those of their derivatives.

A Chebyshev series in ``x`` on [-1, 1] differentiates to another one: ``T_n'`` is
``n (T_0 + 2 T_2 + 2 T_4 + ...)`` up to ``T_{n-1}`` for odd ``n``, ``2 n (T_1 + T_3 + ...)`` for
even ``n``. As matrices (rows: the derivative's coefficients, columns: the series'), each
derivative of a batch of series is one product.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["derivative_maps", "unit_interval_maps"]

_CHEB = np.polynomial.chebyshev


@lru_cache(maxsize=16)
def derivative_maps(width: int) -> tuple[np.ndarray, ...]:
    """Per order 0 to ``width - 1``, the (width, width) map to the order-th derivative in x.

    The first is written out from the closed form above (integer entries, exact); each higher
    order is its power: exact while its entries stay below 2**53 (to degree 14), beyond that
    rounded to a relative 1e-16, as any product of the coefficients is.
    """
    first = np.zeros((width, width))
    for n in range(1, width):
        for k in range(n - 1, -1, -2):  # n - k odd
            first[k, n] = n if k == 0 else 2 * n
    powers = [np.eye(width)]
    for _ in range(1, width):
        powers.append(first @ powers[-1])
    return tuple(powers)


@lru_cache(maxsize=16)
def unit_interval_maps(width: int) -> tuple[np.ndarray, np.ndarray]:
    """(width, width) maps from Chebyshev coefficients in x = 2 s - 1 to those of d/ds, d^2/ds^2.

    As numpy's ``chebder`` gives them (the path family's samples are made with these).
    """
    eye = np.eye(width)
    first = np.zeros((width, width))
    second = np.zeros((width, width))
    if width > 1:
        first[: width - 1] = _CHEB.chebder(eye, 1, scl=2.0)
    if width > 2:
        second[: width - 2] = _CHEB.chebder(eye, 2, scl=2.0)
    return first, second
