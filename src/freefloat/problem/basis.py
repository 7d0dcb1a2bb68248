"""The path basis: the quintic plus orthonormal polynomials that keep the six end conditions.

On normalised time ``s = t / T`` in [0, 1], with ``x = 2 s - 1`` in [-1, 1], joint i follows

    q_i(s) = q_i0 + (q_i1 - q_i0) (10 s^3 - 15 s^4 + 6 s^5) + sum_n beta_in phi_n(s),
    phi_n(s) = c_n s^3 (1 - s)^3 P_n^(6,6)(2 s - 1),   n = 0, 1, ...
    c_n = sqrt((2 n + 13) (n + 12)! n!) / (n + 6)!

``P_n^(6,6)`` is the Jacobi polynomial (weight ``(1 - x)^6 (1 + x)^6`` on [-1, 1], standard
normalisation ``P_n^(6,6)(1) = C(n + 6, n)``). Why this basis:

- every ``phi_n`` has triple roots at s = 0 and s = 1, so each keeps the six end conditions
  (position, rate and acceleration at both ends) exactly, whatever ``beta``;
- ``phi_0 .. phi_m`` span exactly the polynomials of degree ``6 + m`` with those end conditions
  (the same paths as the monomials ``s^j`` with the end conditions removed, so the roots of the
  attitude equations are the same paths);
- the Jacobi weight ``(1 - x)^6 (1 + x)^6 = 4^6 s^6 (1 - s)^6`` is the square of the factor
  ``s^3 (1 - s)^3``, so the ``phi_n`` are orthonormal in plain L2 on [0, 1]:
  ``int_0^1 phi_n phi_m ds = delta_nm`` (``c_n`` is the inverse norm, from the Jacobi norm
  ``h_n = 2^13 / (2 n + 13) ((n + 6)!)^2 / ((n + 12)! n!)`` and ``ds = dx / 2``). Hence
  ``sum beta_in^2 = int_0^1 |q(s) - q_quintic(s)|^2 ds`` (rad^2): the norm of the free
  parameters is the squared L2 deviation of the joint paths from the quintic;
- orthonormal bases are perfectly conditioned in that norm (Gram matrix the identity at every
  degree); they are evaluated here through their Chebyshev series in ``x``, computed once,
  exactly, by the Jacobi three-term recurrence (no monomial coefficients, whose magnitudes
  grow like 4^n and cancel on evaluation).

Everything is duration independent: ``beta`` is in rad (m for prismatic joints).
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction

import numpy as np

__all__ = [
    "BASIS_NAME",
    "basis_chebyshev",
    "basis_scale",
    "quintic_chebyshev",
    "time_to_x",
]

#: Name of the basis in plan files (``path.basis``), see the module docstring.
BASIS_NAME = "quintic+jacobi66"

_CHEB = np.polynomial.chebyshev


def basis_scale(n: int) -> float:
    """``c_n``: the factor that makes ``phi_n`` unit-norm in L2 on [0, 1] (dimensionless)."""
    log = 0.5 * (math.log(2 * n + 13) + math.lgamma(n + 13) + math.lgamma(n + 1))
    return math.exp(log - math.lgamma(n + 7))


def _times_x(c: list[Fraction]) -> list[Fraction]:
    """Chebyshev coefficients of ``x f(x)`` (exact): ``x T_k = (T_{k-1} + T_{k+1}) / 2``."""
    out = [Fraction(0)] * (len(c) + 1)
    for k, value in enumerate(c):
        if k == 0:
            out[1] += value
        else:
            out[k - 1] += value / 2
            out[k + 1] += value / 2
    return out


@functools.lru_cache(maxsize=64)
def basis_chebyshev(count: int) -> np.ndarray:
    """(count, count + 6) Chebyshev coefficients in ``x = 2 s - 1`` of ``phi_0 .. phi_{count-1}``.

    Row n holds ``phi_n`` (dimensionless, degree n + 6). The Jacobi three-term recurrence
    (``a = b = 6``), ``2 n (n + 12)(2 n + 10) P_n = (2 n + 11)(2 n + 12)(2 n + 10) x P_{n-1}
    - 2 (n + 5)^2 (2 n + 12) P_{n-2}`` with ``P_0 = 1``, ``P_1 = 7 x``, is linear, so it holds
    for ``s^3 (1 - s)^3 P_n`` as well; it is run on those in exact rational arithmetic, then
    rounded once and scaled by ``c_n``: the end conditions hold to the rounding of the
    coefficients (all of size below one). Read-only (shared between callers).
    """
    # s^3 (1 - s)^3 = (1 - x^2)^3 / 64 = (10 T_0 - 15 T_2 + 6 T_4 - T_6) / 2048
    bubble = [Fraction(v, 2048) for v in (10, 0, -15, 0, 6, 0, -1)]
    rows = [bubble, [7 * v for v in _times_x(bubble)]]
    for n in range(2, count):
        lead = Fraction((2 * n + 11) * (2 * n + 12) * (2 * n + 10), 2 * n * (n + 12) * (2 * n + 10))
        back = Fraction(2 * (n + 5) ** 2 * (2 * n + 12), 2 * n * (n + 12) * (2 * n + 10))
        ahead = _times_x(rows[-1])
        rows.append(
            [
                lead * a - back * (rows[-2][k] if k < len(rows[-2]) else 0)
                for k, a in enumerate(ahead)
            ]
        )
    out = np.zeros((count, count + 6))
    for n in range(count):
        out[n, : len(rows[n])] = [basis_scale(n) * float(v) for v in rows[n]]
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=1)
def quintic_chebyshev() -> np.ndarray:
    """Chebyshev coefficients in ``x`` of the quintic blend ``10 s^3 - 15 s^4 + 6 s^5`` (6,)."""
    # with s = (1 + x) / 2 the blend is (8 + 15 x - 10 x^3 + 3 x^5) / 16
    out = _CHEB.poly2cheb(np.array([8.0, 15.0, 0.0, -10.0, 0.0, 3.0]) / 16.0)
    out.flags.writeable = False
    return out


def time_to_x(t: np.ndarray, duration: float) -> np.ndarray:
    """``x = 2 t / T - 1`` in [-1, 1] for times ``t`` (s) on [0, T]."""
    return 2.0 * np.asarray(t, dtype=float) / duration - 1.0
