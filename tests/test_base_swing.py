"""The bound on the spacecraft's swing on the way (``[constraints.base_swing]``).

Truths the code under test does not compute: closed forms of a turn about a fixed axis, and
SciPy's DOP853 integration of the attitude from Pinocchio's centroidal map written out here
(``v_base = -A_b^-1 A_q qdot``) along the plan's joint polynomials. The Jacobian against finite
differences and the record's round trip are in the plug-in contract (test_plugins).
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import minimize_scalar

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import InputError
from freefloat.physics.turn_track import quaternion_turn, relative_between, track_turn
from freefloat.problem.constraints import BaseSwing, constraint_from_record
from freefloat.viz.summary import robot_label, summary

import reference

ROOT = Path(__file__).resolve().parents[1]

#: The Panda servicer's arm, where it starts and ends.
_PANDA_JOINTS = """panda_joint1 = 0.0
panda_joint2 = -45.0
panda_joint3 = 0.0
panda_joint4 = -135.0
panda_joint5 = 0.0
panda_joint6 = 90.0
panda_joint7 = 45.0
"""
#: The Panda servicer turned 3 deg in yaw with its arm back where it started: the closed loop
#: the planner starts from swings the spacecraft well beyond 3 deg on the way.
REORIENTATION = f"""
robot = "panda_servicer"
duration = 20.0

[start]
base_zyx_deg = [0.0, 0.0, 0.0]

[start.joints]
{_PANDA_JOINTS}
[goal]
base_zyx_deg = [3.0, 0.0, 0.0]

[goal.joints]
{_PANDA_JOINTS}"""


def _turn_about_an_axis(rate, duration: float, steps: int):
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    return track_turn(lambda t: np.outer(rate(t), axis), duration, steps)


def test_the_turn_about_a_fixed_axis_is_the_integral_of_the_rate():
    # omega = u a sin(2 pi t / T): out and back, the turn (1 - cos(2 pi t / T)) a T / (2 pi)
    a, duration = 0.3, 7.0

    def rate(t):
        return a * np.sin(2.0 * math.pi * np.asarray(t) / duration)

    def closed(t):
        return a * duration / (2.0 * math.pi) * (1.0 - np.cos(2.0 * math.pi * t / duration))

    track = _turn_about_an_axis(rate, duration, 64)
    np.testing.assert_allclose(track.turns, closed(track.times), atol=1e-11)
    finer = track_turn(lambda t: np.outer(rate(t), [1.0, 2.0, -2.0]) / 3.0, duration, 128, track)
    np.testing.assert_allclose(finer.turns, closed(finer.times), atol=1e-12)
    assert np.array_equal(finer.rates[0::2], track.rates)  # reused, not recomputed
    for t in (0.0, 1.234, 3.5, 6.99, 7.0):
        between = relative_between(
            lambda s: np.outer(rate(s), [1.0, 2.0, -2.0]) / 3.0, track, t, duration
        )
        assert quaternion_turn(between) == pytest.approx(closed(t), abs=1e-10)  # a part step


def scipy_largest(plan, robot: ff.Robot, quantity) -> tuple[float, float]:
    """Largest value of ``quantity(relative attitudes (4, K))`` and its time (s).

    The attitude relative to the start integrated by SciPy's DOP853 from Pinocchio's
    centroidal map at zero momentum, its largest sample of 4001 refined by SciPy's bounded
    scalar search. ``plan``: a plan, or joint polynomials.
    """
    path = plan.path() if isinstance(plan, ff.Plan) else plan
    found = _scipy_attitude(path, robot)
    t = np.linspace(0.0, path.duration, 4001)
    k = int(np.argmax(quantity(found.sol(t))))
    if k in (0, len(t) - 1):
        return float(np.ravel(quantity(found.sol(t[k])))[0]), float(t[k])
    best = minimize_scalar(
        lambda x: -float(np.ravel(quantity(found.sol(x)))[0]), bounds=(t[k - 1], t[k + 1]),
        method="bounded",
        options={"xatol": 1e-9},
    )  # fmt: skip
    return float(-best.fun), float(best.x)


def _scipy_attitude(path, robot: ff.Robot):
    """SciPy's DOP853 solution (dense) of the attitude relative to the start along ``path``."""
    model, data = robot.model, robot.model.createData()
    columns = [joint.idx_v for joint in robot.joints]

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        samples = path.evaluate(np.array([t]))
        ag = pin.computeCentroidalMap(model, data, robot.configuration(samples.q[0]))
        omega = -np.linalg.solve(ag[:, :6], ag[:, columns] @ samples.qd[0])[3:]
        x, yy, z, w = y
        wx, wy, wz = omega
        return 0.5 * np.array(
            [w * wx + yy * wz - z * wy, w * wy + z * wx - x * wz, w * wz + x * wy - yy * wx,
             -x * wx - yy * wy - z * wz]
        )  # fmt: skip

    return solve_ivp(
        rhs, (0.0, path.duration), [0.0, 0.0, 0.0, 1.0], "DOP853", rtol=1e-12, atol=1e-13,
        dense_output=True,
    )  # fmt: skip


def _scipy_turns(path, robot: ff.Robot, s: np.ndarray) -> np.ndarray:
    """The turn from the start (rad) at normalised instants ``s`` (SciPy, as above)."""
    y = _scipy_attitude(path, robot).sol(np.asarray(s) * path.duration)
    return 2.0 * np.arctan2(np.linalg.norm(y[:3], axis=0), np.abs(y[3]))


def _scipy_swing(plan, robot: ff.Robot) -> tuple[float, float]:
    """Largest turn (rad) from the start attitude and its time (s) (:func:`scipy_largest`)."""

    def turn(y):
        return 2.0 * np.arctan2(np.linalg.norm(y[:3], axis=0), np.abs(y[3]))

    return scipy_largest(plan, robot, turn)


@pytest.fixture(scope="module")
def reorientation(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("swing") / "reorientation.toml"
    path.write_text(REORIENTATION)
    return path


def test_a_reorientation_keeps_the_spacecraft_within_the_bound(reorientation, tmp_path, capsys):
    scenario = ff.Scenario.from_toml(reorientation)
    free, _ = _scipy_swing(ff.plan(scenario), scenario.robot)
    assert math.degrees(free) > 5.0  # unbounded, the loop swings it 5.7 deg: beyond the goal
    bounded = tmp_path / "bounded.toml"
    bounded.write_text(REORIENTATION + "\n[constraints.base_swing]\nmax_deg = 4.0\n")
    out = tmp_path / "plan.json"
    assert main(["plan", str(bounded), "-o", str(out), "-q"]) == 0
    plan = ff.Plan.load(out)
    swing, when = _scipy_swing(plan, scenario.robot)
    assert math.degrees(swing) <= 4.0 + 1e-7
    assert math.degrees(swing) > 3.99  # the bound binds: the path goes up to it
    data = json.loads(out.read_text())
    assert {"name": "base_swing", "parameters": {"max_deg": 4.0}} in data["constraints"]
    check = next(c for c in data["verification"]["checks"] if c["name"] == "base_swing")
    assert check["value"] == pytest.approx(swing - math.radians(4.0), abs=1e-8)
    said = re.search(r"at t = ([\d.]+) s", check["detail"])
    assert said and float(said.group(1)) == pytest.approx(when, abs=2 * plan.duration / 4000)
    assert main(["verify", str(out)]) == 0
    capsys.readouterr()
    line = next(x for x in summary(plan).splitlines() if x.startswith("  spacecraft"))
    assert line.endswith(
        f"; the check's largest {math.degrees(swing):.7g} deg, at most 4 deg allowed "
        "([constraints.base_swing])); its goal lies 3 deg from it"
    )


def test_the_swing_of_a_path_does_not_depend_on_its_duration(reorientation):
    # Zero momentum: the attitude follows the joints' path, not how fast it is run.
    scenario = ff.Scenario.from_toml(reorientation)
    plan = ff.plan(scenario)
    swing = BaseSwing(math.radians(20.0))
    slow = ff.problem.paths.JointPolynomials(plan.path().coefficients, 2.0 * plan.duration)
    fast, stretched = swing.excess(scenario.robot, plan.path()), swing.excess(scenario.robot, slow)
    assert fast.value == pytest.approx(stretched.value, abs=1e-10)
    assert fast.value == pytest.approx(
        _scipy_swing(plan, scenario.robot)[0] - math.radians(20.0), abs=1e-8
    )


def test_a_goal_attitude_beyond_the_bound_is_refused_before_any_search(tmp_path, capsys):
    # The worked example's goal lies 50 deg (yaw) from its start.
    path = tmp_path / "s.toml"
    path.write_text(
        ff.default_scenario_path().read_text() + "\n[constraints.base_swing]\nmax_deg = 30\n"
    )
    with pytest.raises(ff.GoalAttitudeError) as info:
        ff.plan(ff.Scenario.from_toml(path))
    assert info.value.constraint == "base_swing"
    assert info.value.excess == pytest.approx(math.radians(20.0), abs=1e-12)
    assert str(info.value) == (
        "goal attitude breaks base_swing (it lies 50 deg from the start attitude, at most 30 "
        "deg allowed), where every path ends; choose a goal attitude it allows "
        "or loosen [constraints.base_swing]"
    )
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "goal attitude breaks base_swing" in err
    assert not (tmp_path / "p.json").exists()
    assert main(["check", str(path), "--at", "goal"]) == 1  # check judges the goal attitude
    out = capsys.readouterr().out
    assert (
        "base_swing: goal attitude: it lies 50 deg from the start attitude, at most 30 deg "
        "allowed: BROKEN" in out
    )
    assert main(["check", str(path), "--at", "start"]) == 0  # the turn is 0 there
    assert "base_swing: start attitude: it lies 0 deg from the start attitude" in (
        capsys.readouterr().out
    )


@pytest.mark.parametrize(
    ("record", "said"),
    [
        ({}, "base_swing: missing 'max_deg'; its key is max_deg"),
        ({"max_deg": 5, "axis": 1}, "base_swing: unknown key 'axis'; its key is max_deg"),
        ({"max_deg": 0}, "between 0 and 180 (exclusive) [deg], got 0"),
        ({"max_deg": 180.0}, "between 0 and 180 (exclusive) [deg], got 180.0"),
        ({"max_deg": True}, "between 0 and 180 (exclusive) [deg], got True"),
        ({"max_deg": "5"}, "between 0 and 180 (exclusive) [deg], got '5'"),
        ({"max_deg": math.nan}, "between 0 and 180 (exclusive) [deg], got nan"),
        ({"max_deg": 5e-324}, "between 0 and 180 (exclusive) [deg], got 5e-324"),
    ],
)
def test_bad_bounds_are_named(record, said):
    with pytest.raises(InputError) as info:
        constraint_from_record("base_swing", record)
    assert said in str(info.value)


def test_a_goal_at_the_bound_plans(reorientation):
    # The goal lies 3 deg from the start and the bound is 3 deg: the path must come up to it
    # from below. A row at the end (fixed by the goal) made it unreachable.
    scenario = ff.Scenario.from_toml(reorientation)
    bounded = dataclasses.replace(
        scenario, constraints=(*scenario.constraints, BaseSwing(math.radians(3.0)))
    )
    plan = ff.plan(bounded)
    swing, _ = _scipy_swing(plan, scenario.robot)
    assert math.radians(3.0) - 1e-9 <= swing <= math.radians(3.0) + 1e-7


def test_planar_rows_are_the_closed_form_yaw_and_differentiate(worked_scenario):
    # The worked example turns about z alone: its turn at t is |yaw(t) - yaw(0)|, the
    # quadrature of docs/method.md section 7's gains (tests/reference.py, no freefloat).
    problem = ff.problem_from_scenario(worked_scenario, extra=[2, 2])
    beta = np.array([0.3, -0.2, 0.1, 0.25])
    swing = BaseSwing(math.radians(170.0))
    s = np.array([0.2, 0.5, 0.8, 0.95])
    turns = swing.rows(problem, beta, s).values + swing.max_angle - swing.solver_slack(problem, s)
    path = problem.polynomials(beta)

    def rate(t: float) -> float:
        samples = path.evaluate(np.array([t]))
        g1, g2 = reference.gains(*samples.q[0])
        return g1 * samples.qd[0, 0] + g2 * samples.qd[0, 1]

    yaw = [quad(rate, 0.0, x * path.duration, epsabs=1e-13, epsrel=1e-13, limit=500)[0] for x in s]
    np.testing.assert_allclose(turns, np.abs(yaw), atol=1e-10)
    jacobian = swing.rows(problem, beta, s).jacobian
    fd = np.stack(
        [
            (swing.rows(problem, beta + e, s).values - swing.rows(problem, beta - e, s).values)
            / 2e-6
            for e in 1e-6 * np.eye(len(beta))
        ],
        axis=1,
    )
    np.testing.assert_allclose(jacobian, fd, atol=1e-7)


def test_rows_at_instants_whose_last_step_rounds_short(worked_scenario):
    # a + (b - a) sub / sub rounds below b for these two instants: the step ends held b one
    # slot late and indexing ran off the end (a traceback from plan and reach).
    problem = ff.problem_from_scenario(worked_scenario, extra=[2, 2])
    beta = np.array([0.3, -0.2, 0.1, 0.25])
    a, b = 0.0058245951079809455, 0.39625616221698645
    swing = BaseSwing(math.radians(170.0))
    both = swing.rows(problem, beta, np.array([a, b])).values
    alone = [swing.rows(problem, beta, np.array([x])).values[0] for x in (a, b)]
    np.testing.assert_allclose(both, alone, atol=1e-12)
    assert swing.rows(problem, beta, np.array([0.0, 1.0])).count == 0  # the ends' are fixed


def test_held_by_a_robot_whose_scenario_lists_no_end_effector(tmp_path):
    # The UR5 servicer's scenario names none: held_by must be the robot's own (tool0).
    text = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
    text = text.replace('robot = "ur5_servicer"', f'robot = "{ROOT / "robots"}/ur5_servicer.urdf"')
    path = tmp_path / "held.toml"
    path.write_text(text + '\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\nheld_by = "tool0"\n')
    assert "held by tool0" in robot_label(ff.Scenario.from_toml(path))
    path.write_text(
        text + '\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\nheld_by = "spacecraft"\n'
    )
    with pytest.raises(ff.ScenarioError) as info:
        ff.Scenario.from_toml(path)
    assert str(info.value).endswith(
        "[payload] held_by 'spacecraft' is not one of the scenario's end effectors: 'tool0'"
    )


def test_reach_stops_its_outer_turns_at_the_bound(tmp_path):
    # The Panda servicer's simple motions may turn it 37.3 deg from the start; with a 30 deg
    # bound no goal lies beyond 30 deg. Truth: SciPy's rotations of the printed turns.
    from scipy.spatial.transform import Rotation

    from freefloat.viz.reach_text import verdict

    text = (ROOT / "robots" / "scenarios" / "panda_servicer.toml").read_text()
    path = tmp_path / "bounded.toml"
    path.write_text(text + "\n[constraints.base_swing]\nmax_deg = 30\n")
    report = ff.reachable(ff.Scenario.from_toml(path), budget=0)
    assert report.goal_judged == ("base_swing",) and not report.drift_breaks
    start = Rotation.from_quat(report.start_quaternion)
    drift = Rotation.from_quat(report.drift_quaternion)
    reached = [
        (start.inv() * drift * Rotation.from_rotvec(d.outer * d.axis)).magnitude()
        for d in report.directions
    ]
    assert max(reached) == pytest.approx(math.radians(30.0), abs=1e-9)
    assert math.degrees(report.bound.bound) > 37.0  # the simple-motion bound alone: further
    path.write_text(text + "\n[constraints.base_swing]\nmax_deg = 10\n")  # the drift: 11.9
    said = verdict(ff.reachable(ff.Scenario.from_toml(path), budget=0))
    assert said.startswith(
        "the drift attitude breaks base_swing (it lies 11.94 deg from the start attitude, at "
        "most 10 deg allowed): no goal listed above plans"
    )


def test_a_start_path_that_peaks_between_its_rows_gets_rows_there(monkeypatch):
    # SLSQP's start path sits on the bound at its rows' instants and may peak beyond it
    # between them (Canadarm2 holding 8 t: 4.6e-5 rad, and the plan was refused). Here rows at
    # 33 instants: the first run's path peaks between them; the second, with rows at its
    # peaks, holds. Truth: SciPy's integration of the path found.
    import freefloat.solvers.restore as restore
    from freefloat.solvers.options import SolveOptions

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    goal = ff.physics.attitude.quat_multiply(
        problem.start_quaternion, ff.physics.attitude.quat_exp(np.radians([0.0, 0.0, 5.0]))
    )
    problem = problem.with_goal(goal)  # 5 deg from the start: within the bound
    swing = BaseSwing(math.radians(8.0))  # the plain path turns 11.9 deg
    monkeypatch.setattr(restore, "DEFAULT_INSTANTS", np.linspace(0.0, 1.0, 33))
    monkeypatch.setattr(restore, "RESTORE_ROUNDS", 1)
    assert restore.feasible_start(problem, [swing], SolveOptions()) is None  # one run: broken
    monkeypatch.setattr(restore, "RESTORE_ROUNDS", 3)
    beta = restore.feasible_start(problem, [swing], SolveOptions())
    assert beta is not None
    largest, _ = _scipy_swing(problem.polynomials(beta), scenario.robot)
    assert largest <= math.radians(8.0) + 1e-7


def test_a_goal_beyond_the_bound_by_more_than_rounding_is_refused(worked_scenario):
    # 1e-9 rad beyond: within verification's 1e-7 but not within reach of rows that ask the
    # path to stay inside near its end; accepted, it was searched for seconds and refused.
    turn = ff.geodesic_angle(worked_scenario.start_attitude, worked_scenario.goal_attitude)
    for bound, refused in ((turn - 1e-9, True), (turn, False)):
        scenario = dataclasses.replace(worked_scenario, constraints=(BaseSwing(bound),))
        if refused:
            with pytest.raises(ff.GoalAttitudeError):
                ff.plan(scenario)
        else:
            assert ff.plan(scenario).verification.passed


def _ur5_turned(yaw_deg: float) -> ff.Scenario:
    """The UR5 servicer with its goal attitude yaw_deg in yaw and half that in pitch from
    the start: the plain path ends 11.9 deg from the start attitude, far beyond such a goal."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    goal = ff.physics.attitude.quat_multiply(
        scenario.start_attitude,
        ff.physics.attitude.quat_from_zyx(math.radians(yaw_deg), math.radians(yaw_deg / 2)),
    )
    return dataclasses.replace(scenario, goal_attitude=goal)


def test_a_goal_on_the_bound_plans_when_the_plain_path_swings_far_beyond_it():
    # The bound is the goal's own turn (6.71 deg). Before, the rows near the goal asked for
    # no room at all (half the goal's, none) at every instant, and the start path found on
    # them peaked beyond the bound between them, and it ended beyond it (no row at its end):
    # refused. Now the room tapers to the goal's only near the end and a start path's end
    # has its own row. Truth: SciPy's integration of the plan's paths.
    scenario = _ur5_turned(6.0)
    turn = ff.geodesic_angle(scenario.start_attitude, scenario.goal_attitude)
    bounded = dataclasses.replace(scenario, constraints=(BaseSwing(turn),))
    plan = ff.plan(bounded)
    swing, _ = _scipy_swing(plan, scenario.robot)
    assert turn - 1e-9 <= swing <= turn + 1e-7


def test_a_start_path_ends_within_the_bound():
    # A start path ignores the attitude: its end lies anywhere, and continuation heads from
    # there to the goal. Its end row holds it SOLVER_SLACK inside. Truth: SciPy's turn of the
    # path found, at its end and everywhere.
    import freefloat.solvers.restore as restore
    from freefloat.problem.constraints.base_swing import SOLVER_SLACK
    from freefloat.solvers.options import SolveOptions

    scenario = _ur5_turned(6.0)
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    bound = ff.geodesic_angle(scenario.start_attitude, scenario.goal_attitude)
    beta = restore.feasible_start(problem, [BaseSwing(bound)], SolveOptions())
    assert beta is not None
    path = problem.polynomials(beta)
    largest, _ = _scipy_swing(path, scenario.robot)
    assert largest <= bound + 1e-7
    end = _scipy_turns(path, scenario.robot, np.ones(1))[0]
    assert end <= bound - SOLVER_SLACK + 1e-7


def test_relaxed_rows_lead_slsqp_in_and_give_up_when_a_stage_falls_short(monkeypatch):
    # Each stage allows a fraction of the plain path's excess; the result of the last holds
    # the rows at the default instants (SciPy's turn there, against the room the rows ask:
    # full away from the goal, tapering as the cube to none at a goal on the bound). An
    # SLSQP that gets nowhere (it returns where it started) is given up after one run.
    import freefloat.solvers.restore as restore
    from freefloat.problem.constraints.base_swing import SOLVER_SLACK
    from freefloat.solvers.options import SolveOptions

    scenario = _ur5_turned(6.0)
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    bound = ff.geodesic_angle(scenario.start_attitude, scenario.goal_attitude)
    beta = restore._relaxed_start(problem, [BaseSwing(bound)], SolveOptions())
    assert beta is not None
    s = np.linspace(0.0, 1.0, 97)[1:-1]  # the rows' instants between the ends
    turns = _scipy_turns(problem.polynomials(beta), scenario.robot, s)
    room = np.minimum(SOLVER_SLACK, SOLVER_SLACK * (4.0 * (1.0 - s)) ** 3)  # none at the goal
    assert np.all(turns <= bound - room + 1e-9)
    runs = []

    def stuck(problem, active, options, instants, start, allowance=None):
        runs.append(allowance)
        return np.array(start, dtype=float)

    monkeypatch.setattr(restore, "_least_norm_within", stuck)
    assert restore._relaxed_start(problem, [BaseSwing(bound)], SolveOptions()) is None
    assert len(runs) == 1
    # a bound the plain path keeps at the rows' instants (30 deg against its 14 deg): nothing
    # to relax, no SLSQP run
    assert restore._relaxed_start(problem, [BaseSwing(math.radians(30.0))], SolveOptions()) is None
    assert len(runs) == 1


@pytest.mark.parametrize(
    ("turn_deg", "bound_deg", "said"),
    [
        (50.0, 30.0, ("50", "30")),  # a short bound: 4 digits
        (3.0, 2.9999999, ("3.0000000", "2.9999999")),  # as many digits as the bound shows
        (5.49283697583, 5.49283697582852, ("5.49283697583000", "5.49283697582852")),
        (4.0 + 1e-9, 4.0, ("4.000000001", "4")),  # just beyond: never shown at the bound
    ],
)
def test_a_turn_is_said_with_the_bounds_precision(turn_deg, bound_deg, said):
    # An outside trial read "it lies 5.493 deg ..., at most 5.49283697582852 deg allowed".
    from freefloat.problem.constraints.base_swing import degrees_apart

    assert degrees_apart(math.radians(turn_deg), math.radians(bound_deg), bound_deg) == said
