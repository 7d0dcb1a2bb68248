"""The smallest value of a function of one variable on an interval, without derivatives.

Brent's method (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973,
chapter 5): golden-section steps, replaced by a step to the vertex of the parabola through
the three best points whenever that step is small enough to trust and stays inside. It finds
the minimum of a unimodal function to ``x_tolerance`` (plus a relative ``sqrt(eps)``) in a
few evaluations more than the parabola needs; on a function with several local minima it
finds one of them. The ends of the interval are never evaluated.

The clearance and end-effector checks refine each sampled local extreme with it. Written
here (not SciPy's bounded scalar search) so that a check does not pay SciPy's optimiser
import, about 0.2 s, at its first use in a process.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["MAX_EVALUATIONS", "ScalarMinimum", "scalar_minimum"]

#: Evaluations of one search at most (a count).
MAX_EVALUATIONS = 500
#: The golden-section fraction ``(3 - sqrt 5) / 2``.
_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))
#: Relative part of the tolerance (the square root of the double's epsilon).
_RELATIVE = math.sqrt(2.220446049250313e-16)


@dataclass(frozen=True)
class ScalarMinimum:
    """Where a search on an interval ended.

    Attributes:
        x: the best point found (the unit of the interval).
        value: the function's value there.
        evaluations: the function's evaluations (a count).
        converged: the interval left holds ``x`` within the tolerance (else the evaluation
            budget ran out first).
    """

    x: float
    value: float
    evaluations: int
    converged: bool


def scalar_minimum(
    function: Callable[[float], float],
    low: float,
    high: float,
    x_tolerance: float,
    max_evaluations: int = MAX_EVALUATIONS,
) -> ScalarMinimum:
    """A local minimum of ``function`` strictly between ``low`` and ``high``.

    Args:
        function: ``f(x)``, a finite float for every ``x`` in the interval.
        low: the interval's lower end (any unit).
        high: its upper end, ``>= low`` (equal: that one point, evaluated).
        x_tolerance: the search stops when ``x`` is known within about this (same unit;
            ``> 0``).
        max_evaluations: evaluations at most (a count, ``>= 1``).

    Raises:
        ValueError: an empty interval, a tolerance not above 0 or a budget below 1.
    """
    if not high >= low:
        raise ValueError(f"scalar_minimum needs low <= high, got [{low}, {high}]")
    if high == low:  # one point: nothing to search
        return ScalarMinimum(float(low), float(function(float(low))), 1, True)
    if not x_tolerance > 0.0 or max_evaluations < 1:
        raise ValueError("scalar_minimum needs x_tolerance > 0 and max_evaluations >= 1")
    a, b = float(low), float(high)
    x = w = v = a + _GOLDEN * (b - a)
    fx = fw = fv = float(function(x))
    count, step, before = 1, 0.0, 0.0  # the last step and the one before it
    while True:
        middle = 0.5 * (a + b)
        tolerance = _RELATIVE * abs(x) + x_tolerance / 3.0
        if abs(x - middle) <= 2.0 * tolerance - 0.5 * (b - a):
            return ScalarMinimum(x, fx, count, True)
        if count >= max_evaluations:
            return ScalarMinimum(x, fx, count, False)
        step, before = _next_step(a, b, x, w, v, fx, fw, fv, step, before, tolerance)
        u = x + (step if abs(step) >= tolerance else math.copysign(tolerance, step))
        fu = float(function(u))
        count += 1
        if fu <= fx:  # u is the new best: the interval shrinks to the side of x it lies
            if u < x:
                b = x
            else:
                a = x
            v, fv, w, fw, x, fx = w, fw, x, fx, u, fu
            continue
        if u < x:
            a = u
        else:
            b = u
        if fu <= fw or w == x:
            v, fv, w, fw = w, fw, u, fu
        elif fu <= fv or v in (x, w):
            v, fv = u, fu


def _next_step(
    a: float,
    b: float,
    x: float,
    w: float,
    v: float,
    fx: float,
    fw: float,
    fv: float,
    step: float,
    before: float,
    tolerance: float,
) -> tuple[float, float]:
    """The next step from ``x`` and the step to remember as the one before it.

    The parabola through ``(x, fx)``, ``(w, fw)``, ``(v, fv)`` is used when its vertex lies
    inside ``(a, b)``, not within ``2 tolerance`` of an end, and the step to it is shorter
    than half the step before last (so the steps shrink); else a golden-section step into
    the larger part of the interval.
    """
    middle = 0.5 * (a + b)
    if abs(before) > tolerance:
        r = (x - w) * (fx - fv)
        q = (x - v) * (fx - fw)
        p = (x - v) * q - (x - w) * r
        q = 2.0 * (q - r)
        if q > 0.0:
            p = -p
        q = abs(q)
        if abs(p) < abs(0.5 * q * before) and q * (a - x) < p < q * (b - x):
            parabolic = p / q
            u = x + parabolic
            if u - a < 2.0 * tolerance or b - u < 2.0 * tolerance:
                parabolic = tolerance if x < middle else -tolerance
            return parabolic, step
    part = (b - x) if x < middle else (a - x)
    return _GOLDEN * part, part
