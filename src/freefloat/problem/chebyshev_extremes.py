"""Extremes of Chebyshev series on [-1, 1], many series at once (exact up to rounding).

A polynomial's extremes on an interval are at its ends or at real roots of its derivative
inside. The roots are the eigenvalues of the derivative's colleague matrix (as NumPy's
``chebroots`` finds them); series of one degree share one batched eigenvalue call.
"""

from __future__ import annotations

import numpy as np

__all__ = ["series_extremes"]

_CHEB = np.polynomial.chebyshev


def series_extremes(series: np.ndarray) -> np.ndarray:
    """(N, 4) ``[min, x_min, max, x_max]`` of each row's Chebyshev series on [-1, 1].

    Candidates are the ends and the real roots inside of each row's derivative: the
    eigenvalues of its colleague matrix (as NumPy's ``chebroots``), rows of one degree in one
    batch. Ties go to the first candidate in the order ends, then roots ascending.
    """
    count, width = series.shape
    slope = _CHEB.chebder(series.T).T if width > 1 else np.zeros((count, 0))
    nonzero = np.column_stack([np.ones(count, dtype=bool), slope != 0.0])
    lengths = slope.shape[1] - nonzero[:, ::-1].argmax(axis=1)  # without trailing zeros
    x = np.full((count, max(width - 2, 0) + 2), np.nan)
    x[:, 0], x[:, 1] = -1.0, 1.0
    for length in set(lengths.tolist()) - {0, 1}:
        rows = np.flatnonzero(lengths == length)
        if length == 2:
            roots = (-slope[rows, 0] / slope[rows, 1])[:, None].astype(complex)
        else:
            colleague = _colleagues(slope[rows, :length])[:, ::-1, ::-1]
            roots = np.sort(np.linalg.eigvals(colleague), axis=1)
        inside = (np.abs(roots.imag) <= 1e-9) & (-1.0 < roots.real) & (roots.real < 1.0)
        x[rows, 2 : 2 + roots.shape[1]] = np.where(inside, roots.real, np.nan)
    # inside roots first, in ascending order, after the two ends
    x[:, 2:] = np.sort(x[:, 2:], axis=1)
    valid = ~np.isnan(x)
    vander = _CHEB.chebvander(np.where(valid, x, 0.0), width - 1)
    values = np.einsum("ncw,nw->nc", vander, series)
    lo = np.where(valid, values, np.inf).argmin(axis=1)
    hi = np.where(valid, values, -np.inf).argmax(axis=1)
    rows = np.arange(count)
    return np.column_stack([values[rows, lo], x[rows, lo], values[rows, hi], x[rows, hi]])


def _colleagues(series: np.ndarray) -> np.ndarray:
    """(G, n, n) colleague matrices of G Chebyshev series of degree n.

    NumPy's ``chebcompanion``, entry for entry, for many series at once.
    """
    n = series.shape[1] - 1
    scale = np.array([1.0] + [np.sqrt(0.5)] * (n - 1))
    band = np.full(n - 1, 0.5)
    band[0] = np.sqrt(0.5)
    template = np.diag(band, 1) + np.diag(band, -1)
    out = np.repeat(template[None], len(series), axis=0)
    out[:, :, -1] -= (series[:, :-1] / series[:, -1:]) * (scale / scale[-1]) * 0.5
    return out
