"""A URDF parsed once per text: every load gets a robot of its own, equal to a fresh parse."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.parsed_urdf import parsed_urdf

from conftest import ROOT

PLANAR = ROOT / "robots" / "planar_2dof.urdf"


def _same_model(a: pin.Model, b: pin.Model) -> None:
    """The two models have the same joints, placements, inertias and limits, to the bit."""
    assert list(a.names) == list(b.names)
    assert [f.name for f in a.frames] == [f.name for f in b.frames]
    for x, y in zip(a.inertias, b.inertias, strict=True):
        assert np.array_equal(x.toDynamicParameters(), y.toDynamicParameters())
    for x, y in zip(a.jointPlacements, b.jointPlacements, strict=True):
        assert np.array_equal(x.homogeneous, y.homogeneous)
    for field in ("lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit"):
        assert np.array_equal(getattr(a, field), getattr(b, field))
    assert np.array_equal(a.gravity.vector, b.gravity.vector)


def test_each_load_has_its_own_model_equal_to_pinocchios_parse():
    first, second = ff.load_robot(PLANAR), ff.load_robot(PLANAR)
    assert first.model is not second.model
    direct = pin.buildModelFromXML(PLANAR.read_text(), pin.JointModelFreeFlyer())
    direct.gravity = pin.Motion.Zero()
    for robot in (first, second):
        _same_model(robot.model, direct)
        assert robot.joints == first.joints
        assert robot.end_effector == "ee"


def test_a_change_to_one_robots_model_reaches_no_other_load():
    first = ff.load_robot(PLANAR)
    before = ff.load_robot(PLANAR).model.inertias[2].mass
    first.model.inertias[2] = pin.Inertia.Random()
    assert ff.load_robot(PLANAR).model.inertias[2].mass == before
    assert parsed_urdf(PLANAR.read_text(), PLANAR).model.inertias[2].mass == before


def test_a_changed_file_is_parsed_again(tmp_path):
    path = tmp_path / "r.urdf"
    text = PLANAR.read_text()
    path.write_text(text)
    assert ff.load_robot(path).joints[0].kind == "continuous"
    path.write_text(
        text.replace(
            '<joint name="q1" type="continuous">',
            '<joint name="q1" type="revolute"><limit lower="-1" upper="2" velocity="3" '
            'effort="4"/>',
        )
    )
    joint = ff.load_robot(path).joints[0]
    assert (joint.kind, joint.lower, joint.upper, joint.velocity_limit) == ("revolute", -1, 2, 3)


def test_a_refused_text_is_refused_at_every_load(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text(PLANAR.read_text().replace('<mass value="40.0"/>', '<mass value="-40.0"/>'))
    for _ in range(2):
        with pytest.raises(ff.ModelError, match=str(path.name)):
            ff.load_robot(path)


def test_end_effectors_are_asked_of_every_load():
    assert ff.load_robot(PLANAR, "link1").end_effector == "link1"
    assert ff.load_robot(PLANAR).end_effector == "ee"
    with pytest.raises(ff.UnknownNameError):
        ff.load_robot(PLANAR, "nowhere")


#: A second two-joint chain on the base: two longest chains, no default end effector.
SECOND_ARM = """
  <joint name="q3" type="continuous"><parent link="base"/><child link="link3"/>
    <origin xyz="-0.5 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="link3"><inertial><origin xyz="-0.5 0 0"/><mass value="10.0"/>
    <inertia ixx="0.01" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="q4" type="continuous"><parent link="link3"/><child link="link4"/>
    <origin xyz="-1.0 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="link4"><inertial><origin xyz="-0.5 0 0"/><mass value="10.0"/>
    <inertia ixx="0.01" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""


def test_an_ambiguous_default_is_refused_at_every_load_and_a_named_one_taken(tmp_path):
    path = tmp_path / "two_arms.urdf"
    path.write_text(PLANAR.read_text().replace("</robot>", SECOND_ARM))
    for _ in range(2):
        with pytest.raises(ff.AmbiguousEndEffectorError):
            ff.load_robot(path)
    assert ff.load_robot(path, ["ee", "link4"]).end_effectors == ("ee", "link4")


def test_the_parsers_messages_are_logged_at_every_load(caplog, monkeypatch):
    """A kept parse logs what the parser printed again at each load, as the first parse did."""
    import dataclasses
    import logging

    from freefloat.robot import parsed_urdf as kept

    text = PLANAR.read_text()
    first = parsed_urdf(text, PLANAR)
    monkeypatch.setitem(
        kept._PARSED, text, dataclasses.replace(first, messages=("Warning: a line",))
    )
    with caplog.at_level(logging.DEBUG, logger="freefloat"):
        for _ in range(2):
            caplog.clear()
            ff.load_robot(PLANAR)
            assert "URDF parser: Warning: a line" in caplog.text
