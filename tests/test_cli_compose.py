"""``freefloat compose``: every numeric option is held to its documented limit (docs/limits.md)."""

from __future__ import annotations

import pytest

from freefloat.cli import main

#: A valid two-arm command, each option's numbers in one place (replaced one at a time below).
VALID = {
    "--base-mass": ["100"],
    "--base-size": ["1", "1", "1"],
    "--base-inertia": ["10", "10", "10"],
    "--mount": ["0.5", "0", "0", "-0.5", "0", "0"],
    "--mount-rpy": ["0", "90", "0", "0", "-90", "0"],
    "--payload-mass": ["5"],
    "--payload-com": ["0", "0", "0.1"],
    "--payload-inertia": ["1", "1", "1", "0", "0", "0"],
    "--payload-box": ["0.2", "0.2", "0.2"],
}
#: docs/limits.md: angles at most 3600 deg, lengths 1000 m, any other number 1e9.
BEYOND = {
    "--base-mass": ("2e9", "kg", "1e+09"),
    "--base-size": ("1001", "m", "1000"),
    "--base-inertia": ("2e9", "kg m^2", "1e+09"),
    "--mount": ("1001", "m", "1000"),
    "--mount-rpy": ("3601", "deg", "3600"),
    "--payload-mass": ("2e9", "kg", "1e+09"),
    "--payload-com": ("1001", "m", "1000"),
    "--payload-inertia": ("2e9", "kg m^2", "1e+09"),
    "--payload-box": ("1001", "m", "1000"),
}


def _argv(options, output):
    argv = ["compose", "--arm", "ur5", "--arm", "panda"]
    for option, numbers in options.items():
        per_arm = 2 if option in ("--mount", "--mount-rpy") else 1
        size = len(numbers) // per_arm
        for k in range(per_arm):
            argv += [option, *numbers[k * size : (k + 1) * size]]
    return [*argv, "-o", str(output)]


@pytest.mark.parametrize("option", list(BEYOND))
def test_each_number_beyond_its_limit_is_refused_naming_option_and_unit(tmp_path, capsys, option):
    value, unit, high = BEYOND[option]
    numbers = list(VALID[option])
    numbers[-1] = value  # the last number (of the second arm for per-arm options)
    output = tmp_path / "s.urdf"
    assert main(_argv({**VALID, option: numbers}, output)) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and not output.exists()
    shown = f"{float(value):g}"
    assert err.startswith(f"freefloat: error: {option} = {shown} {unit} is ")
    assert err.endswith(f"is outside the supported range [-{high}, {high}] {unit}\n")


def test_a_servicer_freefloat_refuses_is_never_written(tmp_path, capsys):
    """A 2e7 kg box passes compose's own limit (1e9 kg) but not the URDF reader's (1e7 per
    mass): the command refuses it in one line and writes nothing, and an earlier servicer of
    that name stays as it was, byte for byte."""
    output = tmp_path / "keep.urdf"
    assert main(_argv(VALID, output)) == 0
    kept = output.read_bytes()
    capsys.readouterr()
    assert main(_argv({**VALID, "--base-mass": ["2e7"]}, output)) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "beyond the largest magnitude" in err
    assert err.startswith("freefloat: error: the composed servicer is refused, nothing written: ")
    assert output.read_bytes() == kept
    fresh = tmp_path / "new.urdf"
    assert main(_argv({**VALID, "--base-mass": ["2e7"]}, fresh)) == 2
    assert not fresh.exists() and not fresh.with_suffix(".srdf").exists()


def test_a_payload_mass_of_zero_is_named_before_what_it_would_need(tmp_path, capsys):
    """`--payload-mass 0` alone: the mass is the problem, not a missing inertia."""
    argv = _argv(
        {k: VALID[k] for k in ("--base-mass", "--base-size", "--mount")}, tmp_path / "p.urdf"
    )
    assert main([*argv[:-2], "--payload-mass", "0", *argv[-2:]]) == 2
    assert capsys.readouterr().err == (
        "freefloat: error: --payload-mass must be a finite number > 0 kg, got 0.0\n"
    )


#: A three-joint arm (revolute, prismatic, revolute), with room for one more joint element.
_ARM = """<?xml version="1.0"?>
<robot name="pris">
  <link name="base"><inertial><mass value="10"/>
    <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="1" effort="100"/></joint>
  <link name="l1"><inertial><origin xyz="0.5 0 0"/><mass value="10"/>
    <inertia ixx="0.1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="p2" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="1 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" velocity="0.2" effort="100"/></joint>
  <link name="l2"><inertial><origin xyz="0.2 0 0"/><mass value="5"/>
    <inertia ixx="0.1" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" velocity="1" effort="100"/>{mimic}</joint>
  <link name="l3"><inertial><origin xyz="0.3 0 0"/><mass value="5"/>
    <inertia ixx="0.1" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>
  {extra}
</robot>
"""
_LOOP = (
    '<joint name="close" type="revolute"><parent link="l3"/><child link="l1"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
)


@pytest.mark.parametrize(
    ("mimic", "extra", "message"),
    [
        ("", _LOOP, "closed loop: link 'l1' is the child of two joints"),
        ('<mimic joint="j1" multiplier="2"/>', "", "arm joint 'j3' mimics 'j1'"),
        (  # back to the arm's root: no link is the root
            "",
            _LOOP.replace('child link="l1"', 'child link="base"'),
            "closed loop: every link has a parent joint",
        ),
    ],
)
def test_an_arm_composed_as_no_urdf_loads_it_is_refused(mimic, extra, message, tmp_path, capsys):
    """A closed loop crashed Pinocchio's model builder (exit 139); a mimic was dropped, the arm
    then planned as if its joints moved apart. Both refused in one line, nothing written."""
    arm = tmp_path / "arm.urdf"
    arm.write_text(_ARM.format(mimic=mimic, extra=extra))
    out = tmp_path / "servicer.urdf"
    argv = ["compose", "--arm", str(arm), "--base-mass", "500", "--base-size", "1", "1", "1"]
    assert main([*argv, "--mount", "0.5", "0", "0", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert message in err[-1] and err[-1].startswith("freefloat: error:")
    assert not out.exists()


def test_lock_repeated_locks_every_joint_named(tmp_path, capsys):
    """``--lock A --lock B`` kept only B; the URDF written is read back here by its XML."""
    import xml.etree.ElementTree as ET

    out = tmp_path / "servicer.urdf"
    base = ["compose", "--arm", "ur5", "--base-mass", "500", "--base-size", "1", "1", "1"]
    locks = ["--lock", "shoulder_pan_joint=10", "--lock", "elbow_joint=20"]
    assert main([*base, "--mount", "0.5", "0", "0", *locks, "-o", str(out)]) == 0
    kinds = {j.get("name"): j.get("type") for j in ET.parse(out).getroot().iter("joint")}
    assert kinds["shoulder_pan_joint"] == kinds["elbow_joint"] == "fixed"
    assert kinds["shoulder_lift_joint"] == "revolute"


@pytest.mark.parametrize(
    ("locks", "message"),
    [
        (
            ["--lock", "elbow_joint=90", "elbow_joint=45"],
            "--lock elbow_joint given twice (elbow_joint=90 and elbow_joint=45); lock each "
            "joint once",
        ),
        (["--lock", "elbow_joint", "--lock", "elbow_joint"], "--lock elbow_joint given twice"),
        (["--lock"], "--lock needs at least one JOINT or JOINT=DEG after it"),
        (["--lock", "--lock", "elbow_joint=10"], "--lock needs at least one JOINT"),
        (["--lock", "elbow_joint="], "--lock elbow_joint=: give JOINT or JOINT=DEG"),
    ],
)
def test_a_lock_given_twice_or_empty_is_refused(tmp_path, capsys, locks, message):
    """The second value silently won; a bare --lock silently locked nothing."""
    out = tmp_path / "servicer.urdf"
    base = ["compose", "--arm", "ur5", "--base-mass", "500", "--base-size", "1", "1", "1"]
    assert main([*base, "--mount", "0.5", "0", "0", *locks, "-o", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_compose_will_not_write_over_its_arm(tmp_path, capsys):
    """``compose --arm a.urdf -o a.urdf`` would replace the arm it reads."""
    arm = tmp_path / "arm.urdf"
    arm.write_text(_ARM.format(mimic="", extra=""))
    kept = arm.read_bytes()
    argv = ["compose", "--arm", str(arm), "--base-mass", "500", "--base-size", "1", "1", "1"]
    assert main([*argv, "--mount", "0.5", "0", "0", "-o", str(arm)]) == 2
    assert "is the file this command reads" in capsys.readouterr().err
    assert arm.read_bytes() == kept


@pytest.mark.parametrize(
    ("mount", "said"),
    [
        (["3", "0", "0"], "is mounted at [3.0, 0.0, 0.0] m, 2.5 m off the box's surface"),
        (["0", "0", "0"], "is mounted at [0.0, 0.0, 0.0] m, 0.5 m inside the box"),
        (["0.5", "0.2", "-0.1"], None),  # on the +x face
        (["0.6", "0.6", "0"], "is mounted at [0.6, 0.6, 0.0] m, 0.141 m off the box's surface"),
    ],
)
def test_a_mount_off_the_box_surface_is_said(tmp_path, capsys, mount, said):
    """An arm mounted 2.5 m off its spacecraft, or at its centre, composed without a word."""
    argv = ["compose", "--arm", "ur5", "--base-mass", "100", "--base-size", "1", "1", "1"]
    assert main([*argv, "--mount", *mount, "-o", str(tmp_path / "s.urdf")]) == 0
    err = capsys.readouterr().err
    if said is None:
        assert "mounted at" not in err, err
    else:
        assert f"freefloat: warning: the arm 'ur5' {said} (1 x 1 x 1 m, faces at" in err, err
        assert "it is fixed there rigidly, as on a massless pedestal" in err


#: A second branch as deep as l2 -> l3 (from l1): two longest chains, l3 and l3b.
_TWIN = (
    '<joint name="p2b" type="prismatic"><parent link="l1"/><child link="l2b"/>'
    '<origin xyz="1 0.3 0"/><axis xyz="1 0 0"/>'
    '<limit lower="0" upper="0.5" velocity="0.2" effort="100"/></joint>'
    '<link name="l2b"><inertial><mass value="5"/>'
    '<inertia ixx="0.1" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    '<joint name="j3b" type="revolute"><parent link="l2b"/><child link="l3b"/>'
    '<origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>'
    '<limit lower="-3" upper="3" velocity="1" effort="100"/></joint>'
    '<link name="l3b"><inertial><mass value="5"/>'
    '<inertia ixx="0.1" iyy="0.5" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>'
)


def test_a_payload_on_an_arm_whose_chains_tie_points_to_the_scenario_route(tmp_path, capsys):
    """compose has no option to name the payload's holder; it said "name one in the
    scenario" as if it had."""
    arm = tmp_path / "twin.urdf"
    arm.write_text(_ARM.format(mimic="", extra=_TWIN))
    out = tmp_path / "servicer.urdf"
    argv = ["compose", "--arm", str(arm), "--base-mass", "500", "--base-size", "1", "1", "1"]
    argv += [
        "--mount",
        "0.5",
        "0",
        "0",
        "--payload-mass",
        "5",
        "--payload-box",
        "0.1",
        "0.1",
        "0.1",
    ]
    argv += ["-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "the payload's holder is ambiguous: 2 chains are longest (l3, l3b)" in err
    assert 'end_effector = "..." naming the holder' in err and not out.exists()


def _robot_name(path):
    """The robot element's name attribute, read with the standard library's XML parser."""
    import xml.etree.ElementTree as ET

    return ET.parse(path).getroot().get("name")


def test_the_robot_is_named_as_its_file_or_as_given(tmp_path, capsys):
    one = ["compose", "--arm", "ur5", "--base-mass", "100", "--base-size", "1", "1", "1"]
    one += ["--mount", "0.5", "0", "0"]
    assert main([*one, "-o", str(tmp_path / "my servicer.urdf")]) == 0
    assert _robot_name(tmp_path / "my servicer.urdf") == "my_servicer"
    assert main([*one, "--name", "sat-1.a", "-o", str(tmp_path / "b.urdf")]) == 0
    assert _robot_name(tmp_path / "b.urdf") == "sat-1.a"
    capsys.readouterr()
    assert main([*one, "--name", "two words", "-o", str(tmp_path / "c.urdf")]) == 2
    err = capsys.readouterr().err
    assert err == (
        "freefloat: error: robot name 'two words': give letters, digits, '_', '-' or '.', not "
        "first (at most 100)\n"
    )
    assert not (tmp_path / "c.urdf").exists()
    assert main([*one, "--name", "", "-o", str(tmp_path / "d.urdf")]) == 2
    assert capsys.readouterr().err == (
        "freefloat: error: --name is empty; give the robot's name, or leave --name out\n"
    )
    assert main([*one, "-o", str(tmp_path / ".urdf")]) == 0  # a name not led by a dot
    assert _robot_name(tmp_path / ".urdf") == "urdf"


def test_the_shipped_servicers_are_named_as_their_files():
    from freefloat.robot.model import robots_dir

    for name in ("panda_servicer", "ur5_servicer", "dual_ur5_servicer"):
        assert _robot_name(robots_dir() / f"{name}.urdf") == name


def test_a_prefix_with_a_line_break_is_refused(tmp_path, capsys):
    """A prefix with a line break made multi-line warnings and summaries of every name."""
    argv = ["compose", "--arm", "ur5", "--prefix", "a\nb_", "--arm", "ur5", "--prefix", "c_"]
    argv += ["--base-mass", "100", "--base-size", "1", "1", "1"]
    argv += [
        "--mount",
        "0.5",
        "0.2",
        "0",
        "--mount",
        "0.5",
        "-0.2",
        "0",
        "-o",
        str(tmp_path / "d.urdf"),
    ]
    assert main(argv) == 2
    assert capsys.readouterr().err == (
        "freefloat: error: arm prefix 'a\\nb_': a space, a line break or a control character "
        "would break the names it starts; give letters, digits or '_'\n"
    )
    assert list(tmp_path.iterdir()) == []
