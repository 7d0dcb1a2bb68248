"""The cheap search's path brought inside clearance instead of a second search.

Truth here: every pair's distance measured densely along the finished path (no pair spared),
the plan's own independent verification, and the search with clearance imposed from the start
(another algorithm: a continuation whose every step keeps the margin).
"""

from __future__ import annotations

import dataclasses

import numpy as np

import freefloat as ff
import freefloat.solvers.lazy_search as lazy_search
from freefloat.physics import attitude as att
from freefloat.problem.constraints import scenario_constraints
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.solvers.search import search

from conftest import ROOT

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"


def _turned(degrees_about_z: float) -> ff.Scenario:
    """The Panda servicer, its goal turned about z from the plain quintic path's attitude."""
    scenario = ff.Scenario.from_toml(PANDA)
    problem = ff.problem_from_scenario(scenario, extra=[1, 1, 1] + [0] * (scenario.robot.n - 3))
    origin = problem.achieved(np.zeros(problem.n_free))
    turn = att.quat_exp(np.radians([0.0, 0.0, degrees_about_z]))
    return dataclasses.replace(scenario, goal_attitude=att.quat_multiply(origin, turn))


def _coefficients(found) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.asarray(found.solution.beta, dtype=float)


def test_a_path_that_dips_into_the_margin_is_brought_inside_and_verified():
    """The Panda goal 3 deg about z: the path within the joint limits alone breaks clearance;
    it is brought inside by least-norm corrections. Every pair measured at 2001 instants of
    the plan keeps the margin, the plan verifies, and it deviates from the quintic no more
    than the path of the search with clearance imposed from the start."""
    scenario = _turned(3.0)
    plan = ff.plan(scenario)
    assert any("brought inside by" in step for step in plan.solver.tried)
    assert plan.verification.passed
    robot = scenario.resolved().robot
    everything = CollisionModel(robot, known_srdf(robot))
    q = plan.path().evaluate(np.linspace(0.0, plan.duration, 2001)).q
    smallest = min(float(everything.distances(row).values.min()) for row in q)
    margin = scenario.safety.margin
    assert smallest >= margin - 1e-6
    resolved = scenario.resolved()
    imposed = search(resolved, ff.SolveOptions(), scenario_constraints(resolved))
    deviation = float(_coefficients(imposed) @ _coefficients(imposed))
    assert plan.quality.deviation_rms_deg <= np.degrees(np.sqrt(deviation)) + 1e-9


def test_a_path_brought_inside_that_breaks_a_lazy_limit_is_not_used(monkeypatch):
    """When the path brought inside breaks a lazy constraint (made to, here), the search with
    clearance imposed runs, as it did before there was that path: the result is its path,
    to the bit."""
    scenario = _turned(3.0).resolved()
    constraints = scenario_constraints(scenario)
    eager = [c for c in constraints if not c.lazy]
    real = lazy_search.broken_by

    def veto(found, checked):  # type: ignore[no-untyped-def]
        if any("brought inside by" in step for step in found.tried):
            return "joint_effort_limits (made to break)"
        return real(found, checked)

    monkeypatch.setattr(lazy_search, "broken_by", veto)
    found, imposed = lazy_search.search_lazily(scenario, ff.SolveOptions(), constraints)
    assert not any("brought inside by" in step for step in found.tried)
    assert [c.name for c in imposed] == [c.name for c in eager]
    again = search(scenario, ff.SolveOptions(), eager)
    np.testing.assert_array_equal(_coefficients(found), _coefficients(again))


def test_a_path_that_cannot_be_brought_inside_gets_the_second_search(monkeypatch):
    """Corrections that fail (none honours clearance: made to, here) leave the search with
    clearance imposed, whose path is returned (another path than the one brought inside)."""
    scenario = _turned(3.0).resolved()
    constraints = scenario_constraints(scenario)
    eager = [c for c in constraints if not c.lazy]
    inside, _ = lazy_search.search_lazily(scenario, ff.SolveOptions(), constraints)
    original = lazy_search.nearest_root_within

    def failing(*args, **kwargs):  # type: ignore[no-untyped-def]
        return dataclasses.replace(original(*args, **kwargs), honoured=False)

    monkeypatch.setattr(lazy_search, "nearest_root_within", failing)
    found, _ = lazy_search.search_lazily(scenario, ff.SolveOptions(), constraints)
    assert not any("brought inside by" in step for step in found.tried)
    again = search(scenario, ff.SolveOptions(), eager)
    np.testing.assert_array_equal(_coefficients(found), _coefficients(again))
    assert not np.allclose(_coefficients(inside), _coefficients(again), atol=1e-3)


def test_a_goal_the_second_search_refuses_plans_by_the_corrections():
    """The Panda servicer's goal at yaw 60 deg (zyx 60, 0, 0 deg): the search with
    clearance imposed from the start stops short at both freedom levels; the path found within
    the joint limits at the second level, brought inside clearance, plans (verified), and
    every pair measured at 501 instants keeps the margin."""
    import math

    scenario = ff.Scenario.from_toml(PANDA)
    far = dataclasses.replace(scenario, goal_attitude=ff.quat_from_zyx(math.radians(60.0), 0, 0))
    resolved = far.resolved()
    constraints = scenario_constraints(resolved)
    eager = [c for c in constraints if not c.lazy]
    try:
        search(resolved, ff.SolveOptions(), eager)
    except ff.UnreachableGoalError as refused:
        assert refused.reached_fraction < 1.0
    else:
        raise AssertionError("the search with clearance imposed reached the goal")
    plan = ff.plan(far)
    assert any("brought inside by" in step for step in plan.solver.tried)
    assert plan.verification.passed
    robot = resolved.robot
    everything = CollisionModel(robot, known_srdf(robot))
    q = plan.path().evaluate(np.linspace(0.0, plan.duration, 501)).q
    smallest = min(float(everything.distances(row).values.min()) for row in q)
    assert smallest >= far.safety.margin - 1e-6
