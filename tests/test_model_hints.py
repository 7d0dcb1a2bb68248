"""Messages for plausible URDF and scenario mistakes name the cause and the way out: a
floating root joint, a missing collision mesh, a fixed joint named as a movable one."""

from __future__ import annotations

import pytest

import freefloat as ff
from freefloat.robot.collision import collision_model

import urdfs


def test_a_floating_joint_under_a_world_link_says_the_root_already_floats(tmp_path) -> None:
    body = '\n  <link name="world"/>' + urdfs.joint("world_to_base", "world", "base", "floating")
    text = urdfs.spatial_arm().replace("</robot>", body + "\n</robot>")
    path = tmp_path / "floating.urdf"
    path.write_text(text)
    with pytest.raises(ff.ModelError) as caught:
        ff.load_robot(path)
    assert str(caught.value).endswith(
        "joint 'world_to_base' has type 'floating'; supported: revolute, continuous, prismatic, "
        "fixed; the URDF's root link is the spacecraft and already floats: remove this joint "
        "and the link above it"
    )


def test_a_missing_collision_mesh_says_where_and_how_to_plan_without(tmp_path) -> None:
    mesh = '<collision><geometry><mesh filename="meshes/absent.stl"/></geometry></collision>'
    text = urdfs.spatial_arm().replace('<link name="l2">', f'<link name="l2">{mesh}', 1)
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    with pytest.raises(ff.ModelError) as caught:
        collision_model(ff.load_robot(path))
    message = str(caught.value)
    assert "cannot read its collision geometry (" in message and "absent.stl" in message
    assert message.endswith(
        "put the mesh files where the URDF names them, or plan without clearance: "
        "[safety] check = false"
    )


def test_a_fixed_joint_named_as_a_movable_one_is_said_to_be_fixed(tmp_path) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    robot = ff.load_robot(path)
    with pytest.raises(ff.UnknownNameError) as caught:
        robot.vector({"j1": 0.0, "j2": 0.0, "j3": 0.0, "tip_joint": 0.0})
    assert str(caught.value) == (
        "unknown joint 'tip_joint' (a fixed joint in the URDF: it does not move); valid: j1, j2, j3"
    )
    with pytest.raises(ff.UnknownNameError) as caught:
        robot.joint("j9")
    assert str(caught.value) == "unknown joint 'j9'; valid: j1, j2, j3"


def test_the_command_line_says_each_hint_in_one_line_and_exits_2(tmp_path, capsys) -> None:
    """`freefloat check` on a scenario naming a fixed joint, and on a URDF with a floating
    root joint: one line each, exit 2, no traceback."""
    from freefloat.cli import main

    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    scenario = tmp_path / "s.toml"
    joints = "{ j1 = 10.0, j2 = 20.0, j3 = 30.0, tip_joint = 0.0 }"
    scenario.write_text(
        f'robot = "{path}"\nduration = 5.0\n[safety]\ncheck = false\n'
        f"[start]\njoints = {joints}\n[goal]\njoints = {joints}\n"
    )
    assert main(["check", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "(a fixed joint in the URDF: it does not move)" in err
    body = '\n  <link name="world"/>' + urdfs.joint("world_to_base", "world", "base", "floating")
    path.write_text(urdfs.spatial_arm().replace("</robot>", body + "\n</robot>"))
    scenario.write_text(scenario.read_text().replace(", tip_joint = 0.0", ""))
    assert main(["check", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("freefloat: error: ")
    assert "the URDF's root link is the spacecraft and already floats" in err
