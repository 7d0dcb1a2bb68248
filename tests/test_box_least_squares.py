"""Box least squares against closed forms and SciPy's least-squares solvers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares, lsq_linear

from freefloat.problem.box_least_squares import box_least_squares

INF = np.array([math.inf, math.inf])


def _rosenbrock(x: np.ndarray) -> np.ndarray:
    return np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])


def test_rosenbrocks_valley_ends_at_its_closed_form_minimum() -> None:
    found = box_least_squares(_rosenbrock, np.array([-1.2, 1.0]), -INF, INF)
    np.testing.assert_allclose(found.x, [1.0, 1.0], atol=1e-10)
    assert found.norm < 1e-12
    assert found.converged
    assert found.evaluations >= found.iterations * 5  # 4 differences and a trial at least


def test_a_bound_that_cuts_the_valley_agrees_with_scipys_trust_region_reflective() -> None:
    lower, upper = np.array([-2.0, -2.0]), np.array([0.5, 2.0])
    ours = box_least_squares(_rosenbrock, np.array([-1.2, 1.0]), lower, upper)
    theirs = least_squares(_rosenbrock, [-1.2, 1.0], bounds=(lower, upper), xtol=1e-15)
    assert ours.x[0] == 0.5  # on the bound
    np.testing.assert_allclose(ours.x, theirs.x, atol=1e-7)
    assert ours.norm == pytest.approx(float(np.linalg.norm(theirs.fun)), rel=1e-9)


def test_a_linear_problem_in_a_box_matches_scipys_lsq_linear() -> None:
    rng = np.random.default_rng(5)
    for _ in range(20):
        a, b = rng.normal(size=(8, 4)), rng.normal(size=8)
        lower, upper = np.full(4, -0.3), np.full(4, 0.4)
        ours = box_least_squares(lambda x, a=a, b=b: a @ x - b, np.zeros(4), lower, upper)
        theirs = lsq_linear(a, b, bounds=(lower, upper), tol=1e-14)
        np.testing.assert_allclose(ours.x, theirs.x, atol=1e-7)
        assert np.all((ours.x >= lower) & (ours.x <= upper))


def test_an_underdetermined_system_is_met_nearest_its_start() -> None:
    # Levenberg's steps from x0 stay in the row space of A: the solution is the minimum-norm
    # change x0 + A^+ (b - A x0), the pseudo-inverse's closed form.
    rng = np.random.default_rng(8)
    a, b, start = rng.normal(size=(2, 5)), rng.normal(size=2), rng.normal(size=5)
    found = box_least_squares(lambda x: a @ x - b, start, np.full(5, -np.inf), np.full(5, np.inf))
    nearest = start + np.linalg.pinv(a) @ (b - a @ start)
    np.testing.assert_allclose(found.x, nearest, atol=1e-9)


def test_the_target_stops_the_search_early_and_a_budget_is_a_count() -> None:
    start = np.array([-1.2, 1.0])
    loose = box_least_squares(_rosenbrock, start, -INF, INF, target=1e-3)
    full = box_least_squares(_rosenbrock, start, -INF, INF)
    assert 1e-12 < loose.norm <= 1e-3
    assert loose.iterations < full.iterations
    capped = box_least_squares(_rosenbrock, start, -INF, INF, max_iterations=3)
    assert capped.iterations == 3 and not capped.converged


def test_a_start_outside_the_box_and_an_unknown_without_room_are_handled() -> None:
    # x0 is held at 0.25 by its box; x1 starts outside its box and is brought in: the best
    # x1 for (x0 - 1, x1 - 3) is its upper bound 2, by the closed form.
    found = box_least_squares(
        lambda x: np.array([x[0] - 1.0, x[1] - 3.0]),
        np.array([0.25, 9.0]),
        np.array([0.25, -2.0]),
        np.array([0.25, 2.0]),
    )
    assert found.x.tolist() == [0.25, 2.0]
    assert found.norm == pytest.approx(math.hypot(0.75, 1.0), rel=1e-15)
    assert found.converged
