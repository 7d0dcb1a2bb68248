"""Brent's bounded search against closed forms and SciPy's bounded scalar search."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from freefloat.problem.scalar_minimum import scalar_minimum


@pytest.mark.parametrize(
    ("function", "low", "high", "where"),
    [
        (lambda x: (x - 2.0) ** 2 + 1.0, 0.0, 5.0, 2.0),  # a parabola's vertex
        (math.cos, 2.0, 4.0, math.pi),
        (lambda x: abs(x - 1.0), 0.0, 3.0, 1.0),  # a kink: golden-section steps
        (lambda x: x, 0.0, 1.0, 0.0),  # monotone: the lower end, approached
        (lambda x: math.exp(x) - 3.0 * x, 0.0, 2.0, math.log(3.0)),
    ],
)
def test_the_minimum_is_found_where_the_closed_form_puts_it(function, low, high, where) -> None:
    found = scalar_minimum(function, low, high, 1e-10)
    assert found.converged
    assert found.x == pytest.approx(where, abs=1e-7)
    assert found.value == function(found.x)
    assert low < found.x < high  # the ends are never evaluated


def test_it_agrees_with_scipys_bounded_search_on_smooth_unimodal_functions() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        a, c = rng.uniform(0.1, 3.0), rng.uniform(0.0, 0.4)  # convex: one minimum, inside
        low = rng.uniform(-1.0, 0.0)
        high = low + rng.uniform(0.5, 2.0)
        b = rng.uniform(low + 0.2, high - 0.2)

        def f(x: float, a=a, b=b, c=c) -> float:
            return a * (x - b) ** 2 + c * (x - b) ** 4 + 0.05 * math.sin(x)

        ours = scalar_minimum(f, low, high, 1e-9)
        theirs = minimize_scalar(f, bounds=(low, high), method="bounded", options={"xatol": 1e-9})
        assert ours.value <= theirs.fun + 1e-12
        assert ours.x == pytest.approx(theirs.x, abs=1e-6)
        assert ours.evaluations <= theirs.nfev + 5


def test_the_budget_is_a_count_and_is_reported() -> None:
    calls = []

    def f(x: float) -> float:
        calls.append(x)
        return abs(x - 0.123456789)

    found = scalar_minimum(f, 0.0, 1.0, 1e-12, max_evaluations=6)
    assert not found.converged
    assert found.evaluations == len(calls) == 6
    assert found.value == min(f(x) for x in calls[:6])


def test_an_interval_of_one_point_is_that_point() -> None:
    found = scalar_minimum(math.cos, 2.0, 2.0, 1e-9)
    assert (found.x, found.value, found.evaluations, found.converged) == (
        2.0,
        math.cos(2.0),
        1,
        True,
    )


@pytest.mark.parametrize(
    ("low", "high", "tolerance", "budget", "message"),
    [
        (1.0, 0.5, 1e-9, 10, r"low <= high, got \[1.0, 0.5\]"),
        (0.0, 1.0, 0.0, 10, "x_tolerance > 0"),
        (0.0, 1.0, 1e-9, 0, "max_evaluations >= 1"),
    ],
)
def test_bad_arguments_are_refused_naming_them(low, high, tolerance, budget, message) -> None:
    with pytest.raises(ValueError, match=message):
        scalar_minimum(math.cos, low, high, tolerance, budget)
