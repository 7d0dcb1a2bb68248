"""Composed servicers: composition, validation and three-axis plans on real arms."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest
import yourdfpy

import freefloat as ff
from freefloat.cli import main
from freefloat.robot.compose import ARMS, ServicerSpec, compose_servicer, resolve_mesh
from freefloat.robot.model import example_robot_data_dir
from freefloat.robot.payload import Payload

import reference as ref
from conftest import ROOT

EXPECTED_JOINTS = {"panda": 7, "ur5": 6, "kinova": 6, "xarm7": 7, "z1": 6}


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_every_arm_composes_and_validates(arm, tmp_path):
    spec = ServicerSpec(
        arm, 150.0, (0.8, 0.7, 0.6), mount=(0.4, 0.0, 0.1), mount_rpy=(0.0, math.pi / 2, 0.0)
    )
    path = compose_servicer(spec, tmp_path / f"{arm}.urdf")
    robot = ff.load_robot(path)
    assert robot.n == EXPECTED_JOINTS[arm]
    assert not any("finger" in n.lower() or "gripper" in n.lower() for n in robot.joint_names)
    arm_only = ff.load_robot(path)  # total mass = spacecraft + every arm link
    import xml.etree.ElementTree as ET

    masses = [float(m.get("value")) for m in ET.parse(path).getroot().iter("mass")]
    assert arm_only.total_mass == pytest.approx(sum(masses), rel=1e-12)
    assert robot.model.inertias[1].mass >= 150.0  # the base body carries the spacecraft
    urdf = yourdfpy.URDF.load(
        str(path),
        build_scene_graph=False,
        load_meshes=False,
        filename_handler=yourdfpy.filename_handler_null,
    )
    assert urdf.validate()
    meshes = [
        el.geometry.mesh.filename
        for link in urdf.robot.links
        for el in link.visuals
        if el.geometry.mesh is not None
    ]
    assert meshes and all(resolve_mesh(m) is not None for m in meshes)


def test_spacecraft_inertia_is_the_box_unless_given(tmp_path):
    path = compose_servicer(ServicerSpec("ur5", 120.0, (1.0, 0.5, 0.25)), tmp_path / "a.urdf")
    base = ff.load_robot(path).model.inertias[1]
    assert base.mass > 120.0
    given = compose_servicer(
        ServicerSpec("ur5", 120.0, (1.0, 0.5, 0.25), base_inertia=(10.0, 12.0, 15.0)),
        tmp_path / "b.urdf",
    )
    text = given.read_text()
    assert 'ixx="10.0"' in text and 'izz="15.0"' in text


def test_compose_cli_and_its_errors(tmp_path, capsys):
    out = tmp_path / "s.urdf"
    assert (
        main(
            [
                "compose",
                "--arm",
                "z1",
                "--base-mass",
                "80",
                "--base-size",
                "0.5",
                "0.5",
                "0.5",
                "--mount",
                "0.25",
                "0",
                "0",
                "--mount-rpy",
                "0",
                "90",
                "0",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    assert "6 joints" in capsys.readouterr().out
    assert (
        main(
            [
                "compose",
                "--arm",
                "nope",
                "--base-mass",
                "80",
                "--base-size",
                "1",
                "1",
                "1",
                "--mount",
                "0",
                "0",
                "0",
                "-o",
                str(tmp_path / "x.urdf"),
            ]
        )
        == 2
    )
    assert "unknown arm 'nope'; valid: panda, ur5" in capsys.readouterr().err
    assert (
        main(
            [
                "compose",
                "--arm",
                "z1",
                "--base-mass",
                "80",
                "--base-size",
                "1",
                "0",
                "1",
                "--mount",
                "0",
                "0",
                "0",
                "-o",
                str(tmp_path / "y.urdf"),
            ]
        )
        == 2
    )
    assert "base size must be > 0 m" in capsys.readouterr().err
    assert (
        main(
            [
                "compose",
                "--arm",
                "panda",
                "--base-mass",
                "80",
                "--base-size",
                "1",
                "1",
                "1",
                "--mount",
                "0",
                "0",
                "0",
                "--lock",
                "elbow",
                "-o",
                str(tmp_path / "z.urdf"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "unknown movable joint to lock 'elbow'; valid: panda_joint1, " in err
    assert "panda_joint8" not in err  # a fixed joint (the Panda's flange) is not offered
    assert not (tmp_path / "x.urdf").exists() and not (tmp_path / "y.urdf").exists()


def test_inline_servicer_in_a_scenario(tmp_path, monkeypatch):
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    scenario = tmp_path / "s.toml"
    joints = ", ".join(f"joint{i} = {v}" for i, v in enumerate([0, 20, -30, 10, 5, 0], 1))
    scenario.write_text(f"""
duration = 10.0
[robot]
arm = "z1"
base_mass = 60.0
base_size = [0.5, 0.5, 0.5]
mount = [0.25, 0.0, 0.0]
mount_rpy_deg = [0.0, 90.0, 0.0]
[start]
joints = {{ {joints} }}
[goal]
joints = {{ {joints} }}
""")
    loaded = ff.Scenario.from_toml(scenario)
    assert loaded.robot.n == 6
    assert loaded.robot.urdf.parent == tmp_path / "cache"
    assert ff.Scenario.from_toml(scenario).robot.urdf == loaded.robot.urdf  # cached


def test_a_torso_with_two_equal_arms_composes_and_plans_with_the_end_effector_named(
    tmp_path, monkeypatch
):
    """An arm URDF that is a torso with two equally long chains (Robonaut 2's shape) has no
    default end effector: composed inline, the scenario's ``end_effector`` names one and the
    plan is made and verified (before, composing refused it whatever the scenario named);
    without one, the refusal's advice (name one in the scenario) is what makes it plan. The
    arm's URDF is named relative to the scenario file (the tests run from another folder),
    as ``robot = "..."`` is."""
    import urdfs

    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    body = urdfs.BASE.replace('name="base"', 'name="torso"').format(mass=20.0, i=0.5)
    for side, y in (("left", 0.3), ("right", -0.3)):
        body += urdfs.joint(f"{side}_q1", "torso", f"{side}_upper", xyz=(0.0, y, 0.3))
        body += urdfs.link(f"{side}_upper")
        body += urdfs.joint(f"{side}_q2", f"{side}_upper", f"{side}_lower", axis=(0, 1, 0))
        body += urdfs.link(f"{side}_lower")
    arm = tmp_path / "torso.urdf"
    arm.write_text(urdfs.robot(body, "torso"))
    joints = "{ left_q1 = 0.0, left_q2 = 0.0, right_q1 = 0.0, right_q2 = 0.0 }"
    goal = "{ left_q1 = 20.0, left_q2 = -15.0, right_q1 = -20.0, right_q2 = 10.0 }"
    text = (
        'duration = 10.0\n[robot]\narm = "torso.urdf"\nbase_mass = 200.0\n'
        "base_size = [0.6, 0.6, 0.6]\nmount = [0.3, 0.0, 0.0]\n[safety]\ncheck = false\n"
        f"[start]\njoints = {joints}\n[goal]\njoints = {goal}\n"
    )
    scenario = tmp_path / "torso.toml"
    scenario.write_text(text)
    with pytest.raises(ff.AmbiguousEndEffectorError, match="name one in the scenario"):
        ff.Scenario.from_toml(scenario)
    scenario.write_text('end_effector = "right_lower"\n' + text)
    plan = ff.plan(ff.Scenario.from_toml(scenario))
    assert plan.verification.passed
    assert plan.robot.end_effector == "right_lower"
    assert set(plan.robot.joints) == {"left_q1", "left_q2", "right_q1", "right_q2"}
    # two such torsos side by side (an arms list), one end effector named: planned too
    both = [
        f"arm{k}_{name}" for k in (1, 2) for name in ("left_q1", "left_q2", "right_q1", "right_q2")
    ]
    start = ", ".join(f"{n} = 0.0" for n in both)
    finish = ", ".join(
        f"{n} = {v}" for n, v in zip(both, [20.0, -15.0, -20.0, 10.0] * 2, strict=True)
    )
    scenario.write_text(
        'end_effector = "arm1_right_lower"\nduration = 10.0\n[robot]\nbase_mass = 200.0\n'
        'base_size = [0.6, 0.6, 0.6]\narms = [{ arm = "torso.urdf", mount = [0.3, 0.0, 0.0] }, '
        '{ arm = "torso.urdf", mount = [-0.3, 0.0, 0.0], mount_rpy_deg = [0.0, 0.0, 180.0] }]\n'
        f"[safety]\ncheck = false\n[start]\njoints = {{ {start} }}\n"
        f"[goal]\njoints = {{ {finish} }}\n"
    )
    assert ff.plan(ff.Scenario.from_toml(scenario)).verification.passed
    # composed on its own (freefloat compose), both tips are offered and the file written (it
    # was refused with advice compose cannot follow: "name one in the scenario"); a scenario
    # names the one it plans for, and loaded without one the tie is named
    spec = ServicerSpec(arm=str(arm), base_mass=200.0, base_size=(0.6, 0.6, 0.6))
    path = compose_servicer(spec, tmp_path / "torso_servicer.urdf")
    with pytest.raises(ff.AmbiguousEndEffectorError, match=r"left_lower.*right_lower"):
        ff.load_robot(path)
    assert ff.load_robot(path, ["right_lower"]).end_effector == "right_lower"
    # a captured payload needs the one tip that holds it: refused, nothing written
    held = replace(spec, payload=Payload(10.0, inertia=(1.0, 1.0, 1.0, 0.0, 0.0, 0.0)))
    with pytest.raises(ff.AmbiguousEndEffectorError, match=r"left_lower.*right_lower"):
        compose_servicer(held, tmp_path / "held.urdf")
    assert not (tmp_path / "held.urdf").exists()


def test_an_unknown_arm_name_is_named_as_written(tmp_path):
    """A mistyped arm name is reported as the name written, not as a path in the scenario's
    folder (only a path-like arm, with a folder or .urdf, is taken relative to the file)."""
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        'duration = 10.0\n[robot]\narm = "pandaa"\nbase_mass = 100.0\n'
        "base_size = [0.6, 0.6, 0.6]\n[start]\njoints = { joint1 = 0.0 }\n"
        "[goal]\njoints = { joint1 = 1.0 }\n"
    )
    with pytest.raises(ff.UnknownNameError, match="unknown arm 'pandaa'") as info:
        ff.Scenario.from_toml(scenario)
    assert str(tmp_path) not in str(info.value).split("unknown arm", 1)[1]


@pytest.fixture(scope="module", params=["panda_servicer", "ur5_servicer"])
def servicer_plan(request):
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{request.param}.toml")
    return scenario, ff.plan(scenario)


def test_servicer_three_axis_plan(servicer_plan):
    scenario, plan = servicer_plan
    assert not plan.feasibility.planar
    assert plan.base.attitude_error_rad < 1e-9
    v = plan.verification
    assert v.passed
    assert v["attitude_independent"].value < 1e-7  # adaptive DOP853 re-integration
    assert v["momentum"].value < 1e-9
    assert v["boundary"].value < 1e-9
    target = np.degrees(ff.zyx_from_quat(scenario.goal_attitude))
    np.testing.assert_allclose(plan.base.achieved_zyx_deg, target, atol=1e-7)
    q = np.array(plan.samples.q)
    np.testing.assert_allclose(q[0], scenario.start, atol=1e-14)
    np.testing.assert_allclose(q[-1], scenario.goal, atol=1e-12)
    for i, joint in enumerate(scenario.robot.joints):  # the whole path within the limits
        assert joint.lower <= q[:, i].min() and q[:, i].max() <= joint.upper


def test_exact_jacobian_on_a_servicer(servicer_plan):
    scenario, _ = servicer_plan
    problem = ff.build_problem(
        scenario.robot,
        scenario.start,
        scenario.goal,
        scenario.start_attitude,
        scenario.goal_attitude,
        20.0,
        extra=[1] * scenario.robot.n,
    )
    beta = np.linspace(-2.0, 2.0, problem.n_free)
    jac = problem.jacobian(beta)
    eps = 1e-5
    fd = ref.central_jacobian(problem.residual, beta, eps)
    assert np.abs(jac - fd).max() <= 1e-6 * np.abs(fd).max()


def test_robot_and_arm_tell_a_file_from_a_name_by_one_rule(tmp_path):
    """``robot = "..."`` and a servicer's ``arm`` share the rule; an upper-case suffix or a
    leading ``~`` is a file for both (the robot's rule once sent "Arm.URDF" to the shipped
    names)."""
    from freefloat.robot.locations import is_path_like, resolve_robot, robots_dir

    for text, is_file in [
        ("planar_2dof", False),
        ("ur5", False),
        ("Arm.URDF", True),
        ("arms/ur5", True),
        ("arms\\ur5", True),
        ("~/arm.urdf", True),
    ]:
        assert is_path_like(text) is is_file, text
    urdf = tmp_path / "Arm.URDF"
    urdf.write_text((robots_dir() / "planar_2dof.urdf").read_text())
    assert resolve_robot("Arm.URDF", relative_to=tmp_path) == urdf
    with pytest.raises(ff.UnknownNameError, match="robot"):
        resolve_robot("Arm", relative_to=tmp_path)
    # an inline servicer's arm, through the scenario's [robot] table: the same text is the
    # file next to the scenario (a copy of the Kinova arm), not an unknown arm name
    from freefloat.robot.arms import arm_urdf

    (tmp_path / "Kinova.URDF").write_text(arm_urdf("kinova").read_text())
    example = (ROOT / "examples" / "kinova_servicer.toml").read_text()
    assert 'arm = "kinova"' in example
    scenario_file = tmp_path / "servicer.toml"
    scenario_file.write_text(example.replace('arm = "kinova"', 'arm = "Kinova.URDF"'))
    composed = ff.Scenario.from_toml(scenario_file).robot
    assert (
        composed.joint_names
        == ff.Scenario.from_toml(ROOT / "examples" / "kinova_servicer.toml").robot.joint_names
    )


def test_one_arm_composed_from_a_urdf_keeps_the_srdf_beside_it(tmp_path, capsys):
    """With two arms the arms' SRDF pairs were merged and kept; with one they were dropped, so
    the pairs the arm's makers disable (fingers that interleave, say) were checked."""
    share = example_robot_data_dir() / "example-robot-data" / "robots" / "ur_description"
    urdf = (share / "urdf" / "ur5_robot.urdf").read_text()
    arm = tmp_path / "my_ur5.urdf"
    arm.write_text(urdf.replace("package://example-robot-data/robots/", f"{share.parent}/"))
    (tmp_path / "my_ur5.srdf").write_text((share / "srdf" / "ur5.srdf").read_text())
    out = tmp_path / "servicer.urdf"
    argv = ["compose", "--arm", str(arm), "--base-mass", "100", "--base-size", "0.6", "0.6", "0.6"]
    assert (
        main([*argv, "--mount", "0.3", "0", "0", "--mount-rpy", "0", "90", "0", "-o", str(out)])
        == 0
    )
    assert "with servicer.srdf: the arm's SRDF pairs" in capsys.readouterr().out
    pairs = lambda path: {  # noqa: E731
        frozenset((e.get("link1"), e.get("link2")))
        for e in ET.parse(path).getroot().iter("disable_collisions")
    }
    assert pairs(out.with_suffix(".srdf")) == pairs(tmp_path / "my_ur5.srdf") != set()


def test_one_named_arm_with_a_prefix_gets_its_srdf_prefixed(tmp_path, capsys):
    """Panda's SRDF is found by the servicer's name, but its links are unprefixed: with
    ``--prefix left_`` none matched and every pair it disables was checked."""
    out = tmp_path / "left.urdf"
    argv = ["compose", "--arm", "panda", "--prefix", "left_", "--base-mass", "100"]
    argv += ["--base-size", "1", "1", "1", "--mount", "0.5", "0", "0", "-o", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    share = example_robot_data_dir() / "example-robot-data" / "robots" / "panda_description"
    pairs = lambda path, prefix="": {  # noqa: E731
        frozenset((prefix + e.get("link1"), prefix + e.get("link2")))
        for e in ET.parse(path).getroot().iter("disable_collisions")
    }
    assert pairs(out.with_suffix(".srdf")) == pairs(share / "srdf" / "panda.srdf", "left_")
