"""Property tests: random arms and reachable goals give a verified plan or a clear error."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import freefloat as ff


@st.composite
def arms(draw):
    """URDF text of a random spacecraft with a 2- to 7-joint serial arm (primitive geometry)."""
    n = draw(st.integers(2, 7))
    floats = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False)  # noqa: E731
    base_mass = draw(floats(50.0, 800.0))
    size = [draw(floats(0.5, 2.0)) for _ in range(3)]
    ixx = base_mass * (size[1] ** 2 + size[2] ** 2) / 12
    iyy = base_mass * (size[0] ** 2 + size[2] ** 2) / 12
    izz = base_mass * (size[0] ** 2 + size[1] ** 2) / 12
    parts = [
        f'<link name="base"><inertial><mass value="{base_mass}"/>'
        f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial>'
        f'<visual><geometry><box size="{size[0]} {size[1]} {size[2]}"/></geometry></visual>'
        "</link>"
    ]
    planar = draw(st.booleans()) and n <= 4
    parent, offset = "base", [size[0] / 2, draw(floats(-0.3, 0.3)), draw(floats(-0.3, 0.3))]
    if planar:
        offset[2] = 0.0
    for i in range(1, n + 1):
        kind = draw(st.sampled_from(["revolute", "continuous", "prismatic"]))
        if planar:
            kind = draw(st.sampled_from(["revolute", "continuous"]))
            axis = np.array([0.0, 0.0, 1.0])
        else:
            axis = np.array([draw(floats(-1, 1)) for _ in range(3)])
            if np.linalg.norm(axis) < 0.2:
                axis = np.array([0.0, 0.0, 1.0])
            axis /= np.linalg.norm(axis)
        length, mass = draw(floats(0.2, 1.0)), draw(floats(1.0, 30.0))
        radius = 0.04
        ia = mass * radius**2 / 2
        it = mass * (3 * radius**2 + length**2) / 12
        limit = {
            "revolute": '<limit lower="-3.0" upper="3.0" effort="100" velocity="5"/>',
            "continuous": '<limit effort="100" velocity="5"/>',
            "prismatic": '<limit lower="-0.3" upper="0.3" effort="100" velocity="1"/>',
        }[kind]
        parts.append(
            f'<joint name="j{i}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="{offset[0]} {offset[1]} {offset[2]}"/>'
            f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>{limit}</joint>'
            f'<link name="l{i}"><inertial><origin xyz="{length / 2} 0 0"/>'
            f'<mass value="{mass}"/><inertia ixx="{ia}" iyy="{it}" izz="{it}" ixy="0" ixz="0" '
            f'iyz="0"/></inertial><visual><origin xyz="{length / 2} 0 0" rpy="0 1.5708 0"/>'
            f'<geometry><cylinder radius="{radius}" length="{length}"/></geometry></visual>'
            "</link>"
        )
        parent, offset = f"l{i}", [length, 0.0, 0.0]
    return '<?xml version="1.0"?><robot name="random">' + "".join(parts) + "</robot>"


@settings(
    max_examples=10,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(urdf=arms(), data=st.data())
def test_random_arms_plan_verified_or_raise(tmp_path, urdf, data):
    path = tmp_path / "arm.urdf"
    path.write_text(urdf)
    robot = ff.load_robot(path)
    rng = np.random.default_rng(data.draw(st.integers(0, 2**31)))
    lower = np.array([max(j.lower, -1.5) for j in robot.joints])
    upper = np.array([min(j.upper, 1.5) for j in robot.joints])
    start, goal = rng.uniform(lower, upper), rng.uniform(lower, upper)
    start_quat = ff.quat_from_zyx(*rng.uniform(-1, 1, 3))
    # A goal attitude reachable by construction: the one some path of the family reaches.
    probe = ff.build_problem(robot, start, goal, start_quat, start_quat, 4.0, check_bounds=False)
    goal_quat = probe.achieved(0.01 * rng.normal(size=probe.n_free))
    if probe.planar:  # a planar base keeps its pitch and roll
        yaw = ff.zyx_from_quat(goal_quat)[0] - ff.zyx_from_quat(start_quat)[0]
        goal_quat = ff.physics.attitude.quat_multiply(
            start_quat, ff.physics.attitude.quat_exp([0, 0, yaw])
        )
    scenario = ff.Scenario(
        robot=robot,
        duration=4.0,
        start_joints=dict(zip(robot.joint_names, start, strict=True)),
        goal_joints=dict(zip(robot.joint_names, goal, strict=True)),
        start_attitude=start_quat,
        goal_attitude=goal_quat,
    )
    try:
        plan = ff.plan(scenario, samples=41)
    except ff.FreeFloatError as exc:
        assert str(exc) and "\n" not in str(exc)
        event(f"refused: {type(exc).__name__}")
        return
    event("planned (planar)" if plan.feasibility.planar else "planned (spatial)")
    assert plan.base.attitude_error_rad < 1e-9
    again = ff.verify_plan(ff.Plan.load(plan.save(tmp_path / "p.json")), robot)
    assert again.passed, again.failures
    assert again["attitude_independent"].value < 1e-7
    momentum = again["momentum"]
    assert math.isfinite(momentum.value) and momentum.value <= momentum.tolerance


def test_regression_diverging_sqp_is_a_failed_attempt_not_a_crash():
    """Found by the property test: SLSQP wandered to non-finite coefficients on this arm."""
    from conftest import ROOT

    robot = ff.load_robot(ROOT / "tests" / "data" / "prismatic_tilted_arm.urdf")
    rng = np.random.default_rng(164)
    lower = np.array([max(j.lower, -1.5) for j in robot.joints])
    upper = np.array([min(j.upper, 1.5) for j in robot.joints])
    outcomes = []
    for _ in range(2):
        start, goal = rng.uniform(lower, upper), rng.uniform(lower, upper)
        quat = ff.quat_from_zyx(*rng.uniform(-1, 1, 3))
        probe = ff.build_problem(robot, start, goal, quat, quat, 4.0, check_bounds=False)
        scenario = ff.Scenario(
            robot,
            4.0,
            dict(zip(robot.joint_names, start, strict=True)),
            dict(zip(robot.joint_names, goal, strict=True)),
            start_attitude=quat,
            goal_attitude=probe.achieved(0.01 * rng.normal(size=probe.n_free)),
        )
        try:
            ff.plan(scenario, samples=41)
            outcomes.append("planned")
        except ff.FreeFloatError as exc:  # anything else would fail the test
            outcomes.append(type(exc).__name__)
    assert outcomes[0] == "planned"
    # a refusal of the search (out of reach from its start: the subclass), never a crash
    assert outcomes[1] in ("SolverError", "UnreachableAttitudeError")
