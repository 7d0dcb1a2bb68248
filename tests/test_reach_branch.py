"""The reach estimate's shortcut: a continuation towards a nearer goal about the same axis
takes the traced branch's steps up to where it parts from it, so the confirmation resumes
there. Checked against runs made from scratch (the planner's own), not against the shortcut."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics.attitude import quat_exp, quat_multiply
from freefloat.problem.build import problem_from_scenario
from freefloat.problem.constraints import default_constraints
from freefloat.solvers.continuation import track
from freefloat.solvers.options import SolveOptions
from freefloat.solvers.reach import _parting
from freefloat.solvers.tracked import BranchPoint

SCENARIOS = Path(__file__).resolve().parents[1] / "robots" / "scenarios"


@pytest.fixture(scope="module")
def ur5_problem():
    shipped = ff.Scenario.from_toml(SCENARIOS / "ur5_servicer.toml")
    scenario = replace(shipped, safety=replace(shipped.safety, check=False)).resolved()
    return problem_from_scenario(scenario, extra=[2] * scenario.robot.n, check_bounds=False)


def _towards(problem, axis: np.ndarray, angle: float):
    quintic = problem.achieved(np.zeros(problem.n_free))
    return problem.with_goal(quat_multiply(quintic, quat_exp(angle * axis)))


def test_a_run_towards_a_nearer_goal_shares_the_traced_steps_up_to_the_parting_point(
    ur5_problem,
) -> None:
    axis = np.array([1.0, 1.0, 1.0]) / math.sqrt(3.0)
    far, near = math.radians(25.0), math.radians(16.0)
    options = SolveOptions(max_evaluations=400)
    long: list[BranchPoint] = []
    track(_towards(ur5_problem, axis, far), default_constraints(), options, trace=long)
    short: list[BranchPoint] = []
    result = track(_towards(ur5_problem, axis, near), default_constraints(), options, trace=short)
    assert result.reached and len(long) > 3
    part = _parting(long, near)
    assert 0.0 < part.turn < near
    # Every point of the long run up to the parting point is one of the short run's too.
    shared = [p for p in long if p.turn <= part.turn]
    assert len(shared) >= 2
    for a, b in zip(shared, short, strict=False):
        assert b.turn == pytest.approx(a.turn, abs=1e-12)
        np.testing.assert_allclose(b.beta, a.beta, atol=1e-8)
    # The short run parts there: its next point is its goal or short of the long run's next.
    following = short[len(shared)]
    assert following.turn <= near + 1e-12
    assert following.turn != pytest.approx(long[len(shared)].turn, abs=1e-9)


def test_parting_is_the_first_point_whose_next_step_reaches_the_turn() -> None:
    beta = np.zeros(2)
    trace = [BranchPoint(0.0, beta, 3.0), BranchPoint(3.0, beta, 6.0), BranchPoint(9.0, beta, 3.0)]
    assert _parting(trace, 2.0).turn == 0.0
    assert _parting(trace, 3.0).turn == 0.0
    assert _parting(trace, 8.5).turn == 3.0
    assert _parting(trace, 9.0).turn == 3.0
    assert _parting(trace, 9.5).turn == 9.0
    assert _parting(trace, 11.0).turn == 9.0
    assert _parting(trace, 50.0).turn == 9.0  # beyond the branch: its last point


def test_rows_that_show_a_break_agree_with_the_dense_check() -> None:
    """The shortcut (a clearance row beyond its slack) against the dense check of the path,
    on the shipped UR5 servicer: a path tracked within the joint limits alone sweeps the arm
    through the spacecraft; the quintic path is clear."""
    from freefloat.problem.constraints import Clearance, scenario_constraints
    from freefloat.solvers.restore import broken_constraint, broken_rows_first

    scenario = ff.Scenario.from_toml(SCENARIOS / "ur5_servicer.toml").resolved()
    problem = problem_from_scenario(scenario, extra=[2] * scenario.robot.n, check_bounds=False)
    eager = [c for c in scenario_constraints(scenario) if not c.lazy]
    limits = [c for c in eager if not isinstance(c, Clearance)]
    axis = np.array([0.0, 1.0, 0.0])
    through = track(_towards(problem, axis, math.radians(9.0)), limits, SolveOptions())
    assert through.reached
    said = broken_rows_first(problem, eager, through.beta)
    assert said.startswith("clearance (a solver row")
    assert broken_constraint(problem, eager, through.beta).startswith("clearance")
    zero = np.zeros(problem.n_free)
    assert broken_rows_first(problem, eager, zero) == broken_constraint(problem, eager, zero) == ""
