"""A pure reorientation: joints that end where they start turn the spacecraft by a loop.

The quintic path of such a request does not move, so the attitude map is singular there; the
planner starts from a closed loop chosen with the quadratic model of the turn
(:mod:`freefloat.solvers.loop_start`), as ``freefloat correct`` does. Truths: the plan's joint
paths evaluated at both ends (the same joints), and an RK5 replay of the base attitude along
them (:func:`freefloat.robust.replay_attitude`, not the planner's Magnus scheme), which must
land on the goal attitude; the planar simple-motion bound (an empty interval for joints that
do not travel) is not held against it.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics.attitude import quat_exp, quat_from_zyx, quat_multiply
from freefloat.problem.build import problem_from_scenario
from freefloat.robot.model import robots_dir
from freefloat.robust import replay_attitude
from freefloat.solvers.loop_start import loop_origin, stays_put

SCENARIOS = robots_dir() / "scenarios"


def _in_place(name: str, turn: np.ndarray) -> ff.Scenario:
    """The shipped scenario with its goal joints its start joints, turned by ``turn`` (rad)."""
    scenario = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    goal = quat_multiply(scenario.start_attitude, quat_exp(np.asarray(turn, dtype=float)))
    return dataclasses.replace(
        scenario, goal_joints=dict(scenario.start_joints), goal_attitude=goal, extra=None
    )


@pytest.mark.parametrize(
    ("name", "turn"),
    [
        ("worked_example", [0.0, 0.0, np.radians(2.0)]),
        ("ur5_servicer", np.radians([1.0, -1.0, 1.5])),
    ],
)
def test_a_pure_reorientation_plans_a_loop_that_lands_on_the_goal(name, turn):
    scenario = _in_place(name, turn)
    plan = ff.plan(scenario)
    robot = scenario.robot
    ends = np.array([plan.samples.q[0], plan.samples.q[-1]])
    np.testing.assert_allclose(ends[0], scenario.start, atol=1e-12)
    np.testing.assert_allclose(ends[1], scenario.start, atol=1e-12)
    assert np.ptp(plan.samples.q, axis=0).max() > np.radians(1.0)  # it does move: a loop
    replayed = replay_attitude(plan, robot)
    assert replayed.error_rad <= 1e-9 + replayed.estimate_rad


def test_the_loop_is_the_start_only_where_the_quintic_path_stays_put():
    moving = problem_from_scenario(ff.Scenario.from_toml(SCENARIOS / "ur5_servicer.toml"))
    assert not stays_put(moving) and loop_origin(moving, ff.default_constraints()) is None
    still = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    problem = problem_from_scenario(still, extra=[2] * still.robot.n)
    assert stays_put(problem)
    assert loop_origin(problem, ff.default_constraints()) is None  # already at its goal
    turned = problem.with_goal(quat_multiply(problem.start_quaternion, quat_from_zyx(0.02)))
    loop = loop_origin(turned, ff.default_constraints())
    assert loop is not None and np.any(loop)
    # the quadratic model's turn: within a fifth of the 0.02 rad asked (it is a model)
    reached = np.linalg.norm(turned.residual(np.zeros(turned.n_free)) - turned.residual(loop))
    assert abs(reached - 0.02) < 0.2 * 0.02


def test_reach_of_a_pure_reorientation_starts_from_loops_and_its_goals_plan():
    """reach printed 0 in every direction for joints that end where they start (the quintic
    path stays put: singular). It now heads out from a loop on each axis; the goals it prints
    (at the inner turn and within it) plan. Truth: each plan's RK5 replay lands on its goal."""
    scenario = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    scenario = dataclasses.replace(
        scenario, safety=dataclasses.replace(scenario.safety, check=False)
    )
    axes = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    report = ff.reachable(scenario, directions=axes, jobs=1)
    assert report.loops
    for d in report.directions:
        assert d.outer == 0.0 and d.inner > np.radians(1.0), d
        for fraction in (1.0, 0.5):
            turn = fraction * d.inner
            goal = quat_multiply(report.drift_quaternion, quat_exp(turn * d.axis))
            plan = ff.plan(dataclasses.replace(scenario, goal_attitude=goal))
            replayed = replay_attitude(plan, scenario.robot)
            assert replayed.error_rad <= 1e-9 + replayed.estimate_rad


def test_reach_of_a_planar_pure_reorientation_says_the_bounds_are_of_simple_motions():
    from freefloat.viz.reach_text import reach_lines

    report = ff.reachable(_in_place("worked_example", [0.0, 0.0, 0.0]))
    assert report.loops and report.planar
    assert [d.outer for d in report.directions] == [0.0, 0.0]
    assert reach_lines(report)[-1] == (
        "verdict: the goal joints are the start joints: every motion is a loop, which no "
        "simple-motion bound covers; plan starts each such goal from a loop (docs/reach.md)"
    )


@pytest.mark.parametrize("turn_deg", [[0.0, 0.0, 1.0], [1.0, -1.0, 1.5], [0.5, 0.0, 0.0]])
def test_the_loop_swings_the_spacecraft_about_as_far_as_it_turns_it(turn_deg):
    """A loop picked for its turn alone swung the UR5 servicer 5 to 7.5 times further on the
    way than it turned it at the end (6.1 deg for 0.92 deg), out of any narrow pointing cone;
    the loop that turns the most for its first-order swing swings at most twice its turn.
    Truth: SciPy's DOP853 on Pinocchio's centroidal map, both the swing and the end turn."""
    from test_base_swing import _scipy_attitude, scipy_largest

    still = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    problem = problem_from_scenario(still, extra=[2] * still.robot.n)
    turned = problem.with_goal(
        quat_multiply(problem.start_quaternion, quat_exp(np.radians(turn_deg)))
    )
    loop = loop_origin(turned, ff.default_constraints())
    assert loop is not None
    path = turned.polynomials(loop)

    def angle(y: np.ndarray) -> np.ndarray:
        return 2.0 * np.arctan2(np.linalg.norm(y[:3], axis=0), np.abs(y[3]))

    swing, _ = scipy_largest(path, still.robot, angle)
    end = float(angle(_scipy_attitude(path, still.robot).sol(path.duration)))
    assert end > np.radians(0.2)  # it does turn the spacecraft
    assert swing <= 2.0 * end, (np.degrees(swing), np.degrees(end))


_SLIDES = """<?xml version="1.0"?>
<robot name="slides">
  <link name="base"><inertial><mass value="100.0"/>
    <inertia ixx="10" iyy="10" izz="10" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="px" type="prismatic"><parent link="base"/><child link="sled"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="100" velocity="1"/></joint>
  <link name="sled"><inertial><mass value="1.0"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="py" type="prismatic"><parent link="sled"/><child link="mass"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="100" velocity="1"/></joint>
  <link name="mass"><inertial><mass value="20.0"/>
    <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""


def test_a_pure_reorientation_where_the_map_vanishes_is_refused_in_one_line(tmp_path, capsys):
    """Two slides carrying a mass from the spacecraft's centre of mass: the momentum map is
    zero at the start (a review's robot), so the loop's swing form is zero too, and its
    Cholesky factor raised a LinAlgError: a traceback from plan, correct and reach. The loop
    is then the one of the least joint motion."""
    from freefloat.cli import main

    (tmp_path / "slides.urdf").write_text(_SLIDES)
    scenario = tmp_path / "slides.toml"
    scenario.write_text(
        'robot = "slides.urdf"\nduration = 10.0\n[start]\njoints = { px = 0.0, py = 0.0 }\n'
        "[goal]\njoints = { px = 0.0, py = 0.0 }\nbase_zyx_deg = [1.0, 0.0, 0.0]\n"
        "[safety]\ncheck = false\n"
    )
    problem = problem_from_scenario(ff.Scenario.from_toml(scenario))
    loop = loop_origin(problem, ff.default_constraints())
    assert loop is not None and np.isfinite(loop).all()
    np.testing.assert_array_equal(loop, loop_origin(problem, ff.default_constraints(), False))
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    # the turn asked counts from where the loop took the spacecraft, not from the start
    asked = float(re.search(r"of the ([\d.e+-]+) deg asked", err).group(1))
    assert 0.0 < asked < 0.5, err
    assert "from the attitude of the loop it began on); stopped by" in err, err


def test_no_loop_where_one_joint_moves_alone():
    """The worked example with free coefficients on q1 only: a path of one joint that comes
    back retraces itself, so it turns a planar base by the integral of g1(q1) dq1 over a
    closed interval, 0 (closed form). Its curvature is the differences' noise (about 1e-12),
    which made a loop of 1e4 rad and more; there is none."""
    still = _in_place("worked_example", [0.0, 0.0, np.radians(1.0)])
    problem = problem_from_scenario(still, extra=[2, 0])
    assert stays_put(problem)
    assert loop_origin(problem, ff.default_constraints()) is None


def test_a_reorientation_the_first_loop_cannot_start_plans_from_the_other():
    """The worked example turned 20 deg in place, its tool's x axis within 60 deg of the
    base direction at 70 deg: the search from the loop of the least swing stops; the one
    from the loop of the least joint motion plans (each plans some turns the other cannot).
    Truths: the cone's closed-form gap cos(60 deg) - cos(q1 + q2 - 70 deg) on 20001 instants
    of the plan, and an RK5 replay of the attitude."""
    from freefloat.problem.constraints import constraint_from_record

    cone = constraint_from_record(
        "end_effector_cone",
        {"axis": [1.0, 0.0, 0.0], "direction": [0.3420201433256687, 0.9396926207859083, 0.0],
         "half_angle_deg": 60.0},
    )  # fmt: skip
    scenario = dataclasses.replace(
        _in_place("worked_example", [0.0, 0.0, np.radians(20.0)]), constraints=(cone,)
    )
    plan = ff.plan(scenario)
    solved = [t for t in plan.solver.tried if t.endswith(": solved")]
    assert solved == ["goal as stated, from the loop of the least joint motion, freedom q1+2, "
                      "q2+1: solved"]  # fmt: skip
    q = plan.joint_positions(np.linspace(0.0, plan.duration, 20001))
    gap = np.cos(np.radians(60.0)) - np.cos(q[:, 0] + q[:, 1] - np.radians(70.0))
    assert gap.max() <= 1e-9
    replayed = replay_attitude(plan, scenario.robot)
    assert replayed.error_rad <= 1e-9 + replayed.estimate_rad
