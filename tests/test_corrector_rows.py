"""The corrector's costly rows: measured at the first iterate and where it accepts, linearised
between while every row stays well inside, never accepted outside the rows measured there."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.problem.build import problem_from_scenario
from freefloat.problem.constraints import DEFAULT_INSTANTS, ConstraintRows
from freefloat.problem.constraints.joint_position import JointPositionLimits
from freefloat.solvers.corrector import correct
from freefloat.solvers.rows import Linearised
from test_solver import _independent_final_attitude

SCENARIOS = Path(__file__).resolve().parents[1] / "robots" / "scenarios"


def test_rows_are_trusted_only_while_twice_their_change_keeps_them_inside() -> None:
    """By hand: a row at -1 rising 0.4 stays inside at twice that, one rising 0.6 does not; a
    falling row needs only to be inside; a row outside where it was measured never is."""
    beta0 = np.zeros(2)
    rising = Linearised(beta0, {0: (np.array([-1.0]), np.array([[1.0, 0.0]]))})
    assert rising.trusted_at(np.array([0.4, 7.0]))
    assert not rising.trusted_at(np.array([0.6, 7.0]))
    falling = Linearised(beta0, {3: (np.array([-1e-9]), np.array([[0.0, 2.0]]))})
    assert falling.trusted_at(np.array([0.0, -5.0]))
    outside = Linearised(beta0, {1: (np.array([-3.0, 1e-12]), np.zeros((2, 2)))})
    assert not outside.trusted_at(beta0)
    values, jacobian = rising.at(0, np.array([0.25, 1.0]))
    assert values.tolist() == [-0.75] and jacobian.tolist() == [[1.0, 0.0]]
    assert rising.measured_at(np.zeros(2)) and not rising.measured_at(np.array([0.0, 1e-300]))


class _Counted(JointPositionLimits):
    """Joint position limits declared not affine: measured by the corrector, counted."""

    affine = False

    def __init__(self) -> None:
        super().__init__()
        self.measured = 0

    def rows(
        self, problem: ff.Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        self.measured += 1
        return super().rows(problem, beta, instants)


class _Ball(JointPositionLimits):
    """``|beta|^2 <= radius^2`` at every instant: a row whose linearisation is not exact."""

    affine = False

    def __init__(self, radius: float) -> None:
        super().__init__()
        self.radius = radius

    def tight_instants(self, problem: ff.Problem, beta: np.ndarray) -> np.ndarray:
        return np.zeros(0)

    def rows(
        self, problem: ff.Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        value = float(beta @ beta) - self.radius**2
        return ConstraintRows(np.array([value]), 2.0 * beta[None, :])


def _panda_turned(axis: int, degrees: float) -> ff.Problem:
    """The Panda servicer's goal turned about a body axis from the quintic path's attitude."""
    panda = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")
    base = problem_from_scenario(panda, extra=[2] * panda.robot.n)
    reached = base.achieved(np.zeros(base.n_free))
    rotvec = np.zeros(3)
    rotvec[axis] = math.radians(degrees)
    return base.with_goal(att.quat_multiply(reached, att.quat_exp(rotvec)))


@pytest.fixture(scope="module")
def problem() -> ff.Problem:
    """The Panda servicer's goal 1 deg about x from the quintic path's attitude, 2 free each:
    its Newton iterates stay well inside the joint limits."""
    return _panda_turned(0, 1.0)


def test_a_linearised_affine_row_gives_the_exact_corrector_path(problem: ff.Problem) -> None:
    """Limits declared not affine are measured at the first iterate and where the corrector
    accepts, not at every iterate; their linearisation is exact, so the path is the one of
    the limits as affine rows (to rounding), inside the limits measured directly, and it
    reaches the goal by SciPy's DOP853 (not the planner's integrator)."""
    counted = _Counted()
    solved, _, _, iterations = correct(
        problem, [counted], np.zeros(problem.n_free), 1e-9, DEFAULT_INSTANTS, {}
    )
    assert solved is not None and iterations >= 3
    assert counted.measured <= 2 * 2  # tight instants and instants, at two iterates
    exact, _, _, same = correct(
        problem, [JointPositionLimits()], np.zeros(problem.n_free), 1e-9, DEFAULT_INSTANTS, {}
    )
    assert exact is not None and same == iterations
    np.testing.assert_allclose(solved, exact, rtol=0, atol=1e-10)
    rows = JointPositionLimits().rows(problem, solved, np.linspace(0.0, 1.0, 1001))
    assert float(rows.values.max()) <= 0.0
    final = _independent_final_attitude(problem, solved)
    assert att.geodesic_angle(final, problem.goal_quaternion) < 1e-7


@pytest.mark.parametrize("radius", [0.05, 0.2, 0.36, 0.38, 1.0, 5.0])
def test_a_path_is_never_accepted_outside_a_row_measured_where_it_is(
    problem: ff.Problem, radius: float
) -> None:
    """The ball's row linearised about beta = 0 is flat (its Jacobian is 0 there), so it is
    trusted all the way; where the corrector would accept, the row measured there decides:
    an accepted path is inside the ball (|beta| <= radius, by hand). Balls smaller than the
    minimum-norm root (|beta| = 0.37) leave no path; larger ones give that root."""
    solved, _, _, _ = correct(
        problem, [_Ball(radius)], np.zeros(problem.n_free), 1e-9, DEFAULT_INSTANTS, {}
    )
    free, _, _, _ = correct(problem, [], np.zeros(problem.n_free), 1e-9, DEFAULT_INSTANTS, {})
    assert free is not None
    if radius < float(np.linalg.norm(free)):
        assert solved is None
    else:
        assert solved is not None and float(np.linalg.norm(solved)) <= radius
        np.testing.assert_allclose(solved, free, rtol=0, atol=1e-10)


def test_rows_near_their_limit_are_measured_at_every_iterate() -> None:
    """2 deg about y: the Newton iterates go beyond the limits on the way (a row 0.58 rad
    outside at the second), so the rows are measured at every iterate, once each (the tight
    instants with the instants, in one call), and the path found is inside the limits
    measured directly."""
    problem = _panda_turned(1, 2.0)
    counted = _Counted()
    solved, _, _, iterations = correct(
        problem, [counted], np.zeros(problem.n_free), 1e-9, DEFAULT_INSTANTS, {}
    )
    assert solved is not None
    assert counted.measured == iterations
    rows = JointPositionLimits().rows(problem, solved, np.linspace(0.0, 1.0, 1001))
    assert float(rows.values.max()) <= 0.0


@pytest.mark.parametrize("name", ["base_swing", "base_pointing"])
def test_an_attitude_bounds_rows_in_one_call_are_its_rows_in_two(name):
    """The tight instants and the instants are asked in one call (one integration of the
    path): the rows agree with those asked apart to the integration's own error."""
    from freefloat.solvers.rows import _costly_rows
    from test_plugins import CONSTRAINT_EXAMPLES, ROOT

    ur5_scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")

    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    problem = ff.problem_from_scenario(ur5_scenario, extra=[2] * ur5_scenario.robot.n)
    beta = 0.2 * np.random.default_rng(0).normal(size=problem.n_free)  # a turn peaking inside
    tight = constraint.tight_instants(problem, beta)
    assert len(tight)
    values, jacobian = _costly_rows(problem, constraint, beta, DEFAULT_INSTANTS, np.zeros(0))
    apart = [constraint.rows(problem, beta, at) for at in (tight, DEFAULT_INSTANTS)]
    np.testing.assert_allclose(values, np.concatenate([r.values for r in apart]), atol=1e-9)
    np.testing.assert_allclose(jacobian, np.concatenate([r.jacobian for r in apart]), atol=1e-8)
