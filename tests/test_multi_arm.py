"""Servicers with two arms: several end effectors, goals per arm, locked joints (issue 24).

Truth here is computed without freefloat: Pinocchio's own free-flyer model built from the
URDF file, placed at the base pose the plan reports, for forward kinematics; the arms' own
URDFs for what a locked joint must leave in place; example-robot-data's SRDF files for the
pairs that must not be checked.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.viz.playback import EXTRAS, build_playback

from conftest import ROOT, as_older_format
from urdfs import BASE, joint, link, robot

DUAL = ROOT / "robots" / "dual_ur5_servicer.urdf"
SCENARIO = ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml"
UR5_START = {
    "shoulder_pan_joint": 0.0,
    "shoulder_lift_joint": -90.0,
    "elbow_joint": 90.0,
    "wrist_1_joint": -90.0,
    "wrist_2_joint": -90.0,
    "wrist_3_joint": 0.0,
}


def _joints_toml(values: dict[str, float]) -> str:
    return "{ " + ", ".join(f"{k} = {v!r}" for k, v in values.items()) + " }"


def _both(values: dict[str, float]) -> dict[str, float]:
    return {f"{side}_{k}": v for side in ("left", "right") for k, v in values.items()}


def _pinocchio_frames(urdf, joints: dict[str, float], base_xyz, base_xyzw) -> pin.Data:
    """Frame placements by Pinocchio alone: its free-flyer model of the file, at that pose."""
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    q = pin.neutral(model)
    q[:3] = base_xyz
    q[3:7] = base_xyzw
    for name, value in joints.items():
        index = model.joints[model.getJointId(name)].idx_q
        q[index] = value  # every joint here is revolute
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return model, data


# -- the shipped dual-arm scenario ----------------------------------------------------------


@pytest.fixture(scope="module")
def dual_plan():
    """The shipped scenario planned once (with clearance between the arms: the slow part)."""
    scenario = ff.Scenario.from_toml(SCENARIO)
    return scenario, ff.plan(scenario)


@pytest.mark.slow
def test_shipped_dual_scenario_plans_and_verifies(dual_plan):
    _scenario, plan = dual_plan
    assert plan.format == "freefloat.plan/5"
    assert plan.verification.passed and plan.safety.checked
    assert plan.safety.srdf is not None and plan.safety.srdf.endswith("dual_ur5_servicer.srdf")
    assert plan.robot.end_effectors == ["left_tool0", "right_tool0"]
    assert sorted(plan.samples.end_effector_paths) == ["left_tool0", "right_tool0"]
    # the right arm holds its pose all the way: its joints never leave their start values
    q = np.asarray(plan.samples.q)
    for i, name in enumerate(plan.robot.joints):
        if name.startswith("right_"):
            start = math.radians(UR5_START[name.removeprefix("right_")])
            assert np.max(np.abs(q[:, i] - start)) < 1e-12, name
    # the spacecraft reaches its three-axis attitude
    goal = ff.quat_from_zyx(*np.radians([-5.0, -1.0, -4.0]))
    assert ff.geodesic_angle(np.asarray(plan.samples.base_quaternion_xyzw[-1]), goal) < 1e-7
    # the left tool is at its goal: Pinocchio's own frames at the plan's final base pose
    final = dict(zip(plan.robot.joints, plan.joint_positions(plan.duration), strict=True))
    model, data = _pinocchio_frames(
        DUAL, final, plan.samples.base_position[-1], plan.samples.base_quaternion_xyzw[-1]
    )
    tip = data.oMf[model.getFrameId("left_tool0")].translation
    np.testing.assert_allclose(tip, [0.48, 0.63, -0.43], atol=1e-7)
    for frame in ("left_tool0", "right_tool0"):
        recorded = plan.samples.end_effector_paths[frame][-1]
        np.testing.assert_allclose(
            recorded, data.oMf[model.getFrameId(frame)].translation, atol=1e-7
        )


@pytest.mark.slow
def test_shipped_dual_plan_plays_back_every_end_effector(dual_plan):
    _, plan = dual_plan
    playback = build_playback(plan)
    clips = playback.animation.clips
    for node, frame in ((f"{EXTRAS}/end_effector", 0), (f"{EXTRAS}/end_effector_2", 1)):
        clip = next(c for path, c in clips.items() if path.lower().endswith(node))
        positions = np.array(clip.tracks["position"].values)
        path = plan.samples.end_effector_paths[plan.robot.end_effectors[frame]]
        np.testing.assert_allclose(positions, np.asarray(path), atol=1e-9)


def test_dual_plan_page_legend_has_each_trail_in_its_colour(dual_plan):
    """One path line per end effector, in the colour the scene draws that trail in."""
    import base64
    import gzip
    import json
    import re

    import umsgpack

    from freefloat.viz.playback import page_html

    _, plan = dual_plan
    text = page_html(plan)
    legend = re.search(r'<ul id="ff-legend">(.*?)</ul>', text).group(1)
    said = dict(
        re.findall(r'background:(#[0-9a-f]{6})"></span>end-effector path \(([^)]*)\)', legend)
    )
    assert sorted(said.values()) == sorted(plan.robot.end_effectors), legend
    packed = json.loads(re.search(r"const commands = (\[.*?\]);", text).group(1))
    colours = {}
    for item in packed:
        command = umsgpack.unpackb(gzip.decompress(base64.b64decode(item)))
        if command.get("type") == "set_object" and "/trail" in command["path"]:
            tail = command["path"].rsplit("/", 1)[-1]
            colours[tail] = f"#{command['object']['materials'][0]['color']:06x}"
    trails = {"trail": plan.robot.end_effectors[0], "trail_2": plan.robot.end_effectors[1]}
    assert {trails[node]: colour for node, colour in colours.items()} == {
        frame: colour for colour, frame in said.items()
    }
    assert len(set(colours.values())) == 2


@pytest.mark.slow
def test_dual_plan_exports_and_reloads_every_path(dual_plan, tmp_path):
    from freefloat.export.csv_file import columns
    from freefloat.export.trajectory import from_samples

    _, plan = dual_plan
    saved = ff.Plan.load(plan.save(tmp_path / "dual.json"))
    assert saved.samples == plan.samples  # every array, every end effector's path
    traj = from_samples(saved)
    header = columns(traj)
    assert "ee_right_tool0_x [m]" in header and header.count("ee_x [m]") == 1
    assert (
        main(
            [
                "export",
                str(tmp_path / "dual.json"),
                "--format",
                "csv",
                "-o",
                str(tmp_path / "d.csv"),
            ]
        )
        == 0
    )
    rows = np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1)
    right = header.index("ee_right_tool0_x [m]")
    np.testing.assert_allclose(
        rows[:, right : right + 3], plan.samples.end_effector_paths["right_tool0"]
    )


@pytest.mark.slow
def test_dual_plan_bag_and_mcap_say_which_frame_each_end_effector_topic_follows(
    dual_plan, tmp_path
):
    """Read back by rosbags and mcap themselves: each file records the frame of every
    end-effector topic, and the points on each topic are that frame's path in the plan."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.rosbag2 import Reader
    from ruamel.yaml import YAML

    _, plan = dual_plan
    source = plan.save(tmp_path / "dual.json")
    frames = plan.robot.frames
    expected = {"/end_effector": frames[0], "/end_effector_2": frames[1]}
    mcap_file = tmp_path / "d.mcap"
    assert main(["export", str(source), "--format", "mcap", "-o", str(mcap_file)]) == 0
    points: dict[str, list] = {}
    with open(mcap_file, "rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        (record,) = [m for m in reader.iter_metadata() if m.name == "freefloat.end_effectors"]
        assert json.loads(record.metadata["topics"]) == expected
        for _, channel, _, decoded in reader.iter_decoded_messages(topics=list(expected)):
            points.setdefault(channel.topic, []).append(
                [decoded.point.x, decoded.point.y, decoded.point.z]
            )
    for topic, frame in expected.items():
        np.testing.assert_allclose(
            points[topic], plan.samples.end_effector_paths[frame], atol=1e-12
        )
    bag = tmp_path / "bag"
    assert main(["export", str(source), "--format", "ros2-bag", "-o", str(bag)]) == 0
    with Reader(bag) as reader:  # a bag rosbags reads; its metadata by rosbags' own YAML
        assert set(reader.topics) >= set(expected)
    info = YAML(typ="safe").load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert json.loads(info["custom_data"]["freefloat.end_effectors"]) == expected


@pytest.mark.slow
def test_dual_plan_figures_draw_every_end_effector(dual_plan):
    from freefloat.viz.plots import figures

    _, plan = dual_plan
    figure = figures(plan, ["end_effector_path"])["end_effector_path"]
    lines = {line.get_label(): line for line in figure.axes[0].get_lines()}
    for frame in plan.robot.end_effectors:
        drawn = lines[f"path {frame}"].get_xydata()
        np.testing.assert_allclose(drawn, np.asarray(plan.samples.end_effector_paths[frame])[:, :2])


# -- two Cartesian goals at once --------------------------------------------------------------


def test_two_cartesian_goals_meet_independent_forward_kinematics(tmp_path):
    """Goals for both tools (one with orientation), taken from a configuration's frames; the
    plan's final configuration and base pose put both tools there (Pinocchio's frames)."""
    left = {
        "shoulder_pan_joint": 25.0,
        "shoulder_lift_joint": -75.0,
        "elbow_joint": 80.0,
        "wrist_1_joint": -85.0,
        "wrist_2_joint": -80.0,
        "wrist_3_joint": 10.0,
    }
    right = {
        "shoulder_pan_joint": -20.0,
        "shoulder_lift_joint": -100.0,
        "elbow_joint": 95.0,
        "wrist_1_joint": -95.0,
        "wrist_2_joint": -95.0,
        "wrist_3_joint": -15.0,
    }
    chosen = {f"left_{k}": math.radians(v) for k, v in left.items()}
    chosen |= {f"right_{k}": math.radians(v) for k, v in right.items()}
    attitude = ff.quat_from_zyx(*np.radians([2.0, -1.5, 1.0]))
    # the base position of that configuration: the one that keeps the CM at the origin
    model = pin.buildModelFromUrdf(str(DUAL), pin.JointModelFreeFlyer())
    data = model.createData()
    q = pin.neutral(model)
    q[3:7] = attitude
    for name, value in chosen.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    q[:3] = -pin.centerOfMass(model, data, q)
    pin.framesForwardKinematics(model, data, q)
    goal_left = data.oMf[model.getFrameId("left_tool0")].translation.copy()
    goal_right = data.oMf[model.getFrameId("right_tool0")]
    rpy = pin.rpy.matrixToRpy(goal_right.rotation)
    text = f"""robot = "{DUAL}"
duration = 20.0
end_effectors = ["left_tool0", "right_tool0"]
[start]
joints = {_joints_toml(_both(UR5_START))}
[goal]
base_zyx_deg = [2.0, -1.5, 1.0]
[goal.end_effectors.left_tool0]
xyz = {goal_left.tolist()!r}
[goal.end_effectors.right_tool0]
xyz = {goal_right.translation.tolist()!r}
rpy_deg = {np.degrees(rpy).tolist()!r}
[safety]
check = false
"""
    path = tmp_path / "two.toml"
    path.write_text(text)
    plan = ff.plan(ff.Scenario.from_toml(path))
    assert plan.verification.passed
    final = dict(zip(plan.robot.joints, plan.joint_positions(plan.duration), strict=True))
    model, data = _pinocchio_frames(
        DUAL, final, plan.samples.base_position[-1], plan.samples.base_quaternion_xyzw[-1]
    )
    reached_left = data.oMf[model.getFrameId("left_tool0")]
    reached_right = data.oMf[model.getFrameId("right_tool0")]
    np.testing.assert_allclose(reached_left.translation, goal_left, atol=1e-7)
    np.testing.assert_allclose(reached_right.translation, goal_right.translation, atol=1e-7)
    angle = np.linalg.norm(pin.log3(goal_right.rotation.T @ reached_right.rotation))
    assert angle < 1e-7


def test_a_goal_for_one_arm_moves_only_that_arm(tmp_path):
    """With a goal for the left tool only, the right arm's joints keep their start values."""
    scenario = ff.Scenario.from_toml(SCENARIO).resolved()
    for name, value in scenario.goal_joints.items():
        if name.startswith("right_"):
            assert value == scenario.start_joints[name]
        else:
            assert name.startswith("left_")


# -- locked joints --------------------------------------------------------------------------


def test_locked_joints_of_a_urdf_robot_keep_the_bodies_where_they_were(tmp_path):
    """[robot] urdf + lock: the locked robot's frames equal the full robot's at the lock values."""
    start = {**_both(UR5_START), "right_wrist_2_joint": -80.0}
    text = f"""duration = 10.0
end_effectors = ["left_tool0", "right_tool0"]
[robot]
urdf = "{DUAL}"
lock = ["right_wrist_3_joint", {{ joint = "right_wrist_2_joint", value = -80.0 }}]
[start]
joints = {_joints_toml(start)}
[goal]
joints = {_joints_toml({**start, "left_elbow_joint": 60.0})}
"""
    path = tmp_path / "locked.toml"
    path.write_text(text)
    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    assert robot.n == 10 and "right_wrist_2_joint" not in robot.joint_names
    values = {k: math.radians(v) for k, v in start.items()}
    attitude = ff.quat_from_zyx(0.3, -0.2, 0.1)
    model, data = _pinocchio_frames(DUAL, values, [0.1, -0.2, 0.3], attitude)
    q = robot.configuration(scenario.start, [0.1, -0.2, 0.3], attitude)
    mine = robot.model.createData()
    pin.framesForwardKinematics(robot.model, mine, q)
    for frame in ("right_tool0", "left_tool0", "right_wrist_3_link"):
        expected = data.oMf[model.getFrameId(frame)]
        got = mine.oMf[robot.model.getFrameId(frame)]
        np.testing.assert_allclose(got.homogeneous, expected.homogeneous, atol=1e-12)


def test_a_joint_locked_without_a_value_whose_range_excludes_0_is_fixed_mid_range(tmp_path, caplog):
    """[robot] urdf + lock = ["j2"], j2 limited to [0.3, 0.7] rad and no start value for it: it
    is fixed at 0.5 rad (not refused for 0), the tip where Pinocchio puts it on the full URDF
    at j2 = 0.5."""
    body = BASE.format(mass=200.0, i=30.0)
    body += joint("j1", "base", "l1", axis=(0, 0, 1)) + link("l1")
    body += joint("j2", "l1", "l2", axis=(0, 1, 0), limits=(0.3, 0.7)) + link("l2")
    body += joint("tip_joint", "l2", "tip", "fixed") + '\n  <link name="tip"/>'
    urdf = tmp_path / "mid.urdf"
    urdf.write_text(robot(body))
    path = tmp_path / "mid.toml"
    path.write_text(
        f'duration = 10.0\n[robot]\nurdf = "{urdf}"\nlock = ["j2"]\n'
        "[start]\njoints = { j1 = 0.0 }\n[goal]\njoints = { j1 = 30.0 }\n"
    )
    with caplog.at_level("WARNING"):
        locked = ff.Scenario.from_toml(path).robot
    assert locked.joint_names == ["j1"]
    said = "joint 'j2' locked at 28.6479 deg, the middle of its range [17.19, 40.11] deg"
    assert any(r.getMessage().startswith(said) for r in caplog.records)
    full = pin.buildModelFromUrdf(str(urdf))
    data = full.createData()
    pin.framesForwardKinematics(full, data, np.array([0.4, 0.5]))
    mine = locked.model.createData()
    q = locked.configuration(np.array([0.4]), [0.0, 0.0, 0.0], ff.quat_from_zyx(0.0))
    pin.framesForwardKinematics(locked.model, mine, q)
    tip = mine.oMf[locked.model.getFrameId("tip")].homogeneous
    np.testing.assert_allclose(tip, data.oMf[full.getFrameId("tip")].homogeneous, atol=1e-12)


def _scenario_error(tmp_path, text: str) -> str:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ff.FreeFloatError) as info:
        ff.Scenario.from_toml(path)
    message = str(info.value)
    assert "\n" not in message
    return message


STATES = f"""[start]
joints = {_joints_toml(_both(UR5_START))}
[goal]
joints = {_joints_toml(_both(UR5_START))}
"""


def test_lock_and_end_effector_mistakes_are_one_line_naming_the_choices(tmp_path):
    robot = f'[robot]\nurdf = "{DUAL}"\n'
    message = _scenario_error(
        tmp_path,
        f'duration = 5.0\nend_effector = "left_tool0"\n{robot}'
        f'lock = [{{ joint = "left_elbow_joint", value = 400.0 }}]\n{STATES}',
    )
    assert (
        "joint 'left_elbow_joint' locked at 400 deg: outside its limits [-180, 180] deg" in message
    )
    message = _scenario_error(
        tmp_path,
        f'duration = 5.0\nend_effector = "left_tool0"\n{robot}lock = ["left_elbow"]\n{STATES}',
    )
    assert "unknown joint to lock 'left_elbow'; valid: left_shoulder_pan_joint," in message
    message = _scenario_error(tmp_path, f'duration = 5.0\nrobot = "{DUAL}"\n{STATES}')
    assert (
        "the end effector is ambiguous: 2 chains are longest (left_tool0, right_tool0)" in message
    )
    message = _scenario_error(
        tmp_path, f'duration = 5.0\nend_effector = "left_hand"\nrobot = "{DUAL}"\n{STATES}'
    )
    assert "unknown end-effector frame 'left_hand'; valid: " in message and "left_tool0" in message
    start = _both(UR5_START)
    locked = f"""duration = 5.0
end_effector = "left_tool0"
{robot}lock = ["right_elbow_joint"]
[start]
joints = {_joints_toml(start)}
[goal]
joints = {_joints_toml({**start, "right_elbow_joint": 45.0})}
"""
    message = _scenario_error(tmp_path, locked)
    assert "[goal] joint 'right_elbow_joint' is 45 but the joint is locked at 90 deg" in message


def test_cli_refuses_an_ambiguous_end_effector_in_one_line(tmp_path, capsys):
    path = tmp_path / "amb.toml"
    path.write_text(f'duration = 5.0\nrobot = "{DUAL}"\n{STATES}')
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "left_tool0, right_tool0" in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "p.json").exists()


# -- compose: fingers, two arms ---------------------------------------------------------------


def _gripper_arm() -> str:
    """A two-joint arm with two fingers whose limits exclude 0 (like Astrobee's perching arm)."""
    body = BASE.format(mass=5.0, i=0.1)
    body += joint("shoulder", "base", "upper", xyz=(0.1, 0, 0)) + link("upper")
    body += joint("elbow", "upper", "fore", xyz=(0.5, 0, 0)) + link("fore")
    for side, lower, upper in (("left", 0.35, 0.70), ("right", -0.70, -0.35)):
        body += joint(
            f"gripper_{side}_finger_joint",
            "fore",
            f"{side}_finger",
            axis=(0, 1, 0),
            xyz=(0.5, 0, 0),
            limits=(lower, upper),
        )
        body += link(f"{side}_finger", mass=0.2)
        body += joint(
            f"gripper_{side}_tip_joint",
            f"{side}_finger",
            f"{side}_tip",
            axis=(0, 1, 0),
            xyz=(0.1, 0, 0),
            limits=(-0.5, 0.5),
        )
        body += link(f"{side}_tip", mass=0.1)
    return robot(body, "gripper_arm")


def test_compose_locks_fingers_mid_range_and_never_picks_a_finger(tmp_path, capsys):
    arm = tmp_path / "gripper_arm.urdf"
    arm.write_text(_gripper_arm())
    out = tmp_path / "servicer.urdf"
    assert (
        main(
            [
                "compose",
                "--arm",
                str(arm),
                "--mount",
                "0.3",
                "0",
                "0",
                "--base-mass",
                "100",
                "--base-size",
                "0.6",
                "0.6",
                "0.6",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    captured = capsys.readouterr()
    printed = captured.out
    assert "locked gripper_left_finger_joint at 30.0803 deg" in printed
    assert (  # said once, as a warning: a value the user did not state
        "gripper_left_finger_joint' locked at 30.0803 deg, the middle of its range "
        "[20.05, 40.11] deg (0 is outside it)" in captured.err
    )
    assert "end effector 'fore'" in printed
    servicer = ff.load_robot(out)
    assert servicer.joint_names == ["shoulder", "elbow"] and servicer.end_effector == "fore"
    # the finger sits where the arm's own model puts it at the middle of its range
    original = pin.buildModelFromUrdf(str(arm))
    data = original.createData()
    q = pin.neutral(original)
    q[original.joints[original.getJointId("gripper_left_finger_joint")].idx_q] = 0.525
    q[original.joints[original.getJointId("gripper_right_finger_joint")].idx_q] = -0.525
    pin.framesForwardKinematics(original, data, q)
    composed = servicer.model.createData()
    pin.framesForwardKinematics(servicer.model, composed, servicer.configuration([0.0, 0.0]))
    fore = lambda m, d: d.oMf[m.getFrameId("fore")]  # noqa: E731
    for tip in ("left_tip", "right_tip"):
        expected = fore(original, data).actInv(data.oMf[original.getFrameId(tip)])
        got = fore(servicer.model, composed).actInv(composed.oMf[servicer.model.getFrameId(tip)])
        np.testing.assert_allclose(got.homogeneous, expected.homogeneous, atol=1e-12)


def test_two_arms_compose_with_prefixes_and_their_own_srdf_pairs(tmp_path, capsys):
    out = tmp_path / "two.urdf"
    args = [
        "compose",
        "--arm",
        "ur5",
        "--mount",
        "0.3",
        "0.25",
        "0",
        "--mount-rpy",
        "0",
        "90",
        "0",
        "--arm",
        "panda",
        "--mount",
        "0.3",
        "-0.25",
        "0",
        "--mount-rpy",
        "0",
        "90",
        "0",
        "--base-mass",
        "200",
        "--base-size",
        "0.6",
        "0.6",
        "0.6",
        "-o",
        str(out),
    ]
    assert main([*args, "--lock", "elbow_joint"]) == 2  # which arm's? the prefixes are named
    assert "--lock elbow_joint: name a joint with its arm's prefix (arm1_, arm2_)" in (
        capsys.readouterr().err
    )
    assert main([*args, "--lock", "arm2_panda_joint7=30"]) == 0
    printed = capsys.readouterr().out
    assert "locked arm2_panda_joint7 at 30 deg" in printed
    assert "end effectors 'arm1_tool0', 'arm2_panda_hand_tcp'" in printed
    robot = ff.load_robot(out, ["arm1_tool0", "arm2_panda_hand_tcp"])
    assert robot.n == 12 and all(n.startswith(("arm1_", "arm2_")) for n in robot.joint_names)
    from freefloat.robot.collision import CollisionModel
    from freefloat.robot.model import example_robot_data_dir

    model = CollisionModel(robot, out.with_suffix(".srdf"))
    pairs = {tuple(sorted(n.split(" / "))) for n in model.names}
    share = example_robot_data_dir() / "example-robot-data" / "robots"
    for srdf, prefix in (
        ("ur_description/srdf/ur5.srdf", "arm1_"),
        ("panda_description/srdf/panda.srdf", "arm2_"),
    ):
        disabled = {
            (prefix + e.get("link1"), prefix + e.get("link2"))
            for e in ET.parse(share / srdf).getroot().iter("disable_collisions")
        }
        for a, b in disabled:
            assert not any((a in p[0] and b in p[1]) or (b in p[0] and a in p[1]) for p in pairs)
    across = [p for p in pairs if ("arm1_" in p[0]) != ("arm1_" in p[1]) and "arm2_" in p[0] + p[1]]
    assert across, "the pairs between the two arms must be checked"


def test_two_arms_in_a_scenario_table(tmp_path, monkeypatch):
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    text = f"""duration = 10.0
[robot]
base_mass = 100.0
base_size = [0.6, 0.6, 0.6]
arms = [
  {{ arm = "ur5", mount = [0.3, 0.2, 0.0], mount_rpy_deg = [0.0, 90.0, 0.0], prefix = "left_" }},
  {{ arm = "ur5", mount = [0.3, -0.2, 0.0], mount_rpy_deg = [0.0, 90.0, 0.0], prefix = "right_" }},
]
{STATES}"""
    path = tmp_path / "arms.toml"
    path.write_text(text)
    scenario = ff.Scenario.from_toml(path)
    assert scenario.robot.end_effectors == ("left_tool0", "right_tool0")
    assert scenario.robot.joint_names == ff.load_robot(DUAL, ["left_tool0"]).joint_names
    assert scenario.safety.srdf == (tmp_path / "cache" / f"{scenario.servicer.key()}.srdf")
    scenario.write_robot()
    assert scenario.safety.srdf.read_text() == DUAL.with_suffix(".srdf").read_text()
    # bounds writes the servicer's files itself (its clearance reads the SRDF): a fresh cache
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "fresh"))
    args = ["bounds", str(path), "--budget", "2", "--max-angle", "1", "--jobs", "1"]
    assert main(args) == 0
    assert (tmp_path / "fresh" / f"{scenario.servicer.key()}.srdf").is_file()


# -- plan format ----------------------------------------------------------------------------


def test_a_format_3_plan_still_loads_verifies_and_keeps_its_format(worked_plan, tmp_path):
    data = json.loads(worked_plan.to_json())
    assert data["format"] == "freefloat.plan/5"
    data = as_older_format(data)
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    old = ff.Plan.load(path)
    assert old.format == "freefloat.plan/3" and old.robot.frames == ["ee"]
    assert np.array_equal(old.samples.path_of("ee"), old.samples.end_effector_position)
    assert "end_effector_paths" not in old.to_dict()["samples"]
    assert main(["verify", str(path)]) == 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"end_effectors": 3}, "end_effector must be a frame name (end_effectors a list of them)"),
        ({"end_effector": "left_tool0", "end_effectors": ["left_tool0"]}, "not both"),
        ({"goal": {"end_effectors": {"left_tool0": {"xyz": "up"}}}}, "xyz must be a list of 3"),
        (
            {"goal": {"end_effectors": {"left_tool0": {"xyz": [0, 0, 0], "rpy": [0, 0, 0]}}}},
            "unknown key in [goal.end_effectors.left_tool0] 'rpy'; valid: xyz, rpy_deg",
        ),
        ({"goal": {"end_effectors": {"left_tool0": [1, 2, 3]}}}, "needs xyz = [x, y, z]"),
        ({"robot": {"urdf": str(DUAL), "lock": "left_elbow_joint"}}, "lock must be a list"),
        ({"robot": {"urdf": str(DUAL), "lock": [{"joint": 3}]}}, "lock entries are joint names"),
        (
            {"robot": {"urdf": str(DUAL), "lock": [{"joint": "left_elbow_joint", "deg": 3}]}},
            "unknown key in [robot] lock entry 'deg'; valid: joint, value",
        ),
        ({"robot": {"urdf": str(DUAL), "arm": "ur5"}}, "unknown key in [robot] (with urdf) 'arm'"),
        (
            {"robot": {"arms": "ur5", "base_mass": 1.0, "base_size": [1, 1, 1]}},
            "[robot] arms must be a list of tables",
        ),
        (
            {"robot": {"arm": "ur5", "arms": [], "base_mass": 1.0, "base_size": [1, 1, 1]}},
            "[robot] needs 'arm' (one arm) or 'arms' (a list of arm tables), not both or neither",
        ),
        (
            {
                "robot": {
                    "arms": [{"arm": "ur5", "prefix": 3}],
                    "base_mass": 1.0,
                    "base_size": [1, 1, 1],
                }
            },
            "[robot] arms #1 prefix must be text, got 3",
        ),
    ],
)
def test_bad_multi_arm_keys_are_one_line_errors(change, message):
    start = {k: v for k, v in _both(UR5_START).items()}
    data = {
        "robot": str(DUAL),
        "duration": 5.0,
        "end_effector": "left_tool0",
        "start": {"joints": start},
        "goal": {"joints": start},
    }
    data.update(change)
    if "end_effectors" in change and "end_effector" not in change:
        del data["end_effector"]
    with pytest.raises(ff.FreeFloatError) as info:
        ff.Scenario.from_dict(data)
    assert message in str(info.value) and "\n" not in str(info.value)
