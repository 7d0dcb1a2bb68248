"""What `freefloat plan` prints: wall time and shares, Cartesian goals, full turns, units."""

from __future__ import annotations

import dataclasses
import logging
import math
import re

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.cli.messages import in_degrees
from freefloat.viz.summary import clearance_line, robot_label, rotation_angle

import reference as ref
from conftest import ROOT

SCENARIO = """
robot = "{urdf}"
duration = 10.0
[start]
joints = {{ q1 = 80.0, q2 = 30.0 }}
base_zyx_deg = [-50.0, 0.0, 0.0]
[goal]
{goal}
[path]
{path}
"""


def _write(tmp_path, goal, path="extra = { q2 = 1 }"):
    out = tmp_path / "s.toml"
    urdf = ROOT / "robots" / "planar_2dof.urdf"
    out.write_text(SCENARIO.format(urdf=urdf, goal=goal, path=path))
    return out


def _plan(tmp_path, capsys, scenario, *flags):
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), *flags]) == 0
    return capsys.readouterr().out


def test_cartesian_goal_shows_the_chosen_joints_and_the_end_effector_error(tmp_path, capsys):
    x, y = ref.end_effector(0.0, math.radians(-60), math.radians(90))  # closed form
    goal = f"end_effector_xyz = [{x!r}, {y!r}, 0.0]\nbase_zyx_deg = [0.0, 0.0, 0.0]"
    out = _plan(tmp_path, capsys, _write(tmp_path, goal))
    assert "goal joints     (inverse kinematics) q1 -60.000 deg, q2 90.000 deg" in out
    error = float(re.search(r"position error (\S+) m", out).group(1))
    assert error < 1e-9
    assert f"goal ({x:.4f}, {y:.4f}, 0.0000) m" in out


def test_wall_time_and_the_solve_share(tmp_path, capsys):
    goal = "joints = { q1 = -60.0, q2 = 90.0 }\nbase_zyx_deg = [0.0, 0.0, 0.0]"
    out = _plan(tmp_path, capsys, _write(tmp_path, goal))
    match = re.search(
        r"wall time +(\d+\.\d+) s total: .*solve (\d+\.\d+) s \((\d+) %\), "
        r"sample and verify (\d+\.\d+) s \((\d+) %\)",
        out,
    )
    assert match, out
    total, solve, share = float(match.group(1)), float(match.group(2)), int(match.group(3))
    # The printed seconds are rounded to 1 ms: the share lies within what that rounding allows.
    low = 100 * max(solve - 5e-4, 0.0) / (total + 5e-4)
    high = 100 * (solve + 5e-4) / max(total - 5e-4, 1e-9)
    assert 0 < solve <= total and low - 1 <= share <= high + 1
    assert "final solver call" in out and "free parameters q2: " in out
    assert "as monomials    q2: t^6" in out
    assert re.search(r"t\^6 \S+ rad/s\^6", out)
    assert "planar_2dof (planar_2dof.urdf, 2 joints)" in out


def test_full_turns_show_start_goal_and_travel(tmp_path, capsys):
    goal = "joints = { q1 = -60.0, q2 = 90.0 }\nbase_zyx_deg = [-90.0, 0.0, 0.0]"
    scenario = _write(tmp_path, goal, path="")
    out = _plan(tmp_path, capsys, scenario, "--allow-full-turns")
    assert (
        "full turns      q1: start 80.000 deg, goal 300.000 deg (-60.000 deg +1 turn(s)), "
        "travels 220.000 deg" in out
    )


def test_inline_servicer_is_named_by_arm_and_base(tmp_path, monkeypatch):
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "s.toml"
    path.write_text(
        """
duration = 10.0
[robot]
arm = "ur5"
base_mass = 120.0
base_size = [0.6, 0.5, 0.4]
mount = [0.3, 0.0, 0.0]
[start]
joints = { shoulder_pan_joint = 0.0, shoulder_lift_joint = -60.0, elbow_joint = 90.0, \
wrist_1_joint = 0.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0 }
[goal]
joints = { shoulder_pan_joint = 10.0, shoulder_lift_joint = -60.0, elbow_joint = 90.0, \
wrist_1_joint = 0.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0 }
"""
    )
    label = robot_label(ff.Scenario.from_toml(path))
    assert label == "servicer: ur5 arm on a 120 kg, 0.6 x 0.5 x 0.4 m base (6 joints)"


def test_velocity_limit_error_is_printed_in_degrees_per_second():
    err = ff.VelocityLimitError("q1", 5.625, 2.0, 2.8125, "rad")
    text = in_degrees(err)
    assert f"reaches {math.degrees(5.625):.4g} deg/s" in text
    assert f"velocity limit {math.degrees(2.0):.4g} deg/s" in text
    assert "rad" not in text and "2.813 s" in text  # 2.8125 s rounded up
    metres = ff.VelocityLimitError("slide", 0.5, 0.2, 3.0, "m")
    assert in_degrees(metres) == str(metres)


def test_rounding_level_figures_print_as_zero():
    """An achieved angle of -1e-12 deg prints as 0.000000 (no minus sign), and an excursion
    beyond a span of 2.5e-14 deg (the extremes' rounding) as 0, naming no joint as the
    largest (none goes beyond its span); a real one as itself, with its joint."""
    import dataclasses

    from freefloat.viz.summary import _attitude_table, quality_line

    plan = ff.plan(ff.Scenario.from_toml(ff.default_scenario_path()))
    base = dataclasses.replace(plan.base, achieved_zyx_deg=[-1e-12, 0.0, -0.0])
    achieved = _attitude_table(dataclasses.replace(plan, base=base))[-1]
    assert "-0.000000" not in achieved and achieved.split()[1:] == ["0.000000"] * 3
    joint = plan.robot.joints[0]
    for excursion, shown in ((2.54e-14, "0 deg"), (0.25, "0.25 deg")):
        quality = dataclasses.replace(
            plan.quality,
            largest_joint=joint,
            largest_excursion=excursion,
            excursion_beyond_span={joint: excursion},
        )
        line = quality_line(dataclasses.replace(plan, quality=quality))
        named = f" ({joint})" if excursion > 1e-9 else ""
        assert f"span {shown}{named}; {joint} {shown}" in line


def test_the_summary_names_each_path_constraint_and_its_margin(tmp_path, capsys):
    """A scenario with an end-effector cone: the printed summary lists the cone beside the
    joint limits, margins in degrees (an all-revolute arm), the cone by its detail (its value
    is a cosine gap: no margin in degrees). The position margin agrees with the plan's
    samples against the URDF's limits (read from the file here), to what 201 samples can miss
    of the exact extremes."""
    import xml.etree.ElementTree as ET

    import numpy as np

    path = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
    cone = (
        "\n[constraints.end_effector_cone]\naxis = [1.0, 0.0, 0.0]\n"
        "direction = [1.0, 0.0, 0.0]\nhalf_angle_deg = 179.0\n"
    )
    scenario = tmp_path / "cone.toml"
    scenario.write_text(path.read_text() + cone)
    out = _plan(tmp_path, capsys, scenario)
    line = next(x for x in out.splitlines() if x.startswith("  constraints "))
    assert "rad" not in line and " deg/s, " in line
    assert re.search(
        r", end_effector_cone \(\w+'s axis [\d.]+ deg from the direction \(half-angle "
        r"179 deg\) at t = [\d.]+ s\)$",
        line,
    ), line
    printed = float(re.search(r"joint_position_limits ([0-9.e+-]+) deg", line).group(1))
    plan = ff.Plan.load(tmp_path / "p.json")
    urdf = ET.parse(ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf").urdf).getroot()
    limits = {
        j.get("name"): (float(j.find("limit").get("lower")), float(j.find("limit").get("upper")))
        for j in urdf.iter("joint")
        if j.find("limit") is not None and j.get("type") == "revolute"
    }
    q = np.asarray(plan.samples.q, dtype=float)
    sampled = min(
        min(q[:, i].min() - limits[name][0], limits[name][1] - q[:, i].max())
        for i, name in enumerate(plan.robot.joints)
    )
    assert 0.0 < printed <= math.degrees(sampled) * 1.005 + 1e-9
    assert printed >= 0.99 * math.degrees(sampled)


def test_verify_reads_a_constraint_row_with_the_plans_own_figure(tmp_path, capsys):
    """The note under verify's table explains a constraint row with that row's own value
    (the clearance the plan file records), not a made-up one."""
    out = tmp_path / "p.json"
    assert (
        main(["plan", str(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"), "-o", str(out)])
        == 0
    )
    capsys.readouterr()
    assert main(["verify", str(out)]) == 0
    note, closest = capsys.readouterr().out.rstrip().splitlines()[-2:]
    saved = ff.Plan.load(out)
    clearance = next(c for c in saved.verification.checks if c.name == "clearance")
    assert clearance.value < 0.0
    assert note == (
        f"  it holds (clearance {clearance.value:.3g} m: the smallest distance is at least "
        f"{-clearance.value:.3g} m beyond the margin)"
    )
    # the closest pair, its instant and the margin: the line plan prints, word for word
    assert closest == clearance_line(saved)
    assert closest.startswith("  clearance       min clearance ") and "margin 0.01 m" in closest


def test_a_spacecraft_lighter_than_what_it_carries_is_warned_about(tmp_path, caplog):
    """A 1 kg root carrying two 5 kg links (the URDF of an arm alone, say): plan says so, with
    the masses read from the file; the shipped servicer (104 kg under a 17 kg arm) says
    nothing of the kind."""
    import logging

    import numpy as np

    import urdfs

    body = urdfs.BASE.format(mass=1.0, i=0.05)
    body += urdfs.joint("q1", "base", "l1") + urdfs.link("l1")
    body += urdfs.joint("q2", "l1", "l2") + urdfs.link("l2")
    urdf = tmp_path / "arm_alone.urdf"
    urdf.write_text(urdfs.robot(body))
    robot = ff.load_robot(urdf)
    problem = ff.build_problem(
        robot, [0.2, 0.3], [0.6, -0.2], ff.quat_from_zyx(0.0), ff.quat_from_zyx(0.0), 4.0
    )
    reached = problem.achieved(np.zeros(problem.n_free))
    scenario = ff.Scenario(
        robot, 4.0, {"q1": 0.2, "q2": 0.3}, {"q1": 0.6, "q2": -0.2}, goal_attitude=reached
    )
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        ff.plan(scenario)
    said = [r.getMessage() for r in caplog.records if "lighter than" in r.getMessage()]
    assert said == [
        "the spacecraft (the URDF's root link 'base', 1 kg) is lighter than the arm it "
        "carries (10 kg); if the URDF describes an arm alone, add a spacecraft with freefloat "
        "compose or an inline [robot] table"
    ]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="freefloat"):  # reach says it too
        ff.reachable(scenario, budget=0)
    assert [r.getMessage() for r in caplog.records if "lighter than" in r.getMessage()] == said
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    assert not any("lighter than" in r.getMessage() for r in caplog.records)
    # a captured client five times the servicer's mass is a real case, not a slip
    held = tmp_path / "held.toml"
    held.write_text(
        (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
        + "\n[payload]\nmass = 500.0\ninertia = [50.0, 50.0, 50.0, 0.0, 0.0, 0.0]\n"
    )
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        ff.reachable(ff.Scenario.from_toml(held), budget=0)
    assert not any("lighter than" in r.getMessage() for r in caplog.records)


def test_verify_reads_a_limit_row_when_there_is_no_clearance(tmp_path, capsys):
    """The UR5 servicer with clearance turned off: the note reads its first constraint row,
    the joint position limits, with that row's figure, inside its limits."""
    text = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
    scenario = tmp_path / "unchecked.toml"
    scenario.write_text(f"{text}\n[safety]\ncheck = false\n")
    out = tmp_path / "p.json"
    assert main(["plan", str(scenario), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["verify", str(out)]) == 0
    note = capsys.readouterr().out.strip().splitlines()[-1]
    checks = ff.Plan.load(out).verification.checks
    assert not any(c.name == "clearance" for c in checks)
    row = next(c for c in checks if c.name == "joint_position_limits")
    assert row.value < 0.0
    assert note == (
        f"  it holds (joint_position_limits {row.value:.3g} {row.unit}: the tightest is "
        f"{-row.value:.3g} {row.unit} inside it)"
    )


def test_a_joint_turned_a_full_turn_beyond_its_span_is_warned_of(tmp_path, caplog):
    """min_effort on ETS-VII turned its continuous wrist 16 turns beyond its span: legal for the
    model, seldom for the real joint. A turn or more beyond the span of a turning joint is
    named with its count of turns; a prismatic joint's metres and smaller swings are not."""
    import logging

    from freefloat.pipeline import _warn_spinning
    from freefloat.plans.records import PathQuality

    import urdfs

    urdf = tmp_path / "mixed.urdf"
    urdf.write_text(urdfs.spatial_arm(kinds=("continuous", "prismatic", "revolute")))
    robot = ff.load_robot(urdf)
    a, b, c = robot.joint_names
    quality = PathQuality({a: 900.0, b: 720.0, c: 359.0}, 900.0, a, 10.0)
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        _warn_spinning(quality, robot, "min_effort")
    said = [r.getMessage() for r in caplog.records if "full turn" in r.getMessage()]
    assert len(said) == 1 and f"({a!r} 2.5 turns)" in said[0] and "min_effort" in said[0]
    assert said[0].endswith("give it limits in the URDF, or plan with the default objective")
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="freefloat"):  # already the default one
        _warn_spinning(quality, robot, "min_norm")
    said = [r.getMessage() for r in caplog.records if "full turn" in r.getMessage()]
    assert len(said) == 1 and said[0].endswith("give it limits in the URDF")
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    assert plan.quality is not None and plan.quality.largest_excursion < 360.0
    assert not any("full turn" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 2e-9, 1e-6, 0.3, 2.0, 3.1])
def test_the_orientation_error_printed_is_the_rotations_angle_to_rounding(angle):
    """The angle of a rotation built by Rodrigues' formula about a skew axis, read back to
    within rounding at every size (an arc cosine of the trace printed 1.2e-6 deg for a pose
    error of 5e-14 deg)."""
    axis = np.array([0.3, -0.5, 0.81])
    axis /= np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    rotation = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
    assert rotation_angle(rotation) == pytest.approx(angle, rel=1e-12, abs=1e-15)


def test_joints_without_velocity_or_effort_limits_are_named(tmp_path, capsys):
    """A URDF whose second joint has no <limit> (no velocity, no effort): the plan summary
    names that joint for both, beside the constraints; the UR5 servicer (every limit given)
    has no such line. Not a warning: the paper's own planar model gives no limit at all."""
    import urdfs

    body = urdfs.BASE.format(mass=100.0, i=10.0)
    body += urdfs.joint("q1", "base", "l1") + urdfs.link("l1")
    body += urdfs.joint("q2", "l1", "l2", "continuous").replace(
        '<limit effort="50" velocity="2"/>', ""
    )
    body += urdfs.link("l2")
    urdf = tmp_path / "unlimited.urdf"
    urdf.write_text(urdfs.robot(body))
    assert urdf.read_text().count("<limit") == 1  # q1's alone
    path = tmp_path / "unlimited.toml"
    text = (
        f'robot = "{urdf}"\nduration = 4.0\n[start]\njoints = {{ q1 = 10.0, q2 = 20.0 }}\n'
        "[goal]\njoints = { q1 = 30.0, q2 = -10.0 }\n"
    )
    path.write_text(text)
    problem = ff.problem_from_scenario(ff.Scenario.from_toml(path))
    drift = problem.achieved(np.zeros(problem.n_free))  # a goal attitude that plans
    path.write_text(text + f"base_quaternion_xyzw = {drift.tolist()}\n")
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 0
    out = capsys.readouterr().out
    said = [line for line in out.splitlines() if line.startswith("  URDF limits")]
    assert said == [
        "  URDF limits     no velocity limit for 'q2'; no effort limit for 'q2': none imposed there"
    ]
    ur5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
    assert main(["plan", str(ur5), "-o", str(tmp_path / "u.json")]) == 0
    assert "URDF limits" not in capsys.readouterr().out


def test_a_unitless_check_is_summarised_by_its_detail(tmp_path, capsys):
    """The README's scenario keeps the tool's x axis within 60 deg of a direction: its
    constraints line gives the largest angle and when (a cosine gap alone said nothing), and
    that angle is the one Pinocchio's kinematics give at that instant (the cone's angle does
    not depend on the base attitude: the tool's orientation relative to the spacecraft)."""
    import numpy as np
    import pinocchio as pin

    block = re.search(r"```toml\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    path = tmp_path / "cone.toml"
    path.write_text(block)
    assert main(["plan", str(path), "-o", str(tmp_path / "cone.json")]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("  constraints"))
    said = re.search(
        r"end_effector_cone \(\w+'s axis ([\d.]+) deg from the direction \(half-angle 60 deg\) at "
        r"t = ([\d.]+) s\)",
        line,
    )
    assert said is not None, line
    angle, when = float(said.group(1)), float(said.group(2))
    plan = ff.Plan.load(tmp_path / "cone.json")
    robot = ff.load_robot(ROOT / "robots" / "planar_2dof.urdf")
    q = robot.configuration(plan.joint_positions(when), [0.0, 0.0, 0.0], ff.quat_from_zyx(0.0))
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    tool = data.oMf[robot.model.getFrameId("ee")].rotation @ np.array([1.0, 0.0, 0.0])
    direction = np.array([0.34, 0.94, 0.0]) / np.linalg.norm([0.34, 0.94, 0.0])
    truth = math.degrees(math.acos(float(np.clip(tool @ direction, -1.0, 1.0))))
    assert angle == pytest.approx(truth, abs=0.01)


def test_a_far_planar_swing_suggests_more_freedom_which_helps(tmp_path, capsys):
    """The worked example with automatic freedom and the goal yaw -20 deg: its path swings q1
    265 deg beyond its span (one coefficient, the least that reaches the goal). The summary
    says more free coefficients may swing less, and they do: with two on each joint the
    largest excursion, sampled densely here, is far smaller."""
    from freefloat.cli import main

    base = (ROOT / "tests" / "data" / "worked_example_auto.toml").read_text()
    text = base.replace(
        "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }   # [deg]; end effector at (1.71, -0.29) m "
        "from the CM\nbase_zyx_deg = [0.0, 0.0, 0.0]",
        "[goal]\njoints = { q1 = -60.0, q2 = 90.0 }\nbase_zyx_deg = [-20.0, 0.0, 0.0]",
    )
    assert "[-20.0, 0.0, 0.0]" in text
    (tmp_path / "far.toml").write_text(text)
    assert main(["plan", str(tmp_path / "far.toml"), "-o", str(tmp_path / "far.json")]) == 0
    assert "more free coefficients ([path] extra on every joint) may find one" in (
        capsys.readouterr().out
    )
    (tmp_path / "more.toml").write_text(text + "\n[path]\nextra = { q1 = 2, q2 = 2 }\n")
    assert main(["plan", str(tmp_path / "more.toml"), "-o", str(tmp_path / "more.json")]) == 0

    def swing(path):  # beyond the start-goal span, the largest over joints (rad)
        plan = ff.Plan.load(path)
        q = plan.joint_positions(np.linspace(0.0, plan.duration, 20001))
        low, high = np.minimum(q[0], q[-1]), np.maximum(q[0], q[-1])
        return float(np.max(np.maximum(q.max(axis=0) - high, low - q.min(axis=0))))

    assert swing(tmp_path / "far.json") > np.radians(200.0)
    assert swing(tmp_path / "more.json") < 0.5 * swing(tmp_path / "far.json")


def test_the_header_names_the_end_effector_that_holds_the_payload(tmp_path):
    """A payload is held by the first end effector listed: the summary's header says which,
    and how heavy; the URDF the robot was loaded from fixes it there (read with ElementTree)."""
    import xml.etree.ElementTree as ET

    from freefloat.robot.payload import PAYLOAD_LINK
    from freefloat.viz.summary import robot_label

    text = (ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml").read_text()
    text = text.replace(
        'robot = "dual_ur5_servicer"', f'robot = "{ROOT / "robots"}/dual_ur5_servicer.urdf"'
    )
    text += "\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\n"
    for order in (["left_tool0", "right_tool0"], ["right_tool0", "left_tool0"]):
        path = tmp_path / "held.toml"
        listed = 'end_effectors = ["left_tool0", "right_tool0"]'
        assert listed in text
        path.write_text(text.replace(listed, f"end_effectors = {order!r}".replace("'", '"')))
        scenario = ff.Scenario.from_toml(path)
        assert robot_label(scenario).endswith(f", a 5 kg payload held by {order[0]})")
        root = ET.fromstring(scenario.robot.urdf_text)
        joint = next(j for j in root.iter("joint") if j.find("child").get("link") == PAYLOAD_LINK)
        assert joint.find("parent").get("link") == order[0]


def test_held_by_names_the_end_effector_that_holds_the_payload(tmp_path):
    """``[payload] held_by`` picks the holder whatever the order the end effectors are listed
    in (ElementTree reads where the URDF fixes it); a name that is not one of them is refused
    with the ones that are."""
    import xml.etree.ElementTree as ET

    from freefloat.robot.payload import PAYLOAD_LINK
    from freefloat.viz.summary import robot_label

    text = (ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml").read_text()
    text = text.replace(
        'robot = "dual_ur5_servicer"', f'robot = "{ROOT / "robots"}/dual_ur5_servicer.urdf"'
    )
    path = tmp_path / "held.toml"
    for holder in ("right_tool0", "left_tool0"):
        path.write_text(
            text + f'\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\nheld_by = "{holder}"\n'
        )
        scenario = ff.Scenario.from_toml(path)
        assert tuple(scenario.robot.end_effectors) == ("left_tool0", "right_tool0")  # order kept
        assert robot_label(scenario).endswith(f", a 5 kg payload held by {holder})")
        root = ET.fromstring(scenario.robot.urdf_text)
        joint = next(j for j in root.iter("joint") if j.find("child").get("link") == PAYLOAD_LINK)
        assert joint.find("parent").get("link") == holder
    for bad, said in (
        ('"wrist_3_link"', "[payload] held_by 'wrist_3_link' is not one of the scenario's end "
         "effectors: 'left_tool0', 'right_tool0'"),
        ('""', "[payload] held_by must name the end effector that holds it, got ''"),
        ("3", "[payload] held_by must name the end effector that holds it, got 3"),
    ):  # fmt: skip
        path.write_text(text + f"\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\nheld_by = {bad}\n")
        with pytest.raises(ff.ScenarioError) as info:
            ff.Scenario.from_toml(path)
        assert said in str(info.value)


def test_a_body_whose_inertia_no_solid_has_is_warned_of_once(tmp_path, caplog):
    """link2's moments 10, 3.33, 3.33 kg m^2 (10 > 3.33 + 3.33) were planned without a word,
    where the payload and --base-inertia checks refuse the same flaw. Truth: the moments as
    written (diagonal: they are the principal ones); the shipped robots are all physical."""
    text = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    start = text.index('<link name="link2">')
    old = text[
        text.index("<inertia ", start) : text.index("/>", text.index("<inertia ", start)) + 2
    ]
    urdf = tmp_path / "bad.urdf"
    urdf.write_text(
        text.replace(old, '<inertia ixx="10.0" iyy="3.33" izz="3.33" ixy="0" ixz="0" iyz="0"/>')
    )
    scenario = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    path = tmp_path / "bad.toml"
    path.write_text(scenario.replace('robot = "planar_2dof"', f'robot = "{urdf}"'))
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        ff.plan(ff.Scenario.from_toml(path))
    said = [r.getMessage() for r in caplog.records if "no solid's" in r.getMessage()]
    assert said == [
        "the inertia of the body moved by q2 (3.33, 3.33, 10 kg m^2) is no solid's: its largest "
        "principal moment exceeds the sum of the other two; planned as the URDF gives it"
    ]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        for name in ("worked_example", "ur5_servicer"):
            ff.reachable(
                ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml"), budget=0
            )
    assert not any("no solid's" in r.getMessage() for r in caplog.records)


def test_the_summary_says_how_far_the_spacecraft_turns_on_the_way():
    """How far the spacecraft turns on the way went unsaid (Canadarm2 with a 5 t payload
    swung it 82.5 deg for a 2.46 deg goal). Truth: SciPy's rotations of the plan's samples."""
    from scipy.spatial.transform import Rotation

    from freefloat.physics.attitude import quat_from_zyx, zyx_from_quat
    from freefloat.viz.summary import summary

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "worked_example.toml")
    start = zyx_from_quat(scenario.start_attitude)
    turned = dataclasses.replace(
        scenario,
        goal_joints=dict(scenario.start_joints),  # a loop: back to its joints, 5 deg turned
        goal_attitude=quat_from_zyx(start[0] + math.radians(5.0), 0.0, 0.0),
        extra=None,
    )
    plan = ff.plan(turned)
    rotations = Rotation.from_quat(np.asarray(plan.samples.base_quaternion_xyzw))
    turns = np.degrees((rotations[0].inv() * rotations).magnitude())
    k = int(np.argmax(turns))
    goal = Rotation.from_quat(plan.base.target_quaternion_xyzw)
    away = np.degrees((rotations[0].inv() * goal).magnitude())
    assert turns[k] > away + 1.0  # a loop swings it beyond its goal
    line = next(x for x in summary(plan).splitlines() if x.startswith("  spacecraft"))
    assert line == (
        f"  spacecraft      turns up to {turns[k]:.3g} deg from its start attitude on the way "
        f"(at t = {plan.samples.t[k]:.4g} s, the largest of {len(turns)} samples); its goal "
        f"lies {away:.3g} deg from it"
    )
