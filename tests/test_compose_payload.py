"""``freefloat compose --payload-*``: the payload's mass is in the URDF, the end effector stays."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.robot.arm_tips import payload_parent
from freefloat.robot.compose import ServicerSpec, arm_urdf, compose_servicer_text
from freefloat.robot.payload import PAYLOAD_LINK, Payload

BASE = ["--base-mass", "500", "--base-size", "1", "1", "1", "--mount", "0.5", "0", "0"]

#: A two-link arm whose tip link has no tool-like name (so the payload could win the default).
ARM = """<?xml version="1.0"?>
<robot name="plain_arm">
  <link name="root"><inertial><mass value="2.0"/><inertia ixx="0.01" iyy="0.01" izz="0.01"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a1" type="revolute"><parent link="root"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="upper"><inertial><origin xyz="0.25 0 0"/><mass value="5.0"/>
    <inertia ixx="0.01" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a2" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="lower"><inertial><origin xyz="0.25 0 0"/><mass value="3.0"/>
    <inertia ixx="0.01" iyy="0.06" izz="0.06" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""


def _urdf_mass(path) -> float:
    """Independent: the sum of every <mass> in a URDF file."""
    root = ET.parse(path).getroot()
    return sum(float(m.get("value")) for m in root.iter("mass"))


@pytest.fixture
def plain_arm(tmp_path):
    path = tmp_path / "plain_arm.urdf"
    path.write_text(ARM)
    return str(path)


@pytest.mark.parametrize("arm", ["panda", "plain"])
def test_payload_mass_is_added_and_end_effector_kept(arm, plain_arm, tmp_path, capsys):
    arm = plain_arm if arm == "plain" else arm
    bare, held = tmp_path / "bare.urdf", tmp_path / "held.urdf"
    assert main(["compose", "--arm", arm, *BASE, "-o", str(bare)]) == 0
    payload = ["--payload-mass", "75", "--payload-box", "0.4", "0.3", "0.2"]
    assert main(["compose", "--arm", arm, *BASE, *payload, "-o", str(held)]) == 0
    out = capsys.readouterr().out
    arm_mass = _urdf_mass(arm_urdf(arm))
    without = ff.load_robot(bare)
    text = held.read_text()
    assert payload_parent(text) == without.end_effector
    with_payload = ff.load_robot(held, payload_parent(text))
    assert without.total_mass == pytest.approx(500.0 + arm_mass, rel=1e-12)
    assert with_payload.total_mass == pytest.approx(500.0 + arm_mass + 75.0, rel=1e-12)
    assert with_payload.end_effector == without.end_effector != PAYLOAD_LINK
    assert f"end effector {without.end_effector!r}" in out.splitlines()[-2]
    assert "captured payload 75 kg" in out
    link = ET.fromstring(text).find(f"link[@name='{PAYLOAD_LINK}']")
    assert link is not None and link.find("visual/geometry/box").get("size") == "0.4 0.3 0.2"
    # the uniform box's inertia (default without --payload-inertia)
    inertia = link.find("inertial/inertia")
    assert float(inertia.get("ixx")) == pytest.approx(75.0 / 12.0 * (0.3**2 + 0.2**2))


def test_payload_with_com_and_inertia(tmp_path):
    out = tmp_path / "held.urdf"
    args = ["--payload-mass", "20", "--payload-com", "0", "0", "0.3"]
    args += ["--payload-inertia", "1", "2", "2.5", "0.1", "0", "0"]
    assert main(["compose", "--arm", "ur5", *BASE, *args, "-o", str(out)]) == 0
    link = ET.fromstring(out.read_text()).find(f"link[@name='{PAYLOAD_LINK}']")
    assert link.find("inertial/origin").get("xyz") == "0.0 0.0 0.3"
    assert float(link.find("inertial/inertia").get("ixy")) == 0.1
    assert link.find("visual") is None  # no box: nothing drawn


@pytest.mark.parametrize(
    "args, message",
    [
        (["--payload-mass", "-1", "--payload-box", "1", "1", "1"], "--payload-mass must be"),
        (
            ["--payload-mass", "10", "--payload-inertia", "1", "1", "5", "0", "0", "0"],
            "triangle inequality",
        ),
        (["--payload-mass", "10"], "--payload-mass needs --payload-inertia"),
        (["--payload-box", "1", "1", "1"], "need --payload-mass"),
    ],
)
def test_bad_payloads_are_refused(args, message, tmp_path, capsys):
    out = tmp_path / "x.urdf"
    assert main(["compose", "--arm", "ur5", *BASE, *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("freefloat: error: ") and "\n" not in err and message in err
    assert not out.exists()


def test_payload_is_in_the_cache_key():
    spec = ServicerSpec(arm="ur5", base_mass=500.0, base_size=(1.0, 1.0, 1.0))
    held = ServicerSpec(
        arm="ur5",
        base_mass=500.0,
        base_size=(1.0, 1.0, 1.0),
        payload=Payload(10.0, inertia=(1.0, 1.0, 1.0, 0.0, 0.0, 0.0)),
    )
    heavier = ServicerSpec(
        arm="ur5",
        base_mass=500.0,
        base_size=(1.0, 1.0, 1.0),
        payload=Payload(11.0, inertia=(1.0, 1.0, 1.0, 0.0, 0.0, 0.0)),
    )
    assert len({spec.key(), held.key(), heavier.key()}) == 3
    assert PAYLOAD_LINK in compose_servicer_text(held)
    assert PAYLOAD_LINK not in compose_servicer_text(spec)


def test_an_arm_without_collision_geometry_is_composed_with_a_warning(plain_arm, tmp_path, capsys):
    # the plain arm has no <collision> element: nothing can keep it out of the box
    out = tmp_path / "bare.urdf"
    assert main(["compose", "--arm", plain_arm, *BASE, "-o", str(out)]) == 0
    assert f"no link of the arm {plain_arm!r} has collision geometry" in capsys.readouterr().err
    assert ET.parse(out).getroot().find("link/collision") is not None  # the box's own
    # an arm with collision meshes: no such warning
    assert main(["compose", "--arm", "panda", *BASE, "-o", str(tmp_path / "p.urdf")]) == 0
    assert "collision geometry" not in capsys.readouterr().err
    two = ["--arm", "panda", "--mount", "0.5", "0", "0", "--arm", plain_arm, "--mount", "-0.5"]
    two += ["0", "0", "--base-mass", "500", "--base-size", "1", "1", "1"]
    assert main(["compose", *two, "-o", str(tmp_path / "d.urdf")]) == 0
    err = capsys.readouterr().err  # two arms, one without: that one is named
    assert err.count("has collision geometry") == 1 and repr(plain_arm) in err


def test_a_payload_table_for_a_servicer_already_holding_one_says_what_to_do(
    plain_arm, tmp_path, capsys
):
    held = tmp_path / "held.urdf"
    payload = ["--payload-mass", "75", "--payload-box", "0.4", "0.3", "0.2"]
    assert main(["compose", "--arm", plain_arm, *BASE, *payload, "-o", str(held)]) == 0
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'robot = "{held}"\nend_effector = "lower"\nduration = 10.0\n'
        "[start]\njoints = { a1 = 0.0, a2 = 0.0 }\n[goal]\njoints = { a1 = 10.0, a2 = 5.0 }\n"
        "[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\n[safety]\ncheck = false\n"
    )
    capsys.readouterr()
    assert main(["check", str(scenario)]) == 2
    err = capsys.readouterr().err
    assert (
        err.count("\n") == 1
        and (
            f"already has a link {PAYLOAD_LINK!r} (a payload composed into it): drop the "
            "scenario's [payload] table, or compose the servicer without --payload-*"
        )
        in err
    ), err
