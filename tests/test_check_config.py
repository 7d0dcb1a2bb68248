"""freefloat check (one configuration: limits, closest pairs, clearance), the fixed-extra hint,
the shipped sweep scenario, and plans' samples as arrays."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main

ROOT = Path(__file__).resolve().parents[1]
UR5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"


def _urdf_limits(urdf: Path) -> dict[str, tuple[float, float]]:
    """Joint limits (rad) read from the URDF text itself."""
    out = {}
    for joint in ET.parse(urdf).getroot().iter("joint"):
        limit = joint.find("limit")
        if limit is not None and joint.get("type") == "revolute":
            out[joint.get("name")] = (float(limit.get("lower")), float(limit.get("upper")))
    return out


def test_check_reports_limits_and_exit_code(capsys) -> None:
    limits = _urdf_limits(ROOT / "robots" / "ur5_servicer.urdf")
    elbow_upper = math.degrees(limits["elbow_joint"][1])
    beyond = elbow_upper + 5.0
    assert main(["check", str(UR5), "--at", f"0,-90,{beyond},-90,-90,0"]) == 1
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.strip().startswith("elbow_joint"))
    value, _, upper, room = (float(x) for x in row.split()[1:5])
    assert (value, upper) == pytest.approx((beyond, elbow_upper), abs=1e-3)
    assert room == pytest.approx(-5.0, abs=1e-3) and "OUTSIDE" in row
    assert "configuration: NOT OK" in out


def test_a_joint_a_hair_beyond_its_limit_shows_a_room_that_is_not_zero(capsys) -> None:
    """0.0004 deg beyond the elbow's URDF limit: the row prints the room with the decimals
    that show it (-0.0004, not -0.000), and the value and limit apart."""
    limits = _urdf_limits(ROOT / "robots" / "ur5_servicer.urdf")
    beyond = math.degrees(limits["elbow_joint"][1]) + 0.0004
    assert main(["check", str(UR5), "--at", f"0,-90,{beyond!r},-90,-90,0"]) == 1
    row = next(line for line in capsys.readouterr().out.splitlines() if "elbow_joint" in line)
    value, _, upper, room = row.split()[1:5]
    assert room == "-0.0004" and float(value) > float(upper) and "OUTSIDE" in row


def test_check_names_the_closest_pair_at_the_goal(capsys) -> None:
    assert main(["check", str(UR5), "--at", "goal"]) == 0
    out = capsys.readouterr().out
    distances = [float(x) for x in re.findall(r"(-?\d+\.\d+) m$", out, re.M)]
    pairs = distances[:-1]  # the last is the clearance line's margin
    assert pairs == sorted(pairs) and len(pairs) == 5
    # The planner's start/goal check (pipeline) agrees: the goal keeps the margin.
    plan_scenario = ff.Scenario.from_toml(UR5)
    assert f"clearance {pairs[0]:.4f} m keeps the margin" in out
    assert plan_scenario.safety.margin < pairs[0]


@pytest.mark.parametrize(
    "at",
    [
        "1,2",
        "a,b,c,d,e,f",
        "nan,0,0,0,0,0",
        "1_0,0,0,0,0,0",  # float() takes these three
        "\u0661,0,0,0,0,0",
        "0,0,0,0,0,0,",
        "1e300,0,0,0,0,0",
    ],
)
def test_check_refuses_bad_joints_in_one_line(at: str, capsys) -> None:
    assert main(["check", str(UR5), "--at", at]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("freefloat: error: --at") and "\n" not in err


def test_a_fixed_extra_too_small_is_named_in_the_refusal() -> None:
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())  # extra = { q2 = 1 }
    # 40 deg of yaw change lies inside the planar bounds (1.358, 72.27) deg but one free
    # coefficient on q2 has no root there; automatic freedom plans it.
    goal = replace(scenario, goal_attitude=ff.quat_from_zyx(math.radians(-10.0)))
    with pytest.raises(ff.SolverError) as info:
        ff.plan(goal)
    assert "fixes [path] extra" in str(info.value) and "remove [path] extra" in str(info.value)
    planned = ff.plan(replace(goal, extra=None))
    assert planned.base.attitude_error_rad < 1e-9


def test_the_shipped_sweep_scenario_plans_inside_the_planar_bounds(tmp_path) -> None:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        'scenario = "worked_example_sweep.toml"\nsamples = 21\n[[axis]]\n'
        'key = "goal.base_zyx_deg.0"\nvalues = { start = -55.0, stop = 25.0, num = 17 }\n'
        '[[axis]]\nkey = "goal.joints.q2"\nvalues = [60.0, 120.0]\n'
    )
    rows = ff.sweep(sweep, workers=2, output=tmp_path / "out.csv", progress=False)
    for row in rows:
        low, high = row.yaw_change_min_deg, row.yaw_change_max_deg
        inside = low < row.requested_yaw_change_deg < high
        assert row.status == ("planned" if inside else "infeasible"), row.message


def test_samples_are_arrays_and_survive_the_file(tmp_path) -> None:
    plan = ff.plan(ff.Scenario.from_toml(ff.default_scenario_path()), samples=11)
    assert plan.samples.q.shape == (11, 2) and plan.samples.t.shape == (11,)
    assert plan.samples.base_quaternion_xyzw.shape == (11, 4)
    np.testing.assert_allclose(plan.samples.q[-1], plan.request.goal_joints, atol=1e-12)
    again = ff.Plan.load(plan.save(tmp_path / "p.json"))
    assert again == plan and isinstance(again.samples.tau, np.ndarray)


def test_check_says_why_clearance_was_not_checked(tmp_path, capsys) -> None:
    """`[safety] check = false` is named as the reason, not a guess between two."""
    text = UR5.read_text()
    assert "[safety]" not in text
    path = tmp_path / "unchecked.toml"
    path.write_text(f"{text}\n[safety]\ncheck = false\n")
    assert main(["check", str(path)]) == 0
    assert (
        "  clearance: not checked ([safety] check = false)" in capsys.readouterr().out.splitlines()
    )


def test_check_warns_of_joint_values_that_look_like_radians(capsys) -> None:
    """--at is in degrees, as scenario files: a ROS joint state pasted in radians is warned of
    with the scenario's own words (-1.57 rad = -1.57 * 180 / pi = -89.95 deg); degrees are not."""
    assert main(["check", str(UR5), "--at", "0,-1.57,1.57,0,1.2,0"]) == 0
    err = capsys.readouterr().err
    assert err == (
        "freefloat: warning: --at joints look like radians (every value within +-6.28, "
        "shoulder_lift_joint = -1.57); scenario joints are in degrees (-1.57 rad is -89.95 deg)\n"
    )
    assert main(["check", str(UR5), "--at", "0,-90,90,-90,-90,0"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_joint_values_that_start_negative_are_taken_as_values(capsys) -> None:
    """``--at -10,-90,...`` (argparse takes a leading minus for an option) reads as written."""
    assert main(["check", str(UR5), "--at", "-10,-90,90,-90,-90,0"]) in (0, 1)
    out = capsys.readouterr().out
    values = [float(row.split()[1]) for row in out.splitlines() if row.strip().endswith("deg")]
    assert values == [-10.0, -90.0, 90.0, -90.0, -90.0, 0.0]


@pytest.mark.parametrize(
    ("at", "said"),
    [
        ("-3e1,0,0,0,0,0", "configuration:"),
        ("-inf,0,0,0,0,0", "joint 'shoulder_pan_joint' is not finite"),
        ("-36.6;-76.4", "comma-separated numbers"),
    ],
)
def test_values_that_start_negative_reach_the_parser(at, said, capsys) -> None:
    """argparse said "expected one argument" for each: the value is read and judged."""
    main(["check", str(UR5), "--at", at])
    out, err = capsys.readouterr()
    assert said in out + err and "expected one argument" not in err


def test_a_value_that_is_not_finite_is_named_not_counted(capsys) -> None:
    assert main(["check", str(UR5), "--at", "0,0,nan,0,0,0"]) == 2
    err = capsys.readouterr().err.strip()
    assert "joint 'elbow_joint' is not finite" in err and "got 6" not in err


def test_the_start_is_checked_whatever_the_cartesian_goal(tmp_path, capsys) -> None:
    """An end-effector goal 10 m away has no joints: only ``--at goal`` needs them."""
    text = UR5.read_text()
    goal = re.search(r"^\[goal\]\n(joints = .*\n)", text, re.M)
    assert goal
    far = text.replace(goal.group(1), "end_effector_xyz = [10.0, 0.0, 0.0]\n")
    scenario = tmp_path / "far.toml"  # the robot by its shipped name
    scenario.write_text(far)
    assert main(["check", str(scenario), "--at", "start"]) == 0, capsys.readouterr().err
    capsys.readouterr()
    assert main(["check", str(scenario), "--at", "goal"]) == 2
    assert "out of reach" in capsys.readouterr().err
