"""Cartesian goals, three-axis goals at pitch +-90 deg, and the spatial bounds estimate."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.physics import attitude as att

import reference as ref
import urdfs
from conftest import ROOT

CARTESIAN = """
robot = "{urdf}"
duration = 10.0
[start]
joints = {{ q1 = 80.0, q2 = 30.0 }}
base_zyx_deg = [-50.0, 0.0, 0.0]
[goal]
end_effector_xyz = [{x}, {y}, 0.0]
base_zyx_deg = [0.0, 0.0, 0.0]
[path]
extra = {{ q2 = 1 }}
"""


def _cartesian(tmp_path, x, y):
    path = tmp_path / "c.toml"
    path.write_text(CARTESIAN.format(urdf=ROOT / "robots" / "planar_2dof.urdf", x=x, y=y))
    return path


def test_cartesian_goal_recovers_the_worked_example(tmp_path, worked_plan):
    x, y = ref.end_effector(0.0, math.radians(-60), math.radians(90))  # closed form
    scenario = ff.Scenario.from_toml(_cartesian(tmp_path, x, y))
    assert scenario.goal == pytest.approx([math.radians(-60), math.radians(90)], abs=1e-9)
    plan = ff.plan(scenario)
    assert plan.free_parameters["q2"][0] == pytest.approx(
        worked_plan.free_parameters["q2"][0], rel=1e-6
    )
    assert plan.samples.end_effector_position[-1][:2] == pytest.approx([x, y], abs=1e-9)


def test_unreachable_cartesian_goal_names_the_workspace(tmp_path, capsys):
    assert main(["plan", str(_cartesian(tmp_path, 2.5, 0.3)), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    radius = ref.A + ref.B + ref.C
    assert "end-effector goal position [2.5, 0.3, 0.0] m is out of reach" in err
    assert f"the workspace radius from the system CM is about {radius:.3f} m" in err
    assert "numbers" not in err  # two joints meet an in-plane point: no count of them
    # the miss has its unit, and no configuration comes nearer than the goal's distance from
    # the system CM less the arm's full reach (closed form)
    miss = float(
        re.search(r"misses it by ([0-9.e+-]+) m \(a goal is met within 1e-09 m", err).group(1)
    )
    assert miss >= math.hypot(2.5, 0.3) - radius - 1e-3
    assert not (tmp_path / "p.json").exists()


def test_a_pose_goal_for_an_arm_of_fewer_than_six_joints_says_a_position_may_be_met(
    tmp_path, capsys
):
    """The planar two-joint arm asked for a reachable point with a tool tilted out of its
    plane: the refusal states the acceptance (1e-9 m and rad) and that a pose fixes six
    numbers where two joints are free; the same point alone plans."""
    x, y = ref.end_effector(0.0, math.radians(-60), math.radians(90))  # closed form
    text = _cartesian(tmp_path, x, y).read_text()
    path = tmp_path / "pose.toml"
    path.write_text(
        text.replace(
            "base_zyx_deg = [0.0, 0.0, 0.0]\n[path]",
            "end_effector_rpy_deg = [30.0, 0.0, 0.0]\nbase_zyx_deg = [0.0, 0.0, 0.0]\n[path]",
        )
    )
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert "(a goal is met within 1e-09 m and rad)" in err
    assert err.strip().endswith(
        "the goals fix 6 numbers and 2 joints are free to meet them: a position alone may be met"
    )
    assert ff.plan(ff.Scenario.from_toml(_cartesian(tmp_path, x, y))).verification.passed


def test_cartesian_pose_goal_on_a_servicer(tmp_path):
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mmap = ff.MomentumMap(robot)
    known = np.array([0.4, -1.2, 1.4, -1.0, -1.3, 0.2])
    quat = ff.quat_from_zyx(0.1, -0.05, 0.02)
    pose = mmap.end_effector_pose(known, quat)
    from freefloat.problem.cartesian import solve_cartesian_goal

    start = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
    found = solve_cartesian_goal(mmap, pose.translation, quat, start, pose.rotation)
    reached = mmap.end_effector_pose(found, quat)
    assert np.linalg.norm(reached.translation - pose.translation) < 1e-9
    assert (
        np.linalg.norm(
            att.quat_log(
                att.quat_multiply(att.quat_conjugate(_q(pose.rotation)), _q(reached.rotation))
            )
        )
        < 1e-8
    )


def _q(rotation):
    import pinocchio as pin

    return np.asarray(pin.Quaternion(rotation).coeffs())


def test_goal_at_pitch_90_degrees(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    robot = ff.load_robot(path)
    start_j, goal_j = [0.2, -0.3, 0.1], [1.1, 0.4, -0.6]
    probe = ff.build_problem(
        robot, start_j, goal_j, att.IDENTITY, att.IDENTITY, 8.0, extra=[1, 1, 1]
    )
    change = probe.achieved(np.array([0.03, -0.02, 0.04]))  # attitude change of a known path
    target = ff.quat_from_zyx(0.3, math.pi / 2, 0.0)  # pitch exactly +90 deg
    start = att.quat_multiply(target, att.quat_conjugate(change))
    scenario = ff.Scenario(
        robot,
        8.0,
        dict(zip(robot.joint_names, start_j, strict=True)),
        dict(zip(robot.joint_names, goal_j, strict=True)),
        start_attitude=start,
        goal_attitude=target,
        extra={"j1": 1, "j2": 1, "j3": 1},
    )
    plan = ff.plan(scenario)
    assert plan.base.attitude_error_rad < 1e-9
    assert plan.base.achieved_zyx_deg[1] == pytest.approx(90.0, abs=1e-4)
    assert ff.geodesic_angle(np.array(plan.base.achieved_quaternion_xyzw), target) < 1e-9


def test_spatial_bounds_inner_estimate(tmp_path, capsys):
    figure = tmp_path / "reach.png"
    scenario = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
    code = main(
        ["bounds", str(scenario), "--max-angle", "5", "--budget", "60", "--plot", str(figure)]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "INNER ESTIMATE" in out and "may reach further" in out
    rows = [line.split() for line in out.splitlines() if line.strip()[:1] in ("+", "-")]
    assert len(rows) == 14  # six axis directions and eight diagonals
    for row in rows:
        assert 0.0 <= float(row[3]) <= 5.0 + 1e-9
    assert figure.stat().st_size > 0


def test_solved_goal_joints_take_the_turn_nearest_the_start():
    """An unlimited joint solved whole turns away from its start (ETS-VII's wrist at -209 deg
    from 20 deg, where 151 deg is the same pose) is moved to the turn nearest the start: the
    same frame placement (Pinocchio's kinematics) and within half a turn of the start."""
    import pinocchio as pin

    from freefloat.problem.cartesian import _nearest_turns

    robot = ff.load_robot(ROOT / "robots" / "planar_2dof.urdf")  # two continuous joints
    start = np.radians([20.0, 30.0])
    solved = np.radians([-209.0, 30.0 + 720.0])
    nearer = _nearest_turns(robot, solved, start)
    assert np.degrees(nearer) == pytest.approx([151.0, 30.0], abs=1e-9)
    model, data = robot.model, robot.model.createData()
    frame = model.getFrameId(robot.end_effector)
    placed = []
    for joints in (solved, nearer):
        pin.framesForwardKinematics(model, data, robot.configuration(joints))
        placed.append(data.oMf[frame].homogeneous.copy())
    assert placed[0] == pytest.approx(placed[1], abs=1e-12)
