"""Hostile URDFs (issue 26): what is checked is what Pinocchio loads, and the model it built
is checked too. Each refusal is one line naming the problem."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.built_model import check_built_model
from freefloat.robot.urdf_checks import check_urdf_xml

from conftest import ROOT

PLANAR = ROOT / "robots" / "planar_2dof.urdf"

#: A document type whose unused entity hides a second robot from Python's parser: TinyXML2
#: ends the declaration at the first '>' and reads the <robot> inside the entity's text.
HIDDEN_ROBOT = '<!DOCTYPE robot [<!ENTITY e "x> {robot} <!--">]>\n<!-- -->\n'


#: A massless link with a negative inertia, fixed to link2 (2.5 kg m^2 about z).
NEGATIVE_LINK = (
    '<link name="bad"><inertial><mass value="0"/>'
    '<inertia ixx="0" iyy="0" izz="-100" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    '<joint name="fix" type="fixed"><parent link="link2"/><child link="bad"/></joint>'
)


def _variant(tmp_path, old, new, name="r.urdf"):
    text = PLANAR.read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def _evil_robot() -> str:
    """The planar robot with link1 at 41 kg instead of 40 (single quotes, for the entity)."""
    body = PLANAR.read_text().split("-->", 1)[1]
    return body.replace('<mass value="40.0"/>', '<mass value="41.0"/>').replace('"', "'")


def test_the_hidden_robot_is_another_robot_for_pinocchio():
    """The attack is real: given the file's own text, Pinocchio builds the 41 kg robot."""
    text = HIDDEN_ROBOT.format(robot=_evil_robot()) + PLANAR.read_text().split("-->", 1)[1]
    with ff.robot.parser_messages.parser_messages():
        model = pin.buildModelFromXML(text)
    assert model.inertias[1].mass == 41.0  # Python's parser reads 40 kg in the same text


def test_a_document_type_declaration_is_refused_by_name(tmp_path):
    text = HIDDEN_ROBOT.format(robot=_evil_robot()) + PLANAR.read_text().split("-->", 1)[1]
    path = tmp_path / "evil.urdf"
    path.write_text(text)
    with pytest.raises(ff.ModelError, match="document type declaration") as info:
        ff.load_robot(path)
    assert "\n" not in str(info.value)


def test_entities_alone_are_refused(tmp_path):
    path = _variant(
        tmp_path,
        '<robot name="planar_2dof">',
        '<!DOCTYPE robot [<!ENTITY m "40.0">]><robot name="planar_2dof">',
    )
    with pytest.raises(ff.ModelError, match="document type declaration"):
        ff.load_robot(path)


def test_pinocchio_is_given_the_checked_tree(tmp_path):
    """A link in another XML namespace is no link for either parser."""
    path = _variant(
        tmp_path,
        "</robot>",
        '<link xmlns="urn:x" name="ghost"><inertial><mass value="5"/>'
        '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>',
    )
    robot = ff.load_robot(path)
    assert robot.total_mass == pytest.approx(470.0)  # 400 + 40 + 30, no ghost
    assert "ghost" not in robot.link_names


@pytest.mark.parametrize("raw", ["4_0", "40 ", "\uff14\uff10", "0x28", "40\n"])
def test_numbers_urdfdom_reads_otherwise_are_refused(tmp_path, raw):
    """Python's float() takes these; urdfdom refuses them and builds a 0 kg link instead."""
    path = _variant(tmp_path, '<mass value="40.0"/>', f'<mass value="{raw}"/>')
    with pytest.raises(ff.ModelError, match=r"link 'link1' mass value=.* is not a number"):
        ff.load_robot(path)


def test_an_inertia_attribute_urdfdom_needs_is_required(tmp_path):
    """Without ixy urdfdom drops the <inertial>: a massless base where the file says 400 kg."""
    path = _variant(tmp_path, 'ixy="0"', "")
    with pytest.raises(ff.ModelError, match="link 'base' inertia has no 'ixy' attribute"):
        ff.load_robot(path)


def test_a_massless_link_with_negative_inertia_is_refused(tmp_path):
    """Fixed to link2 it would make the merged body's inertia indefinite (-97.5 kg m^2)."""
    path = _variant(tmp_path, "</robot>", NEGATIVE_LINK + "</robot>")
    with pytest.raises(ff.ModelError, match="link 'bad' has no mass but a negative inertia"):
        ff.load_robot(path)


def test_the_built_model_is_checked_against_the_checked_file():
    """The backstop: a model other than the checked file's is refused, body by body."""
    text = PLANAR.read_text()
    checked = check_urdf_xml(text)
    heavier = pin.buildModelFromXML(
        text.replace('<mass value="40.0"/>', '<mass value="41.0"/>'), pin.JointModelFreeFlyer()
    )
    with pytest.raises(ff.ModelError, match="471 kg where the checked file says 470 kg"):
        check_built_model(heavier, checked)
    merged = pin.buildModelFromXML(
        text.replace("</robot>", NEGATIVE_LINK + "</robot>"), pin.JointModelFreeFlyer()
    )
    assert np.linalg.eigvalsh(merged.inertias[3].inertia).min() == pytest.approx(-97.5)
    with pytest.raises(ff.ModelError, match=r"body moved by joint 'q2'.*unphysical.*-97\.5"):
        check_built_model(merged, checked)
    renamed = pin.buildModelFromXML(text.replace('"q2"', '"q3"'), pin.JointModelFreeFlyer())
    with pytest.raises(ff.ModelError, match=r"built joints \['q1', 'q3'\]"):
        check_built_model(renamed, checked)


@pytest.mark.parametrize("value", ["1e308", "1e13", "-1e13"])
def test_huge_inertias_are_one_line_naming_the_value(tmp_path, value):
    path = _variant(tmp_path, 'izz="3.33"', f'izz="{value}"')
    with pytest.raises(ff.ModelError, match=f"link 'link1' inertia izz={value!r} is beyond"):
        ff.load_robot(path)


def test_huge_origins_are_refused(tmp_path):
    path = _variant(tmp_path, '<origin xyz="1.0 0 0"/>', '<origin xyz="1e300 0 0"/>')
    with pytest.raises(ff.ModelError, match="joint 'q2' origin xyz='1e300 0 0' is not three"):
        ff.load_robot(path)


@pytest.mark.parametrize(
    "filename",
    ["package://../../../../etc/passwd", "package://pkg/../../x.stl", "package:///etc/x.stl"],
)
def test_package_paths_that_leave_their_package_are_refused(tmp_path, filename):
    path = _variant(
        tmp_path,
        '<geometry><box size="1.0 1.0 1.0"/></geometry>',
        f'<geometry><mesh filename="{filename}"/></geometry>',
    )
    with pytest.raises(ff.ModelError, match="leaves its package"):
        ff.load_robot(path)


def test_a_package_path_inside_its_package_is_fine(tmp_path):
    path = _variant(
        tmp_path,
        '<geometry><box size="1.0 1.0 1.0"/></geometry>',
        '<geometry><mesh filename="package://pkg/meshes/../meshes/x.stl"/></geometry>',
    )
    assert ff.load_robot(path).n == 2


@pytest.mark.parametrize(
    ("old", "new", "needle"),
    [
        ('<joint name="q2"', '<joint name=""', "a <joint> has no name"),
        ('<joint name="q2"', '<joint name="q1"', "duplicate joint name 'q1'"),
        ('<link name="link2">', '<link name=" ">', "a <link> has no name"),
    ],
)
def test_empty_and_duplicate_names_are_refused(tmp_path, old, new, needle):
    path = _variant(tmp_path, old, new)
    with pytest.raises((ff.ModelError, ff.UnknownNameError), match=needle):
        ff.load_robot(path)


def test_a_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.urdf"
    path.write_bytes(b"\xef\xbb\xbf" + PLANAR.read_bytes())
    assert ff.load_robot(path).n == 2


# -- plans that name their robot badly ----------------------------------------------------


def _plan_doc(worked_plan):
    import json

    return json.loads(worked_plan.to_json())


def _load(tmp_path, text):
    from freefloat.plans.schema import load_plan_file

    path = tmp_path / "p.json"
    path.write_text(text)
    return load_plan_file(path)


def test_duplicate_json_keys_in_a_plan_are_refused_by_name(tmp_path, worked_plan):
    text = worked_plan.to_json().replace('"duration": ', '"duration": 1.0, "duration": ', 1)
    with pytest.raises(ff.PlanFileError, match="key 'duration' appears twice in one object"):
        _load(tmp_path, text)


def test_an_empty_joint_name_in_a_plan_is_refused_by_name(tmp_path, worked_plan):
    import json

    doc = _plan_doc(worked_plan)
    doc["robot"]["joints"][1] = ""
    with pytest.raises(ff.PlanFileError, match=r"robot\.joints\[1\]: '' is empty"):
        _load(tmp_path, json.dumps(doc))
    doc["format"] = "freefloat.plan/1"  # not schema-checked: the limits name it
    with pytest.raises(ff.PlanFileError, match=r"robot\.joints\[1\]' is an empty name"):
        _load(tmp_path, json.dumps(doc))


def test_a_plan_with_a_byte_order_mark_loads(tmp_path, worked_plan):
    plan = _load(tmp_path, "\ufeff" + worked_plan.to_json())
    assert plan.duration == worked_plan.duration
