"""A one-joint planar robot: every path turns the spacecraft alike.

With one joint the base's rate is ``f(q) q'``, so its attitude obeys an ODE in ``q`` alone and
a path that goes back and forth retraces it: the goal attitude is fixed by the joints. Truth
here: SciPy's integrator on Pinocchio's centroidal map along two different joint paths (one
monotone, one that overshoots and comes back), not the planner's Magnus scheme or planar map.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

import freefloat as ff
from freefloat.cli import main

#: A 100 kg box and one link turning about the box's y axis, off its centre.
URDF = """<?xml version="1.0"?>
<robot name="one">
  <link name="base"><inertial><mass value="100"/>
    <inertia ixx="10" iyy="10" izz="10" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.5 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-{limit}" upper="{limit}" velocity="100" effort="1000"/></joint>
  <link name="l1"><inertial><origin xyz="{lever} 0 0"/><mass value="{mass}"/>
    <inertia ixx="0.1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""

SCENARIO = """robot = "one.urdf"
duration = 10.0
[start]
joints = {{ j1 = 0.0 }}
[goal]
joints = {{ j1 = {travel} }}
{goal}
[safety]
check = false
"""

#: (lever m, mass kg, limit rad, travel deg): a short turn, and 5 turns of a heavy far link
#: (the problem's first grid of 64 steps missed that one's change by 3e-4 rad)
ARMS = [(0.5, 10.0, 3.0, 60.0), (1.5, 80.0, 70.0, 1800.0)]


def _paths(goal: float):
    """Two joint paths (q rad, qd rad/s) on [0, 1] s from 0 to ``goal`` (rad): the quintic,
    and one that goes 1.2 rad beyond it at mid-way and comes back."""

    def monotone(t: float) -> tuple[float, float]:
        s = 10 * t**3 - 15 * t**4 + 6 * t**5
        return goal * s, goal * (30 * t**2 - 60 * t**3 + 30 * t**4)

    def overshoot(t: float) -> tuple[float, float]:
        q, qd = monotone(t)
        return q + 1.2 * math.sin(math.pi * t) ** 2, qd + 1.2 * math.pi * math.sin(2 * math.pi * t)

    return monotone, overshoot


def _omega(model: pin.Model, data: pin.Data, q: float, qd: float) -> np.ndarray:
    """The base's angular velocity (rad/s, base frame) at zero momentum, from Pinocchio's
    centroidal map."""
    config = pin.neutral(model)
    config[7] = q
    ag = pin.computeCentroidalMap(model, data, config)
    return -np.linalg.solve(ag[:, :6], ag[:, 6:] @ np.array([qd]))[3:]


def _pitch(model: pin.Model, path) -> float:
    """The base's final turn about y (rad) along ``path(t) -> (q, qd)`` on [0, 1] s."""
    data = model.createData()

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return _omega(model, data, *path(t))[1:2]  # the base turns about y alone

    return float(solve_ivp(rhs, (0.0, 1.0), [0.0], rtol=1e-12, atol=1e-14).y[0, -1])


@pytest.mark.parametrize(("lever", "mass", "limit", "travel"), ARMS)
def test_a_one_joint_robot_reaches_one_attitude_and_says_which(
    tmp_path, capsys, lever, mass, limit, travel
) -> None:
    text = URDF.format(lever=lever, mass=mass, limit=limit)
    (tmp_path / "one.urdf").write_text(text)

    def one(goal: str) -> str:
        path = tmp_path / "one.toml"
        path.write_text(SCENARIO.format(goal=goal, travel=travel))
        return str(path)

    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    monotone, overshoot = _paths(math.radians(travel))
    exact = _pitch(model, monotone)
    assert _pitch(model, overshoot) == pytest.approx(exact, abs=1e-9)
    # the planner says so, naming that turn
    assert main(["plan", one("base_zyx_deg = [0.0, -5.0, 0.0]"), "-o", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err
    said = re.search(r"by (-?[\d.]+) deg about its y axis", err)
    assert said and float(said.group(1)) == pytest.approx(math.degrees(exact), rel=1e-8)  # 9 digits
    # bounds gives that one change, no interval of gains
    assert main(["bounds", one("base_zyx_deg = [0.0, -5.0, 0.0]")]) == 0
    out = capsys.readouterr().out
    printed = re.search(r"yaw change: (-?[\d.]+) deg \(along every path\)", out)
    assert printed and float(printed.group(1)) == pytest.approx(math.degrees(exact), abs=1e-6)
    assert "g_min" not in out
    # reach says there is nothing to reach, and the attitude to paste in full
    assert main(["reach", one("base_zyx_deg = [0.0, -5.0, 0.0]"), "-q"]) == 0
    out = capsys.readouterr().out
    assert out.count("one joint: every path turns the spacecraft alike") == 2
    pasted = re.search(r"base_quaternion_xyzw = (\[[^\]]+\]) \(the figures", out)
    assert pasted
    quaternion = [float(v) for v in pasted.group(1).strip("[]").split(",")]
    assert quaternion[1] == pytest.approx(math.sin(exact / 2), abs=1e-9)
    # and that attitude plans
    plan = ff.plan(ff.Scenario.from_toml(one(f"base_quaternion_xyzw = {quaternion}")))
    assert plan.verification.passed and plan.base.attitude_error_rad <= 1e-9
    assert (
        main(["plan", one(f"base_quaternion_xyzw = {quaternion}"), "-o", str(tmp_path / "o.json")])
        == 0
    )
    summary = capsys.readouterr().out  # the one change is its own interval: not "beyond"
    assert re.search(r"planar bounds   yaw change \S+ deg in \(", summary), summary
    # and no loop corrects it (it said "cannot turn ... within the plan's limits")
    saved = plan.save(tmp_path / "one.plan.json")
    assert main(["correct", str(saved), "--base-zyx-deg", "1", "2", "3"]) == 2
    assert "a robot with one joint cannot correct its attitude" in capsys.readouterr().err


def _final_attitude(model: pin.Model, path) -> np.ndarray:
    """The base quaternion ``[x, y, z, w]`` at t = 1 s from rest at the identity, by SciPy on
    the quaternion equation with Pinocchio's centroidal map along ``path(t) -> (q, qd)``."""
    data = model.createData()

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        w = _omega(model, data, *path(t))
        x, y_, z, s = y
        return 0.5 * np.array(  # q (x) [w, 0] / 2, w in the base frame
            [
                s * w[0] + y_ * w[2] - z * w[1],
                s * w[1] + z * w[0] - x * w[2],
                s * w[2] + x * w[1] - y_ * w[0],
                -(x * w[0] + y_ * w[1] + z * w[2]),
            ]
        )

    end = solve_ivp(rhs, (0.0, 1.0), [0.0, 0.0, 0.0, 1.0], rtol=1e-12, atol=1e-14).y[:, -1]
    return end / np.linalg.norm(end)


def test_a_spatial_one_joint_robot_reaches_one_attitude_and_says_which(tmp_path, capsys):
    """A joint about (0.3, 0.5, 0.8): the base turns about changing axes, still alike along
    a monotone path and one that overshoots (SciPy); plan names that attitude, reach says so,
    and the quaternion it prints plans."""
    text = URDF.format(lever=0.5, mass=10.0, limit=3.0).replace(
        '<axis xyz="0 1 0"/>', '<axis xyz="0.3 0.5 0.8"/>'
    )
    (tmp_path / "one.urdf").write_text(text)
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    monotone, overshoot = _paths(math.radians(60.0))
    exact = _final_attitude(model, monotone)
    assert ff.geodesic_angle(_final_attitude(model, overshoot), exact) < 1e-9
    scenario = tmp_path / "one.toml"
    scenario.write_text(SCENARIO.format(goal="base_zyx_deg = [-10.0, 0.0, 0.0]", travel=60.0))
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    named = re.search(r"can only be base_quaternion_xyzw = (\[[^\]]+\])", err)
    assert named, err
    quaternion = np.array([float(v) for v in named.group(1).strip("[]").split(",")])
    assert ff.geodesic_angle(quaternion, exact) < 1e-8
    assert main(["reach", str(scenario), "-q"]) == 0
    out = capsys.readouterr().out
    assert out.count("one joint: every path turns the spacecraft alike") == 14
    assert "one joint: every path between these joints reaches the drift attitude" in out
    assert "inner estimate: continuation" not in out and "(outer: as far as" not in out
    assert main(["bounds", str(scenario)]) == 0  # no continuation to run: the one attitude
    said = re.search(r"reaches base_quaternion_xyzw = (\[[^\]]+\])", capsys.readouterr().out)
    assert said
    bounded = np.array([float(v) for v in said.group(1).strip("[]").split(",")])
    assert ff.geodesic_angle(bounded, exact) < 1e-8
    scenario.write_text(
        SCENARIO.format(goal=f"base_quaternion_xyzw = {quaternion.tolist()}", travel=60.0)
    )
    plan = ff.plan(ff.Scenario.from_toml(scenario))
    assert plan.verification.passed and plan.base.attitude_error_rad <= 1e-9


def test_every_turned_goal_refused_up_front_says_so(tmp_path, capsys) -> None:
    """A continuous one-joint robot with full turns allowed: each turned goal is refused
    before any search, and the refusal read "best residual nan rad"."""
    text = URDF.format(lever=0.5, mass=10.0, limit=3.0).replace(
        'type="revolute"', 'type="continuous"'
    )
    (tmp_path / "one.urdf").write_text(text)
    scenario = tmp_path / "one.toml"
    scenario.write_text(
        SCENARIO.format(goal="base_zyx_deg = [0.0, -5.0, 0.0]", travel=60.0)
        + "[path]\nallow_full_turns = true\n"
    )
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("freefloat: error: no goal tried can be reached; tried: goal as stated")
    assert "nan" not in err and "j1 +1 turn(s): a robot with one joint" in err
