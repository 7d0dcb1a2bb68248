"""The plug-in contract: every registered constraint and objective passes the same checks.

- its Jacobian (constraints) or gradient (objectives) agrees with central finite differences
  of its own values, on a spatial servicer with free coefficients on every joint;
- its record round-trips: ``from_record(to_record())`` through JSON gives the same values;
- a plan made with it is saved, loaded and passes ``freefloat verify``, which rebuilds it from
  the registry by its record.

A plug-in defined here, in the test file (:class:`ToyCeiling`, :class:`ToyWeightedNorm`), is
registered with one line each and goes the whole way: scenario key, plan, file, verify.
A new built-in plug-in must be added to :data:`CONSTRAINT_EXAMPLES` (a test says so).
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import InputError
from freefloat.problem.constraints import (
    CONSTRAINTS,
    BasePointing,
    BaseSwing,
    Constraint,
    ConstraintRows,
    EndEffectorCone,
    Excess,
    JointEffortLimits,
    JointPositionLimits,
    JointVelocityLimits,
    scenario_constraints,
)
from freefloat.problem.constraints.base import DEFAULT_INSTANTS
from freefloat.problem.constraints.registry import SAFETY_RECORDED
from freefloat.problem.objectives import OBJECTIVES, Objective, ObjectiveValue
from test_objectives import _fd_gradient

from conftest import as_older_format

ROOT = Path(__file__).resolve().parents[1]

#: One example of every built-in constraint, given a scenario whose robot it is for.
CONSTRAINT_EXAMPLES: dict[str, Callable[[ff.Scenario], Constraint]] = {
    "joint_position_limits": lambda _: JointPositionLimits(),
    "joint_velocity_limits": lambda _: JointVelocityLimits(),
    "joint_effort_limits": lambda _: JointEffortLimits(),
    "clearance": lambda scenario: next(
        c for c in scenario_constraints(scenario) if c.name == "clearance"
    ),
    "end_effector_cone": lambda _: EndEffectorCone([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], 0.9),
    "base_swing": lambda _: BaseSwing(0.3),
    "base_pointing": lambda _: BasePointing([1.0, 0.0, 0.0], [0.9, 0.3, 0.1], 0.9),
}


# -- plug-ins defined in this test file -------------------------------------------------------


class ToyCeiling(Constraint):
    """Joint ``joint`` stays below ``ceiling`` (rad) at every instant (a test plug-in)."""

    name = "toy_ceiling"
    unit = "rad"
    affine = True

    def __init__(self, joint: str, ceiling: float) -> None:
        self.joint, self.ceiling = joint, ceiling

    def to_record(self) -> dict[str, Any]:
        return {"joint": self.joint, "ceiling_deg": math.degrees(self.ceiling)}

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> ToyCeiling:
        if set(record) != {"joint", "ceiling_deg"}:
            raise InputError(f"toy_ceiling takes joint and ceiling_deg, got {sorted(record)}")
        return cls(str(record["joint"]), math.radians(float(record["ceiling_deg"])))

    def rows(self, problem, beta, instants=DEFAULT_INSTANTS):
        i = problem.robot.joint_names.index(self.joint)
        base, dq, _ = problem.family.linear_map(np.asarray(instants, dtype=float))
        return ConstraintRows(base.q[:, i] + dq[:, i, :] @ beta - self.ceiling, dq[:, i, :])

    def critical_times(self, robot, path):
        (_, _), (_, t_hi) = path.extremes(robot.joint_names.index(self.joint), 0)
        return np.array([t_hi])

    def excess(self, robot, path):
        (_, _), (hi, t_hi) = path.extremes(robot.joint_names.index(self.joint), 0)
        return Excess(hi - self.ceiling, 0.0, f"at t = {t_hi:.4g} s")


class ToyWeightedNorm(Objective):
    """``weight * |beta|^2`` (rad^2; a test plug-in with a parameter)."""

    name = "toy_weighted_norm"
    unit = "rad^2"

    def __init__(self, weight: float = 2.0) -> None:
        self.weight = weight

    def evaluate(self, problem, beta):
        beta = np.asarray(beta, dtype=float)
        return ObjectiveValue(self.weight * float(beta @ beta), 2.0 * self.weight * beta)

    def to_record(self) -> dict[str, Any]:
        return {"weight": self.weight}

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> ToyWeightedNorm:
        return cls(float(record.get("weight", 2.0)))


@pytest.fixture
def toy_plugins(monkeypatch):
    """The test plug-ins, registered with one line each (taken out again after the test)."""
    monkeypatch.setitem(CONSTRAINTS, ToyCeiling.name, ToyCeiling)
    monkeypatch.setitem(OBJECTIVES, ToyWeightedNorm.name, ToyWeightedNorm)


@pytest.fixture(scope="module")
def ur5_scenario():
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    scenario = scenario.resolved()
    scenario.write_robot()
    return scenario


# -- the contract ------------------------------------------------------------------------------


def test_every_registered_constraint_has_a_contract_example():
    assert set(CONSTRAINTS) == set(CONSTRAINT_EXAMPLES)


@pytest.mark.parametrize("name", sorted(CONSTRAINT_EXAMPLES))
def test_constraint_jacobian_matches_finite_differences(ur5_scenario, name):
    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    problem = ff.problem_from_scenario(ur5_scenario, extra=[1] * ur5_scenario.robot.n)
    beta = 0.05 * np.random.default_rng(5).normal(size=problem.n_free)
    instants = np.linspace(0.05, 0.95, 7)
    rows = constraint.rows(problem, beta, instants)
    assert rows.count > 0 and rows.jacobian.shape == (rows.count, problem.n_free)
    h = 1e-6
    fd = np.empty_like(rows.jacobian)
    for k in range(problem.n_free):
        step = np.zeros(problem.n_free)
        step[k] = h
        plus = constraint.rows(problem, beta + step, instants).values
        minus = constraint.rows(problem, beta - step, instants).values
        fd[:, k] = (plus - minus) / (2 * h)
    scale = max(1.0, float(np.abs(rows.jacobian).max()))
    np.testing.assert_allclose(rows.jacobian, fd, rtol=1e-5, atol=1e-6 * scale)


@pytest.mark.parametrize("name", sorted(CONSTRAINT_EXAMPLES))
def test_end_rows_match_finite_differences_and_the_dense_check_at_the_end(ur5_scenario, name):
    # A start path ends anywhere: the rows at its end (none for most constraints) have the
    # Jacobian of central differences, and where given, their value less the room they ask
    # is the dense check's figure at the end (the swing's turn, the boresight's angle there,
    # from another integrator: RK5 on Pinocchio's centroidal map, attitude_check).
    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    problem = ff.problem_from_scenario(ur5_scenario, extra=[1] * ur5_scenario.robot.n)
    beta = 0.05 * np.random.default_rng(7).normal(size=problem.n_free)
    rows = constraint.end_rows(problem, beta)
    assert rows.jacobian.shape == (rows.count, problem.n_free)
    if not rows.count:
        assert name not in ("base_swing", "base_pointing")
        return
    h = 1e-6
    fd = np.empty_like(rows.jacobian)
    for k in range(problem.n_free):
        step = np.zeros(problem.n_free)
        step[k] = h
        plus = constraint.end_rows(problem, beta + step).values
        minus = constraint.end_rows(problem, beta - step).values
        fd[:, k] = (plus - minus) / (2 * h)
    scale = max(1.0, float(np.abs(rows.jacobian).max()))
    np.testing.assert_allclose(rows.jacobian, fd, rtol=1e-5, atol=1e-6 * scale)
    from freefloat.problem.constraints.attitude_check import attitude_track

    track = attitude_track(problem.robot, problem.polynomials(beta))
    at_end = constraint.at_attitude(track.fine.relative[-1]).value  # beyond the bound there
    slack = sys.modules[type(constraint).__module__].SOLVER_SLACK  # the room the row asks
    assert rows.values[0] - slack == pytest.approx(at_end, abs=1e-9)


@pytest.mark.parametrize("name", sorted(CONSTRAINT_EXAMPLES))
def test_tight_instants_find_the_tightest_value_the_dense_check_finds(ur5_scenario, name):
    # The solvers add rows at a constraint's tight instants: where given, the largest row
    # there is the exact excess of the dense check (for joint limits, the polynomials'
    # extremes from the roots of their derivatives: another method). On the integration grid
    # the planner certifies such a path on (the spacecraft's swing follows the attitude).
    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    family = ff.problem_from_scenario(ur5_scenario, extra=[2] * ur5_scenario.robot.n)
    for seed in range(4):
        beta = 0.8 * np.random.default_rng(seed).normal(size=family.n_free)
        problem = family.with_steps(family.steps_for(beta))
        tight = constraint.tight_instants(problem, beta)
        assert tight.ndim == 1 and np.all((tight >= 0.0) & (tight <= 1.0))
        assert len(tight) or name != "joint_position_limits"
        if not len(tight):
            continue
        excess = constraint.violation(problem, beta).value
        slack = constraint.solver_slack(problem, tight)  # the room the rows ask there
        largest = float((constraint.rows(problem, beta, tight).values - slack).max())
        assert largest == pytest.approx(excess, abs=1e-9)


@pytest.mark.parametrize("name", sorted(CONSTRAINT_EXAMPLES))
def test_constraint_record_round_trips(ur5_scenario, name):
    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    if name in SAFETY_RECORDED:  # recorded by the plan's safety section (test_collision)
        assert constraint.to_record() == {}
        return
    record = json.loads(json.dumps(constraint.to_record()))
    again = ff.problem.constraints.constraint_from_record(name, record)
    problem = ff.problem_from_scenario(ur5_scenario, extra=[1] * ur5_scenario.robot.n)
    beta = 0.05 * np.random.default_rng(6).normal(size=problem.n_free)
    assert type(again) is type(constraint) and again.to_record() == record
    np.testing.assert_array_equal(
        again.rows(problem, beta).values, constraint.rows(problem, beta).values
    )


@pytest.mark.parametrize("name", sorted(CONSTRAINT_EXAMPLES))
def test_a_restarted_constraint_turned_back_is_the_same(ur5_scenario, name):
    """A correction's constraints (:meth:`Constraint.restarted`): a start turned and turned
    back (SciPy's rotations) gives the same record, and a space-fixed one judges an attitude
    in space alike from either start."""
    from scipy.spatial.transform import Rotation

    constraint = CONSTRAINT_EXAMPLES[name](ur5_scenario)
    turn = Rotation.from_rotvec([0.3, -0.2, 0.5])
    there = constraint.restarted(turn.as_quat())
    back = there.restarted(turn.inv().as_quat())
    assert type(there) is type(constraint) and type(back) is type(constraint)
    _close_records(back.to_record(), constraint.to_record())
    seen = Rotation.from_rotvec([0.1, 0.05, -0.02])  # an attitude, from the first start
    from_first = constraint.at_attitude(seen.as_quat())
    if from_first is not None and there is not constraint:  # fixed in space: judged alike
        from_second = there.at_attitude((turn.inv() * seen).as_quat())
        assert from_second.value == pytest.approx(from_first.value, abs=1e-12)


def _close_records(found: object, expected: object) -> None:
    """Records equal, their numbers to 1e-12."""
    if isinstance(expected, dict):
        assert isinstance(found, dict) and found.keys() == expected.keys()
        for key, value in expected.items():
            _close_records(found[key], value)
    elif isinstance(expected, list):
        assert isinstance(found, list) and len(found) == len(expected)
        for a, b in zip(found, expected, strict=True):
            _close_records(a, b)
    elif isinstance(expected, float):
        assert found == pytest.approx(expected, abs=1e-12)
    else:
        assert found == expected


@pytest.mark.parametrize("name", sorted(OBJECTIVES))
def test_objective_gradient_and_record(ur5_scenario, name):
    problem = ff.problem_from_scenario(ur5_scenario, extra=[1] * ur5_scenario.robot.n)
    beta = 0.05 * np.random.default_rng(3).normal(size=problem.n_free)
    objective = OBJECTIVES[name]()
    found = objective.evaluate(problem, beta)
    fd = _fd_gradient(lambda b: objective.evaluate(problem, b).value, beta, h=1e-5)
    scale = max(np.abs(found.gradient).max(), 1e-300)
    np.testing.assert_allclose(found.gradient, fd, rtol=1e-5, atol=1e-7 * scale)
    again = OBJECTIVES[name].from_record(json.loads(json.dumps(objective.to_record())))
    assert again.evaluate(problem, beta).value == found.value


def test_toy_plugins_pass_the_contract(worked_scenario, toy_plugins):
    problem = ff.problem_from_scenario(worked_scenario, extra=[0, 2])
    beta = np.array([0.3, -0.2])
    ceiling = ToyCeiling("q2", 1.0)
    rows = ceiling.rows(problem, beta)
    step = 1e-6 * np.eye(2)
    fd = np.stack(
        [(ceiling.rows(problem, beta + s).values - rows.values) / 1e-6 for s in step], axis=1
    )
    np.testing.assert_allclose(rows.jacobian, fd, atol=1e-7)  # affine: forward differences
    toy = ToyWeightedNorm(3.0)
    fd = _fd_gradient(lambda b: toy.evaluate(problem, b).value, beta)
    np.testing.assert_allclose(toy.evaluate(problem, beta).gradient, fd, rtol=1e-7)
    assert ToyWeightedNorm.from_record(toy.to_record()).weight == 3.0


# -- end to end: scenario key, plan, file, freefloat verify -------------------------------------


def _scenario(tmp_path: Path, extra: str) -> Path:
    text = ff.default_scenario_path().read_text() + extra
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    return path


#: The worked example's end-effector axis (its x axis, along the arm) must stay within 60 deg
#: of the base direction at 70 deg from x: the joints' sum runs from 110 to 30 deg.
CONE = """
[constraints.end_effector_cone]
axis = [1.0, 0.0, 0.0]
direction = [0.3420201433256687, 0.9396926207859083, 0.0]
half_angle_deg = 60.0
"""


def test_cone_and_toy_plugins_round_trip_through_plan_file_and_verify(
    tmp_path, capsys, toy_plugins
):
    scenario = _scenario(
        tmp_path,
        CONE + '\n[constraints.toy_ceiling]\njoint = "q2"\nceiling_deg = 120.0\n',
    )
    out = tmp_path / "plan.json"
    code = main(["plan", str(scenario), "-o", str(out), "--objective", "toy_weighted_norm"])
    _, err = capsys.readouterr()
    assert code == 0, err
    data = json.loads(out.read_text())
    assert data["format"] == "freefloat.plan/5"
    assert data["objective"]["name"] == "toy_weighted_norm"
    assert data["objective"]["parameters"] == {"weight": 2.0}
    records = {c["name"]: c["parameters"] for c in data["constraints"]}
    assert records["toy_ceiling"] == {"joint": "q2", "ceiling_deg": pytest.approx(120.0)}
    # the degrees as written, not their round trip through radians (59.99999999999999)
    assert records["end_effector_cone"]["half_angle_deg"] == 60.0
    checks = {c["name"]: c for c in data["verification"]["checks"]}
    # Closed form, not the constraint's code: the planar arm's x axis points at q1 + q2 in
    # the base plane, so the cone's gap is cos(60 deg) - cos(q1 + q2 - 70 deg).
    plan = ff.Plan.load(out)
    t = np.linspace(0.0, plan.duration, 20001)
    q = plan.joint_positions(t)
    gap = math.cos(math.radians(60)) - np.cos(q[:, 0] + q[:, 1] - math.radians(70))
    assert checks["end_effector_cone"]["value"] == pytest.approx(gap.max(), abs=1e-7)
    assert checks["toy_ceiling"]["value"] == pytest.approx(
        q[:, 1].max() - math.radians(120), abs=1e-7
    )
    assert main(["verify", str(out)]) == 0
    capsys.readouterr()

    # verify rebuilds the constraints from the records: a ceiling 20 deg lower moves the
    # toy_ceiling check's figure by 20 deg from the one stored
    index = [c["name"] for c in data["verification"]["checks"]].index("toy_ceiling")
    for item in data["constraints"]:
        if item["name"] == "toy_ceiling":
            item["parameters"]["ceiling_deg"] = 100.0
    out.write_text(json.dumps(data))
    assert main(["verify", str(out)]) == 2
    _, err = capsys.readouterr()
    assert f"verification.checks[{index}].value' disagrees" in err
    assert f"by {math.radians(20):.3g} rad" in err


def test_a_start_or_goal_outside_the_cone_is_refused_before_any_search(tmp_path, capsys):
    """Closed form: the worked example's tool points at q1 + q2 in the base plane, 110 deg at
    the start and 30 deg at the goal, each 40 deg from the cone's direction (70 deg). With a
    35 deg half-angle no path can start or end inside: refused at once, as a joint limit is,
    with no freedom or full-turn advice; ``check`` names it at either end."""
    angle = abs(math.degrees(math.radians(80 + 30) - math.radians(70)))
    assert angle == pytest.approx(40.0)
    scenario = _scenario(tmp_path, CONE.replace("half_angle_deg = 60.0", "half_angle_deg = 35.0"))
    with pytest.raises(ff.EndpointError) as info:
        ff.plan(ff.Scenario.from_toml(scenario))
    assert (info.value.where, info.value.constraint) == ("start", "end_effector_cone")
    assert info.value.excess == pytest.approx(
        math.cos(math.radians(35)) - math.cos(math.radians(angle)), abs=1e-12
    )
    assert str(info.value) == (
        f"start configuration breaks end_effector_cone (ee's axis {angle:.4g} deg from the "
        "direction (half-angle 35 deg)), where every path starts; move the start joints or loosen "
        "[constraints.end_effector_cone]"
    )
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json")]) == 2
    assert capsys.readouterr().err.startswith(f"freefloat: error: {scenario}: start configuration")
    for where in ("start", "goal"):
        assert main(["check", str(scenario), "--at", where]) == 1
        out = capsys.readouterr().out
        assert f"end_effector_cone: ee's axis {angle:.4g} deg from the direction" in out
        assert "BROKEN" in out and "configuration: NOT OK" in out
    wide = _scenario(tmp_path, CONE.replace("half_angle_deg = 60.0", "half_angle_deg = 45.0"))
    assert main(["check", str(wide), "--at", "goal"]) == 0
    assert "half-angle 45 deg): holds" in capsys.readouterr().out


def test_a_plan_naming_an_unregistered_plugin_is_refused_in_one_line(tmp_path, capsys, worked_plan):
    data = json.loads(worked_plan.to_json())
    data["constraints"].append({"name": "toy_ceiling", "parameters": {}})
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(data))
    assert main(["verify", str(path)]) == 2
    _, err = capsys.readouterr()
    assert "toy_ceiling" in err and "end_effector_cone" in err and len(err.splitlines()) == 1


def test_scenario_constraint_errors(tmp_path):
    bad = {
        "[constraints.nope]\n": "unknown constraint 'nope'",
        "[constraints.joint_position_limits]\n": "always honoured",
        "[constraints.end_effector_cone]\naxis = [1, 0, 0]\n": "missing 'direction'",
        CONE.replace("60.0", "190.0"): "half_angle_deg must be a number between 0 and 180",
        CONE.replace("[1.0, 0.0, 0.0]", "[0, 0, 0]"): "axis must be a non-zero vector",
        # an integer beyond the floats raised OverflowError (a traceback)
        CONE.replace("[1.0, 0.0, 0.0]", f"[{10**400}, 0, 0]"): "axis must be finite numbers",
    }
    for text, message in bad.items():
        with pytest.raises(ff.FreeFloatError, match=message):
            ff.Scenario.from_toml(_scenario(tmp_path, text))
    # a vector whose norm overflows, or underflows, still has a direction
    for axis in ("[1e300, 1e300, 0.0]", "[1e-300, 0.0, 0.0]"):
        scenario = ff.Scenario.from_toml(_scenario(tmp_path, CONE.replace("[1.0, 0.0, 0.0]", axis)))
        (cone,) = scenario.constraints
        expected = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0) if "300, 1e" in axis else [1, 0, 0]
        np.testing.assert_allclose(cone.axis, expected, rtol=1e-15)


def test_a_format_3_plan_is_held_to_the_limits_it_promised(tmp_path, capsys, worked_plan):
    data = json.loads(worked_plan.to_json())
    assert [c["name"] for c in data["constraints"]] == list(
        ff.plans.versions.PROMISED["freefloat.plan/3"]
    )
    data = as_older_format(data)
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    assert main(["verify", str(path)]) == 0, capsys.readouterr().err
    loaded = ff.Plan.load(path)
    assert loaded.format == "freefloat.plan/3" and "constraints" not in loaded.to_dict()
    assert [c.name for c in loaded.constraints] == [
        c["name"] for c in worked_plan.to_dict()["constraints"]
    ]


def _tool_angles_deg(plan: ff.Plan, robot: ff.Robot, axis, direction, samples=2001):
    """Angle (deg) of the end effector's ``axis`` to ``direction`` (base frame) along the plan,
    from Pinocchio's frame placements computed here (not by the constraint's code)."""
    import pinocchio as pin

    data, frame = robot.model.createData(), robot.end_effector_frame
    out = []
    for q in plan.joint_positions(np.linspace(0.0, plan.duration, samples)):
        pin.framesForwardKinematics(robot.model, data, robot.configuration(q))
        cos = float(direction @ (data.oMf[frame].rotation @ axis))
        out.append(math.degrees(math.acos(min(1.0, max(-1.0, cos)))))
    return np.array(out)


def test_a_binding_cone_is_held_on_a_spatial_servicer(ur5_scenario, tmp_path, capsys):
    """The UR5's tool x axis swings 1.9 deg beyond its ends' angle on the default path; a cone
    0.28 deg tighter than that swing is held, touching its edge."""
    axis = np.array([1.0, 0.0, 0.0])
    free = ff.plan(ur5_scenario)
    robot = ur5_scenario.robot
    import pinocchio as pin

    data, frame = robot.model.createData(), robot.end_effector_frame
    ends = []
    for q in free.joint_positions(np.array([0.0, free.duration])):
        pin.framesForwardKinematics(robot.model, data, robot.configuration(q))
        ends.append(data.oMf[frame].rotation @ axis)
    direction = (ends[0] + ends[1]) / np.linalg.norm(ends[0] + ends[1])
    swing = _tool_angles_deg(free, robot, axis, direction)
    edge = max(swing[0], swing[-1])
    half = edge + 0.85 * (swing.max() - edge)
    assert swing.max() > half + 0.25  # the default path breaks the cone
    cone = EndEffectorCone(axis, direction, math.radians(half))
    held = ff.plan(ur5_scenario, constraints=[*scenario_constraints(ur5_scenario), cone])
    angles = _tool_angles_deg(held, robot, axis, direction, 4001)
    assert angles.max() <= half + 1e-6
    assert angles.max() > half - 0.05  # it binds
    assert main(["verify", str(held.save(tmp_path / "cone.json"))]) == 0, capsys.readouterr().err


def test_the_cones_rows_ask_a_hair_inside_but_never_beyond_the_ends_room():
    """Closed form: the worked example's tool points at q1 + q2 (110 deg at the start, 30 deg
    at the goal), 40 deg from a direction at 70 deg at both ends. The rows' half-angle is the
    cone's less SOLVER_SLACK away from the ends, or less half the roomier end's room when that
    is less; within a quarter of the motion of an end with less room than twice that, it
    tapers as the cube of the time from the end to half that end's room (room / 2 + asked
    (4 d)^3), and is never negative (none anywhere when both ends lie on the rim or beyond)."""
    from freefloat.problem.constraints.end_effector_cone import SOLVER_SLACK

    problem = ff.problem_from_scenario(ff.Scenario.from_toml(ff.default_scenario_path()))
    direction = [math.cos(math.radians(70)), math.sin(math.radians(70)), 0.0]
    s = np.array([0.0, 0.05, 0.2, 0.5, 0.9, 1.0])
    d = np.minimum(s, 1.0 - s)  # both ends have the same room here
    for half_deg, room in (
        (60.0, math.radians(20.0)),
        (40.0 + math.degrees(SOLVER_SLACK), SOLVER_SLACK),
        (40.0, 0.0),
        (39.0, -math.radians(1.0)),
    ):
        cone = EndEffectorCone([1.0, 0.0, 0.0], direction, math.radians(half_deg))
        asked = min(SOLVER_SLACK, max(0.0, room / 2))
        want = [min(asked, max(0.0, room / 2 + asked * (4 * x) ** 3)) for x in d]
        np.testing.assert_allclose(cone._slack(problem, s), want, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "cone",
    [
        # the spacecraft's yaw axis, which never tilts on a planar robot, in a cone of 2e-5
        # rad about it: inside by the whole half-angle at every instant
        lambda: BasePointing([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 2e-5),
        # the tool's z axis (the world's z on a planar robot) 40 deg from the direction, in
        # a 40 deg cone: on the rim at every instant, whatever the path
        lambda: EndEffectorCone(
            [0.0, 0.0, 1.0],
            [math.sin(math.radians(40)), 0.0, math.cos(math.radians(40))],
            math.radians(40.0),
        ),
    ],
)
def test_rows_never_ask_more_room_than_a_path_has(cone):
    # Closed form: on the planar worked example these axes never move, so every path keeps
    # exactly the room its ends have; no row may ask more (a review found rows asking the
    # full SOLVER_SLACK in mid-motion, which no path could meet, and a start path refused).
    cone = cone()
    problem = ff.problem_from_scenario(ff.Scenario.from_toml(ff.default_scenario_path()))
    for seed in range(3):
        beta = 0.3 * np.random.default_rng(seed).normal(size=problem.n_free)
        assert cone.rows(problem, beta).values.max() <= 1e-12
        assert np.all(cone.end_rows(problem, beta).values <= 1e-12)
