"""A captured payload is checked against the link before the one that holds it.

The payload is fixed to the end-effector body, so the rule that spares a parent and its child
(they touch at their joint by design) once spared the payload against the forearm: a plan
could carry a client satellite straight through it. Truth here is closed form: a sphere
against a box placed by hand from the joint angles.
"""

from __future__ import annotations

import math
import re

import pytest

from freefloat.cli import main

#: A 1 m cube spacecraft and two links along x, each with a 5 cm sphere at its middle.
URDF = """<?xml version="1.0"?>
<robot name="holder">
  <link name="spacecraft">
    <inertial><mass value="500"/><inertia ixx="80" iyy="80" izz="80" ixy="0" ixz="0" iyz="0"/>
    </inertial>
    <collision><geometry><box size="1 1 1"/></geometry></collision>
  </link>
  <joint name="a1" type="revolute"><parent link="spacecraft"/><child link="upper"/>
    <origin xyz="0.8 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/></joint>
  <link name="upper">
    <inertial><origin xyz="0.25 0 0"/><mass value="5"/>
      <inertia ixx="0.01" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.25 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="a2" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/></joint>
  <link name="lower">
    <inertial><origin xyz="0.25 0 0"/><mass value="3"/>
      <inertia ixx="0.01" iyy="0.06" izz="0.06" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.25 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
</robot>
"""

#: A 10 cm cube payload held 0.25 m behind the lower link's joint: at a2 = 0 its centre is
#: the upper link's sphere centre.
SCENARIO = """robot = "holder.urdf"
duration = 20.0
[start]
joints = {{ a1 = 0.0, a2 = 90.0 }}
base_zyx_deg = [0.0, 0.0, 0.0]
[goal]
joints = {{ a1 = 0.0, a2 = {goal} }}
base_zyx_deg = [0.0, 0.0, 0.0]
[payload]
mass = 20.0
inertia = [0.05, 0.05, 0.05, 0.0, 0.0, 0.0]
com_xyz = [-0.25, 0.0, 0.0]
box = [0.1, 0.1, 0.1]
"""


@pytest.fixture
def holder(tmp_path):
    (tmp_path / "holder.urdf").write_text(URDF)

    def scenario(goal: float) -> str:
        path = tmp_path / f"holder_{goal:g}.toml"
        path.write_text(SCENARIO.format(goal=goal))
        return str(path)

    return scenario


def _pair_distance(out: str, pair: str) -> float:
    found = re.search(rf"^\s*{re.escape(pair)}\s+(-?\d+\.\d+) m$", out, re.M)
    assert found, out
    return float(found.group(1))


def test_the_payload_is_measured_against_the_link_before_its_holder(holder, capsys) -> None:
    """At a2 = 90 deg the payload's centre is at (1.3, -0.25, 0) m and the upper sphere's at
    (1.05, 0, 0) m: the sphere's centre lies 0.2 m beyond two faces of the (still axis-aligned)
    cube, so their distance is sqrt(0.2^2 + 0.2^2) - 0.05 m. At a2 = 0 the centres coincide:
    the sphere is 0.05 + 0.05 m deep in the box."""
    scenario = holder(0.0)
    assert main(["check", scenario, "--at", "start"]) == 0
    apart = _pair_distance(capsys.readouterr().out, "upper_0 / captured_payload_0")
    assert apart == pytest.approx(math.hypot(0.2, 0.2) - 0.05, abs=1e-4)
    assert main(["check", scenario, "--at", "goal"]) == 1
    out = capsys.readouterr().out
    assert _pair_distance(out, "upper_0 / captured_payload_0") == pytest.approx(-0.1, abs=1e-4)
    assert "configuration: NOT OK" in out


def test_a_goal_that_puts_the_payload_into_the_forearm_is_refused(holder, tmp_path, capsys) -> None:
    out = tmp_path / "plan.json"
    assert main(["plan", holder(0.0), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "upper_0 / captured_payload_0" in err and "\n" not in err.strip()
    assert not out.exists()


#: The holder with a two-joint finger (joints named so) whose tip sphere sits in the payload's
#: box at a2 = 90 deg (a grasp), hung below the lower link.
FINGERED = URDF.replace(
    "</robot>",
    """  <joint name="finger_f1" type="revolute"><parent link="lower"/><child link="knuckle"/>
    <origin xyz="-0.1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="5" velocity="2"/></joint>
  <link name="knuckle"><inertial><mass value="0.2"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="finger_f2" type="revolute"><parent link="knuckle"/><child link="tip"/>
    <origin xyz="-0.1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="5" velocity="2"/></joint>
  <link name="tip"><inertial><mass value="0.1"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="-0.05 0 0"/><geometry><sphere radius="0.02"/></geometry>
    </collision></link>
</robot>""",
)


def test_a_payload_touches_what_its_holder_carries_at_any_depth(tmp_path) -> None:
    """The fingertip two joints below the holder lies inside the payload's box (by
    construction: its centre 0.25 m behind the lower link's joint, the box's centre): a grasp,
    spared; the payload stays checked against the upper link. The rule spared only the
    holder's direct children."""
    import freefloat as ff
    from freefloat.robot.geometry import checked_pairs, load_collision_geometry

    (tmp_path / "holder.urdf").write_text(FINGERED)
    text = SCENARIO.format(goal=90.0).replace(
        "joints = { a1 = 0.0, a2 = 90.0 }",
        "joints = { a1 = 0.0, a2 = 90.0, finger_f1 = 0.0, finger_f2 = 0.0 }",
    )
    text = 'end_effector = "lower"\n' + text
    (tmp_path / "f.toml").write_text(text)
    robot = ff.Scenario.from_toml(tmp_path / "f.toml").robot
    geometry = load_collision_geometry(robot)
    names = [o.name for o in geometry.geometryObjects]
    pairs = {frozenset((names[a], names[b])) for a, b in checked_pairs(robot, geometry, None)}
    assert frozenset(("upper_0", "captured_payload_0")) in pairs
    assert frozenset(("tip_0", "captured_payload_0")) not in pairs


@pytest.mark.parametrize("holder", ["upper", "spacecraft"])
def test_a_payload_held_in_mid_arm_or_by_the_spacecraft_is_checked_against_the_arm_beyond(
    tmp_path, holder
) -> None:
    """Held by the upper link, or by the spacecraft itself (``end_effector = "spacecraft"``),
    the payload was spared against every body its holder carries: the whole arm beyond, so a
    box enclosing the arm planned and verified. Only fingers (joints named so) are spared."""
    import freefloat as ff
    from freefloat.robot.geometry import checked_pairs, load_collision_geometry

    (tmp_path / "holder.urdf").write_text(FINGERED)
    text = SCENARIO.format(goal=90.0).replace(
        "joints = { a1 = 0.0, a2 = 90.0 }",
        "joints = { a1 = 0.0, a2 = 90.0, finger_f1 = 0.0, finger_f2 = 0.0 }",
    )
    (tmp_path / "f.toml").write_text(f'end_effector = "{holder}"\n' + text)
    robot = ff.Scenario.from_toml(tmp_path / "f.toml").robot
    geometry = load_collision_geometry(robot)
    names = [o.name for o in geometry.geometryObjects]
    pairs = {frozenset((names[a], names[b])) for a, b in checked_pairs(robot, geometry, None)}
    beyond = ["lower_0", "tip_0"] if holder == "upper" else ["upper_0", "lower_0", "tip_0"]
    for body in beyond:
        assert frozenset((body, "captured_payload_0")) in pairs, body


def _payload_pairs(tmp_path, names, folder):
    """The checked pairs of the fingered holder whose finger joints are named ``names``."""
    import freefloat as ff
    from freefloat.robot.geometry import checked_pairs, load_collision_geometry

    where = tmp_path / folder
    where.mkdir()
    text = FINGERED.replace('"finger_f1"', f'"{names[0]}"').replace('"finger_f2"', f'"{names[1]}"')
    (where / "holder.urdf").write_text(text)
    scenario = SCENARIO.format(goal=90.0).replace(
        "joints = { a1 = 0.0, a2 = 90.0 }",
        f"joints = {{ a1 = 0.0, a2 = 90.0, {names[0]} = 0.0, {names[1]} = 0.0 }}",
    )
    (where / "f.toml").write_text('end_effector = "lower"\n' + scenario)
    robot = ff.Scenario.from_toml(where / "f.toml").robot
    geometry = load_collision_geometry(robot)
    objects = [o.name for o in geometry.geometryObjects]
    return {frozenset((objects[a], objects[b])) for a, b in checked_pairs(robot, geometry, None)}


@pytest.mark.parametrize(
    ("names", "spared"),
    [
        (("finger_f1", "finger_f2"), True),
        (("hand_index_flex_1_joint", "hand_index_flex_2_joint"), True),  # Tiago's hand
        (("right_outer_knuckle_joint", "right_inner_finger_joint"), True),  # Robotiq's
        (("a3", "a4"), False),  # an arm's joints: the payload is checked against them
    ],
)
def test_a_grasp_is_spared_by_its_hands_joint_names(tmp_path, names, spared) -> None:
    pairs = _payload_pairs(tmp_path, names, "one")
    assert (frozenset(("tip_0", "captured_payload_0")) not in pairs) == spared


def test_the_kept_pairs_of_one_shape_follow_its_joint_names(tmp_path) -> None:
    """The pairs were kept per shape, not per joint names: the second of two robots of one
    shape got the first one's answer (a pair wrongly spared or checked by load order)."""
    fingers = _payload_pairs(tmp_path, ("finger_f1", "finger_f2"), "a")
    arm = _payload_pairs(tmp_path, ("a3", "a4"), "b")
    again = _payload_pairs(tmp_path, ("finger_f1", "finger_f2"), "c")
    tip = frozenset(("tip_0", "captured_payload_0"))
    assert tip not in fingers and tip in arm and tip not in again
