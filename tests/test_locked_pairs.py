"""A locked joint does not make the next link a child of the spacecraft: its pairs are those
of the arm as built (the audit's wrong accept: with the UR5's first joint locked, its upper
arm passed through the hull unchecked)."""

from __future__ import annotations

import importlib.metadata

import coal
import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.robot.collision import CollisionModel

from conftest import ROOT

#: The upper arm inside the 0.6 m hull box at both ends (shoulder_pan held at 0).
START = {"shoulder_lift_joint": 160.0, "elbow_joint": -60.0, "wrist_1_joint": -90.0}
GOAL = {"shoulder_lift_joint": 155.0, "elbow_joint": -55.0, "wrist_1_joint": -60.0}
WRISTS = {"start": (-90.0, 0.0), "goal": (0.0, 90.0)}


def _joints(which: str) -> str:
    values = dict(START if which == "start" else GOAL)
    values["wrist_2_joint"], values["wrist_3_joint"] = WRISTS[which]
    return ", ".join(f"{k} = {v}" for k, v in values.items())


@pytest.fixture(scope="module")
def locked_urdf(tmp_path_factory) -> str:
    out = tmp_path_factory.mktemp("locked") / "ur5_lockpan.urdf"
    argv = ["compose", "--arm", "ur5", "--base-mass", "100", "--base-size", "0.6", "0.6", "0.6"]
    argv += ["--mount", "0.3", "0", "0", "--mount-rpy", "0", "90", "0"]
    argv += ["--lock", "shoulder_pan_joint=0", "-o", str(out), "-q"]
    assert main(argv) == 0
    return str(out)


def _hull_and_upper_arm_collide(urdf: str, joints: dict[str, float]) -> bool:
    """Coal on the URDF's own shapes (the upper arm's mesh as triangles), no freefloat code."""
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    share = importlib.metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share")
    geometry = pin.buildGeomFromUrdf(
        model, urdf, pin.GeometryType.COLLISION, package_dirs=[str(share)]
    )
    data, gdata = model.createData(), pin.GeometryData(geometry)
    q = pin.neutral(model)
    for name, deg in joints.items():
        q[model.joints[model.getJointId(name)].idx_q] = np.radians(deg)
    pin.updateGeometryPlacements(model, data, geometry, gdata, q)
    hull = geometry.getGeometryId("spacecraft_0")
    arm = geometry.getGeometryId("upper_arm_link_0")
    result = coal.CollisionResult()
    coal.collide(
        geometry.geometryObjects[hull].geometry,
        gdata.oMg[hull],
        geometry.geometryObjects[arm].geometry,
        gdata.oMg[arm],
        coal.CollisionRequest(),
        result,
    )
    return result.isCollision()


def test_the_hull_is_checked_against_the_link_after_a_locked_joint(locked_urdf, tmp_path, capsys):
    goal = {**GOAL, "wrist_2_joint": 0.0, "wrist_3_joint": 90.0}
    assert _hull_and_upper_arm_collide(locked_urdf, goal)  # the truth: they intersect
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'robot = "{locked_urdf}"\nduration = 20.0\n[start]\njoints = {{ {_joints("start")} }}\n'
        f"[goal]\njoints = {{ {_joints('goal')} }}\nbase_zyx_deg = [-1.0, 0.0, 2.0]\n"
    )
    assert main(["check", str(scenario), "--at", "goal"]) == 1
    out = capsys.readouterr().out
    assert "spacecraft_0 / upper_arm_link_0" in out and "configuration: NOT OK" in out
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    assert "upper_arm_link_0" in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()


def test_a_scenario_lock_keeps_the_pairs_of_the_arm_as_built(tmp_path):
    """[robot] lock on the shipped UR5 servicer: every pair of the unlocked robot is checked
    (by Pinocchio's parent-and-child rule on the unlocked model, worked out here) but those
    the lock makes one rigid body."""
    urdf = ROOT / "robots" / "ur5_servicer.urdf"
    free = ff.load_robot(urdf)
    geometry = CollisionModel(free).geometry
    parents = [int(j) for j in free.model.parents]
    names = [o.name for o in geometry.geometryObjects]
    joints = [int(o.parentJoint) for o in geometry.geometryObjects]
    expected = {
        (names[a], names[b])
        for a in range(len(names))
        for b in range(a + 1, len(names))
        if joints[a] != joints[b]
        and parents[joints[a]] != joints[b]
        and parents[joints[b]] != joints[a]
    }
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'duration = 20.0\n[robot]\nurdf = "{urdf}"\nlock = ["shoulder_pan_joint"]\n'
        f"[start]\njoints = {{ {_joints('start')} }}\n[goal]\njoints = {{ {_joints('goal')} }}\n"
    )
    locked = ff.Scenario.from_toml(scenario).robot
    model = CollisionModel(locked)
    objects = model.geometry.geometryObjects
    found = {(objects[a].name, objects[b].name) for a, b in model.pairs}
    rigid = {("spacecraft_0", "shoulder_link_0"), ("base_link_0", "shoulder_link_0")}
    assert found == expected - rigid
    assert ("spacecraft_0", "upper_arm_link_0") in found


def test_two_locks_in_a_row_keep_the_hull_against_the_link_beyond(tmp_path, capsys):
    """The review's case: shoulder_pan and shoulder_lift both locked put the spacecraft and
    the upper arm on one rigid body, skipped as "one body" until now; their pair is kept
    (its distance is constant: the start must keep the margin)."""
    out = tmp_path / "two.urdf"
    argv = ["compose", "--arm", "ur5", "--base-mass", "100", "--base-size", "0.6", "0.6", "0.6"]
    argv += ["--mount", "0.3", "0", "0", "--mount-rpy", "0", "90", "0"]
    argv += ["--lock", "shoulder_pan_joint=0", "shoulder_lift_joint=160", "-o", str(out), "-q"]
    assert main(argv) == 0
    joints = {k: v for k, v in GOAL.items() if k != "shoulder_lift_joint"}
    assert _hull_and_upper_arm_collide(str(out), {**joints, "wrist_2_joint": 0.0})
    scenario = tmp_path / "s.toml"
    rest = "elbow_joint = -55.0, wrist_1_joint = -60.0, wrist_2_joint = 0.0, wrist_3_joint = 90.0"
    scenario.write_text(
        f'robot = "{out}"\nduration = 20.0\n[start]\njoints = {{ {rest} }}\n'
        f"[goal]\njoints = {{ {rest} }}\n"
    )
    capsys.readouterr()
    assert main(["check", str(scenario), "--at", "start"]) == 1
    printed = capsys.readouterr().out
    assert "spacecraft_0 / upper_arm_link_0" in printed and "NOT OK" in printed


def test_composing_an_arm_freefloat_locked_keeps_its_marks(tmp_path):
    """An arm URDF locked by freefloat (lock_joints, as [robot] lock writes it) composed: yourdfpy
    drops unknown attributes, so the marks are carried over from the arm's own XML (else the
    old pair rule came back)."""
    import xml.etree.ElementTree as ET

    from freefloat.robot.arms import arm_urdf
    from freefloat.robot.lock import lock_joints

    source = arm_urdf("ur5")
    arm = tmp_path / "ur5_locked.urdf"
    arm.write_text(lock_joints(source.read_text(), {"shoulder_pan_joint": 0.0}, source.parent))
    out = tmp_path / "again.urdf"
    argv = ["compose", "--arm", str(arm), "--base-mass", "200", "--base-size", "1", "1", "1"]
    assert main([*argv, "--mount", "0.5", "0", "0", "--prefix", "a_", "-o", str(out), "-q"]) == 0
    marks = {
        j.get("name"): j.get("freefloat_locked")
        for j in ET.parse(out).getroot().iter("joint")
        if j.get("freefloat_locked") is not None
    }
    assert marks == {"a_shoulder_pan_joint": "0.0"}


def test_a_lock_mark_that_is_no_number_is_refused_in_one_line(tmp_path, capsys):
    from freefloat.robot.arms import arm_urdf
    from freefloat.robot.lock import lock_joints

    source = arm_urdf("ur5")
    text = lock_joints(source.read_text(), {"shoulder_pan_joint": 0.0}, source.parent)
    arm = tmp_path / "bad_mark.urdf"
    arm.write_text(text.replace('freefloat_locked="0.0"', 'freefloat_locked="zero"'))
    out = tmp_path / "s.urdf"
    argv = ["compose", "--arm", str(arm), "--base-mass", "200", "--base-size", "1", "1", "1"]
    assert main([*argv, "--mount", "0.5", "0", "0", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and not out.exists()
    assert "joint 'shoulder_pan_joint' has freefloat_locked='zero', not a number (rad or m)" in err
