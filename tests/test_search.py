"""Automatic freedom, full turns of continuous joints, velocity limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

import freefloat as ff
from freefloat.solvers.search import freedom_candidates

import reference as ref
import urdfs
from conftest import ROOT

WORKED = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()


def _scenario(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(
        text.replace('robot = "planar_2dof"', f'robot = "{ROOT / "robots" / "planar_2dof.urdf"}"')
    )
    return ff.Scenario.from_toml(path)


def test_freedom_candidates_start_near_the_base():
    assert freedom_candidates(2, 1) == [[1, 0], [0, 1], [1, 1], [2, 1]]
    assert freedom_candidates(7, 3)[0] == [1, 1, 1, 0, 0, 0, 0]
    assert freedom_candidates(7, 3)[1] == [1] * 7
    assert freedom_candidates(2, 3)[0] == [2, 1]  # short arm: degree raised


def test_automatic_freedom_is_chosen_and_recorded(tmp_path):
    scenario = _scenario(tmp_path, WORKED.replace("extra = { q2 = 1 }", ""))
    plan = ff.plan(scenario)
    assert plan.solver.freedom == {"q1": 1, "q2": 0}  # nearest the base first
    assert plan.solver.tried[-1].endswith("freedom q1+1: solved")
    assert plan.base.attitude_error_rad < 1e-9


TURNS = WORKED.replace("extra = { q2 = 1 }", "").replace(
    "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }   # [deg]; end effector at (1.71, -0.29) m "
    "from the CM\nbase_zyx_deg = [0.0, 0.0, 0.0]",
    "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }\nbase_zyx_deg = [-90.0, 0.0, 0.0]",
)


def test_full_turns_are_not_used_unless_asked(tmp_path):
    assert "base_zyx_deg = [-90.0" in TURNS
    with pytest.raises(ff.InfeasibleError) as info:
        ff.plan(_scenario(tmp_path, TURNS))
    assert f"outside the reachable interval {ref.worked_bounds_text()} deg" in str(info.value)
    assert "allow_full_turns = true (or --allow-full-turns)" in str(info.value)


def test_a_planar_pitch_goal_gets_no_full_turns_hint(tmp_path):
    """No way round of a joint turns a planar base about another axis: no such hint."""
    pitched = WORKED.replace(
        "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }   # [deg]; end effector at (1.71, -0.29) m "
        "from the CM\nbase_zyx_deg = [0.0, 0.0, 0.0]",
        "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }\nbase_zyx_deg = [0.0, 5.0, 0.0]",
    )
    assert "base_zyx_deg = [0.0, 5.0, 0.0]" in pitched
    with pytest.raises(ff.InfeasibleError) as info:
        ff.plan(_scenario(tmp_path, pitched))
    assert info.value.off_axis
    assert "give the goal the start's pitch and roll" in str(info.value)
    assert "allow_full_turns" not in str(info.value)


def test_full_turns_make_an_unreachable_request_a_verified_plan(tmp_path):
    scenario = _scenario(tmp_path, TURNS.replace("[path]", "[path]\nallow_full_turns = true"))
    plan = ff.plan(scenario)
    assert plan.solver.full_turns == {"q1": 1, "q2": 0}
    assert plan.base.achieved_zyx_deg[0] == pytest.approx(-90.0, abs=1e-7)
    q1 = np.array(plan.samples.q)[:, 0]
    assert q1[-1] == pytest.approx(math.radians(-60.0) + 2 * math.pi, abs=1e-12)
    lo, hi = plan.feasibility.yaw_change_bounds_deg
    assert lo < -40.0 < hi


def test_no_path_is_faster_than_each_joints_shortest_way_at_its_limit(tmp_path):
    """The least duration: a revolute joint's span over its limit; a continuous joint also
    reaches its goal the other way round (0 to 5 rad is 2 pi - 5 rad back)."""
    from freefloat.problem.constraints.joint_velocity import JointVelocityLimits

    for kind, span in (("revolute", 2.5), ("continuous", 2.0 * math.pi - 5.0)):
        body = urdfs.BASE.format(mass=100.0, i=10.0)
        body += urdfs.joint("q1", "base", "l1", kind, limits=(-6.0, 6.0)) + urdfs.link("l1")
        body += urdfs.joint("q2", "l1", "l2", "revolute") + urdfs.link("l2")
        urdf = tmp_path / f"{kind}.urdf"
        urdf.write_text(urdfs.robot(body))  # velocity limits 2 rad/s
        robot = ff.load_robot(urdf)
        goal = [2.5 if kind == "revolute" else 5.0, -1.0]
        problem = ff.build_problem(
            robot, [0, 0], goal, ff.quat_from_zyx(0.0), ff.quat_from_zyx(0.0), 1.0
        )
        peak = JointVelocityLimits().worst(robot, problem.polynomials(np.zeros(problem.n_free)))
        assert peak is not None and peak.least_duration == pytest.approx(span / 2.0, rel=1e-12)
    # a loop (the goal joints are the start joints) needs no least time: its ends, evaluated,
    # differ by rounding alone (an outside trial read "no path can in under 2.363e-15 s")
    loop = ff.build_problem(
        robot, [0.3, -1.0], [0.3, -1.0], ff.quat_from_zyx(0.0), ff.quat_from_zyx(0.01), 300.0,
        extra=[3, 3],
    )  # fmt: skip
    path = loop.polynomials(np.linspace(-1.0, 1.0, loop.n_free))
    ends = path.positions(np.array([0.0, path.duration]))
    assert np.any(ends[1] != ends[0])  # rounding
    peak = JointVelocityLimits().worst(robot, path)
    assert peak is not None and peak.least_duration == 0.0


def test_velocity_limit_reports_the_shortest_duration(tmp_path):
    body = urdfs.BASE.format(mass=100.0, i=10.0)
    body += urdfs.joint("q1", "base", "l1", "continuous") + urdfs.link("l1")
    body += urdfs.joint("q2", "l1", "l2", "continuous") + urdfs.link("l2")
    urdf = tmp_path / "v.urdf"
    urdf.write_text(urdfs.robot(body))  # velocity limits 2 rad/s
    robot = ff.load_robot(urdf)
    start = {"q1": 0.0, "q2": 0.0}
    goal = {"q1": 3.0, "q2": -1.0}
    fast = ff.Scenario(robot, 1.0, start, goal, extra={"q1": 1})
    problem = ff.build_problem(
        robot, [0, 0], [3, -1], fast.start_attitude, fast.goal_attitude, 1.0, extra={"q1": 1}
    )
    reached = problem.achieved(np.zeros(1))
    fast = ff.Scenario(robot, 1.0, start, goal, goal_attitude=reached, extra={"q1": 1})
    with pytest.raises(ff.VelocityLimitError) as info:
        ff.plan(fast)
    err = info.value
    assert err.joint == "q1" and err.limit == 2.0
    assert err.peak == pytest.approx(3.0 * 15 / 8, rel=1e-6)  # quintic peak rate 15/8 dq/T
    assert err.shortest_duration == pytest.approx(3.0 * 15 / 8 / 2.0, rel=1e-6)
    # q1 travels 3 rad: at 2 rad/s no path does it in under 1.5 s
    assert err.least_duration == pytest.approx(3.0 / 2.0, rel=1e-12)
    # 2.8125 s rounded up (the nearest, 2.812 s, would break the limit as printed)
    assert (
        "the path found keeps every velocity limit from 2.813 s on, no path can in under 1.5 s"
        in str(err)
    )
    slow = ff.Scenario(
        robot, err.shortest_duration * 1.001, start, goal, goal_attitude=reached, extra={"q1": 1}
    )
    plan = ff.plan(slow)
    # the joint rates by finite differences of the plan's joint values on a dense grid (its
    # coefficients are in the plan's basis, not monomials), against the URDF limit
    t = np.linspace(0.0, plan.duration, 20001)
    rates = np.gradient(plan.joint_positions(t), t, axis=0)
    assert 1.9 < np.abs(rates[:, 0]).max() <= 2.0 + 1e-6


def test_spatial_failure_reports_the_residual_per_axis_and_what_was_tried():
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    far = ff.quat_from_zyx(math.radians(75.0), 0.0, 0.0)  # beyond the Panda within its limits
    quick = ff.SolveOptions(starts=2, max_evaluations=200)
    impossible = ff.Scenario(**{**scenario.__dict__, "goal_attitude": far})
    with pytest.raises(ff.SolverError) as info:
        ff.plan(impossible, quick)
    err = info.value
    assert err.per_axis is not None and len(err.per_axis) == 3
    message = str(err)
    assert "per axis x, y, z:" in message
    # each level's figure, how far short; the same freedom for each joint said once
    assert "freedom +2 for each joint: stopped" in message
    assert "freedom +3 for each joint" in message and "panda_joint1+" not in message
    assert "\n" not in message
    # Continuation says how far it got along the way and why it stopped.
    assert 0.0 < err.reached_fraction < 1.0 and err.stopped_by
    assert message.startswith("reachable up to ")


def test_a_goal_out_of_reach_within_the_limits_is_refused_without_the_costly_rows():
    """The Panda servicer's goal rolled 180 deg, with a costly (not affine) constraint that
    never binds: the search within the joint limits alone stops against a limit on a path that
    honours it, so the goal is refused at once and the costly rows are never asked for; the
    refusal says so. (With its real clearance the path it stops on collides, and the search
    runs again with clearance imposed: docs/clearance.md.)"""
    from freefloat.physics import attitude as att
    from freefloat.problem.constraints import Constraint, default_constraints
    from freefloat.problem.constraints.base import Excess
    from freefloat.solvers.lazy_search import search_lazily
    from freefloat.solvers.options import SolveOptions

    class Loose(Constraint):
        name, unit, tolerance, affine = "loose", "m", 1e-6, False

        def rows(self, problem, beta, instants=None):
            raise AssertionError("the costly rows were asked for")

        def excess(self, robot, path):
            return Excess(-1.0, 0.0, "never binds")

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    rolled = att.quat_multiply(scenario.goal_attitude, att.quat_exp(np.array([math.pi, 0, 0])))
    turned = ff.Scenario(**{**scenario.__dict__, "goal_attitude": rolled}).resolved()
    constraints = [*default_constraints(), Loose()]
    with pytest.raises(ff.UnreachableGoalError) as info:
        search_lazily(turned, SolveOptions(), constraints)
    err = info.value
    assert str(err).startswith("reachable up to ")
    assert "; the search without loose stopped on a path that honours loose too" in str(err)
    assert err.stopped_by.startswith("joint_position_limits")
    assert 0.0 < err.reached < err.asked


def test_a_refusal_over_several_goals_reports_the_goal_that_got_closest():
    """With full turns allowed, each goal tried (as stated, or with a joint's turn) has its own
    levels; the refusal gives the figures of the goal whose levels got closest, a continued
    level's included (ETS-VII once reported 5.1 of 20 deg where a turned goal reached 17.3 of
    20.1 deg), every figure from that goal. Errors built here with known figures (rad)."""
    from freefloat.solvers.search import _refuse
    from freefloat.solvers.search_record import SearchRecord

    def stopped(reached, asked, residual, axis, why):
        return ff.UnreachableAttitudeError(
            "reachable ...", residual, reached=reached, asked=asked, axis=axis, stopped_by=why
        )

    stated, turned = "goal as stated", "goal Joint_6 -1 turn(s)"
    record = SearchRecord()
    x, y = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    record.failed(stopped(0.09, 0.30, 0.21, x, "a"), f"{stated}, freedom +2", False, stated)
    record.failed(stopped(0.10, 0.21, 0.20, x, "b"), f"{stated}, freedom +3", True, stated)
    record.failed(stopped(0.20, 0.35, 0.15, y, "c"), f"{turned}, freedom +2", False, turned)
    record.failed(stopped(0.10, 0.15, 0.05, y, "d"), f"{turned}, freedom +3", True, turned)
    nearest = record.nearest_goal()
    assert nearest.goal == turned and nearest.closest.best_residual == 0.05
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    with pytest.raises(ff.UnreachableAttitudeError) as info:
        _refuse(scenario, 2, None, (0.05, None, None), record.tried, nearest, ())
    error = info.value
    # asked and axis from the turned goal's first level; the rest of the way from its
    # closest (continued) level: 0.35 - 0.05
    assert error.asked == 0.35 and error.axis == y and error.reached == pytest.approx(0.30)
    assert error.stopped_by == "d" and error.best_residual == 0.05
    assert str(error).startswith(f"{turned}: reachable up to 17.2 deg of the 20.1 deg asked")


def test_a_continuous_joint_sent_the_long_way_round_is_noted(tmp_path, capsys):
    """q2 from 30 to 380 deg travels 350 deg, where the same pose lies 10 deg back: said, with
    the way to ask for it (the goal attitude is the one the plain path reaches: it plans).
    Truth: the difference of the goals as written, less a turn."""
    from freefloat.cli import main
    from freefloat.physics.attitude import zyx_from_quat
    from freefloat.problem.build import problem_from_scenario

    text = WORKED.replace(
        "joints = { q1 = -60.0, q2 = 90.0 }", "joints = { q1 = -60.0, q2 = 380.0 }"
    )
    assert "q2 = 380.0" in text
    problem = problem_from_scenario(_scenario(tmp_path, text), check_bounds=False)
    drift = np.degrees(zyx_from_quat(problem.achieved(np.zeros(problem.n_free))))
    goal = "base_zyx_deg = [0.0, 0.0, 0.0]"
    assert goal in text
    path = tmp_path / "s.toml"
    turned = f"base_zyx_deg = [{float(drift[0])!r}, 0.0, 0.0]"
    path.write_text(path.read_text().replace(goal, turned))
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 0
    assert (
        "  long way round  q2 travels 350 deg; the same pose lies -10 deg away (continuous: "
        "give that goal for the short way)"
    ) in capsys.readouterr().out.splitlines()
