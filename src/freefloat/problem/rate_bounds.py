"""Bounds of a path's joint rates over time intervals, from its polynomials alone."""

from __future__ import annotations

import numpy as np

from .paths import JointPolynomials

__all__ = ["rate_bounds"]


def rate_bounds(path: JointPolynomials, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
    """(K, N) bounds of every ``|qd_j|`` over each ``[t0, t1]`` (rad/s or m/s).

    The Taylor series of a polynomial about the interval's middle is finite: ``|qd(mid + s)|``
    is at most the sum over the orders ``o >= 1`` of ``|q^(o)(mid)| h^(o-1) / (o-1)!``, ``h``
    half the interval; padded by a relative 1e-9 for rounding.
    """
    half = 0.5 * (t1 - t0)
    x = (t0 + t1) / path.duration - 1.0
    width = path.coefficients.shape[1]
    vander = np.polynomial.chebyshev.chebvander(x, width - 1)
    bound = np.zeros((len(x), path.coefficients.shape[0]))
    factor = np.ones(len(x))
    for order in range(1, width):
        bound += np.abs(vander @ path.derivative(order).T) * factor[:, None]
        factor = factor * half / order
    return bound * (1.0 + 1e-9)
