"""Collision model, clearance constraint, keep-out objects and captured payloads."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.problem.constraints.clearance import Clearance
from freefloat.robot.collision import CollisionModel, Obstacle, known_srdf
from freefloat.robot.payload import Payload

import reference as ref
from conftest import ROOT

#: A box spacecraft (1 m cube) with a two-link planar arm whose second link carries a sphere.
SPHERE_ARM = """<?xml version="1.0"?>
<robot name="sphere_arm">
  <link name="base">
    <inertial><mass value="100.0"/><inertia ixx="16.7" iyy="16.7" izz="16.7" ixy="0" ixz="0"
      iyz="0"/></inertial>
    <collision><geometry><box size="1.0 1.0 1.0"/></geometry></collision>
  </link>
  <joint name="q1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="10" velocity="2"/></joint>
  <link name="l1"><inertial><origin xyz="0.5 0 0"/><mass value="5.0"/>
    <inertia ixx="0.01" iyy="0.4" izz="0.4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="q2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="1.0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="10" velocity="2"/></joint>
  <link name="l2"><inertial><origin xyz="0.3 0 0"/><mass value="3.0"/>
    <inertia ixx="0.01" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.6 0 0"/><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
</robot>
"""
OBSTACLE = Obstacle("post", "sphere", (0.3,), (0.0, 2.0, 0.0))


@pytest.fixture(scope="module")
def sphere_arm(tmp_path_factory):
    path = tmp_path_factory.mktemp("arm") / "sphere_arm.urdf"
    path.write_text(SPHERE_ARM)
    return ff.load_robot(path)


def _sphere_centre(q1: float, q2: float) -> np.ndarray:
    """Closed form: the sphere's centre in the spacecraft frame (m)."""
    return np.array(
        [
            0.5 + math.cos(q1) + 0.6 * math.cos(q1 + q2),
            math.sin(q1) + 0.6 * math.sin(q1 + q2),
            0.0,
        ]
    )


def _closed_form(q1: float, q2: float) -> dict[str, float]:
    p = _sphere_centre(q1, q2)
    outside = p - np.clip(p, -0.5, 0.5)
    return {
        "base_0 / l2_0": float(np.linalg.norm(outside)) - 0.1,
        "l2_0 / obstacle:post": float(np.linalg.norm(p - np.array(OBSTACLE.xyz))) - 0.4,
    }


@pytest.mark.parametrize("q", [(0.3, 2.0), (1.2, -0.5), (2.5, 1.0), (-1.0, 2.6)])
def test_distances_equal_the_closed_form(sphere_arm, q):
    model = CollisionModel(sphere_arm, obstacles=[OBSTACLE])
    assert sorted(model.names) == sorted(_closed_form(*q))
    got = dict(zip(model.names, model.distances(np.array(q)).values, strict=True))
    for name, want in _closed_form(*q).items():
        assert got[name] == pytest.approx(want, abs=1e-8), name


def test_distance_gradients_against_finite_differences(sphere_arm):
    model = CollisionModel(sphere_arm, obstacles=[OBSTACLE])
    for q in ([0.3, 2.0], [1.2, -0.5], [-1.0, 2.6]):
        q = np.array(q)
        grads = model.distances(q, gradients=True).gradients
        fd = ref.central_jacobian(lambda x: model.distances(x).values, q, 1e-6)
        np.testing.assert_allclose(grads, fd, atol=1e-7)


def test_servicer_clearance_against_coal_directly():
    """The model's distances equal coal's own distance queries on the placed shapes."""
    import coal
    import pinocchio as pin

    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    model = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(3)
    data = robot.model.createData()
    geometry_data = pin.GeometryData(model.geometry)
    for _ in range(3):
        q = rng.uniform(-2.0, 2.0, robot.n)
        ours = model.distances(q).values
        config = robot.configuration(q)
        pin.updateGeometryPlacements(robot.model, data, model.geometry, geometry_data, config)
        objects = model.geometry.geometryObjects
        for k, (a, b) in enumerate(model.pairs):
            request, result = coal.DistanceRequest(), coal.DistanceResult()
            request.gjk_tolerance = 1e-9
            request.enable_signed_distance = True
            distance = coal.distance(
                objects[a].geometry,
                coal.Transform3s(geometry_data.oMg[a].rotation, geometry_data.oMg[a].translation),
                objects[b].geometry,
                coal.Transform3s(geometry_data.oMg[b].rotation, geometry_data.oMg[b].translation),
                request,
                result,
            )
            assert ours[k] == pytest.approx(distance, abs=1e-7), model.names[k]


def test_srdf_removes_pairs_and_adjacent_bodies_are_not_checked():
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    everything = CollisionModel(robot)
    trimmed = CollisionModel(robot, known_srdf(robot))
    assert trimmed.n_pairs < everything.n_pairs
    assert "spacecraft_0 / shoulder_link_0" not in everything.names  # mounted on it
    assert any(name.startswith("spacecraft_0 / upper_arm") for name in everything.names)


@pytest.mark.parametrize(
    "shape, size, message",
    [
        ("box", (0.1, -0.2, 0.3), "sizes must be finite and > 0 m"),
        ("cone", (0.1,), "unknown shape 'cone'; valid: box, sphere, capsule"),
        ("capsule", (0.1,), "a capsule takes 2 size(s) [m], got 1"),
    ],
)
def test_bad_obstacles_are_refused(shape, size, message):
    with pytest.raises(ff.InputError) as info:
        Obstacle("panel", shape, size)
    assert message in str(info.value)


def test_payload_must_be_physical():
    with pytest.raises(ff.InputError, match="payload mass must be a finite number > 0 kg"):
        Payload(0.0, inertia=(1.0, 1.0, 1.0, 0.0, 0.0, 0.0))
    with pytest.raises(ff.InputError, match="triangle inequality"):
        Payload(10.0, inertia=(1.0, 1.0, 5.0, 0.0, 0.0, 0.0))
    with pytest.raises(ff.InputError, match="not positive definite"):
        Payload(10.0, inertia=(1.0, 1.0, 1.0, 2.0, 0.0, 0.0))


UR5_TOML = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("mass = -5.0\nbox = [1.0, 1.0, 1.0]", "payload mass must be a finite number > 0 kg"),
        ("mass = -5.0", "payload mass must be a finite number > 0 kg"),  # before the inertia
        ("mass = 20.0", "[payload] needs inertia = [ixx, iyy, izz, ixy, ixz, iyz]"),
        ("box = [1.0, 1.0, 1.0]", "[payload] needs mass [kg]"),
    ],
)
def test_a_bad_payload_table_is_named(table, message, tmp_path):
    path = tmp_path / "held.toml"
    path.write_text(UR5_TOML.read_text() + f"\n[payload]\n{table}\n")
    with pytest.raises(ff.ScenarioError) as info:
        ff.Scenario.from_toml(path)
    assert message in str(info.value)


def test_a_payload_box_without_inertia_is_a_uniform_box(tmp_path):
    """Closed form of a uniform 20 kg box of edges 0.2, 0.4, 0.6 m about its centre:
    m / 12 (y^2 + z^2) and so on."""
    path = tmp_path / "held.toml"
    path.write_text(UR5_TOML.read_text() + "\n[payload]\nmass = 20.0\nbox = [0.2, 0.4, 0.6]\n")
    payload = ff.Scenario.from_toml(path).payload
    assert payload is not None
    m = 20.0 / 12.0
    want = (m * (0.16 + 0.36), m * (0.04 + 0.36), m * (0.04 + 0.16), 0.0, 0.0, 0.0)
    assert payload.inertia == pytest.approx(want, rel=1e-14)
    assert payload.box == (0.2, 0.4, 0.6)


def _scenario(tmp_path, body: str, robot: str = "ur5_servicer"):
    path = tmp_path / "s.toml"
    path.write_text(f'robot = "{robot}"\nduration = 10.0\n{body}')
    return path


UR5_START = (
    "shoulder_pan_joint = {pan}, shoulder_lift_joint = -45.0, elbow_joint = 120.0, "
    "wrist_1_joint = -90.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0"
)


def test_start_in_collision_is_refused_naming_the_pair(tmp_path, capsys, monkeypatch):
    import pinocchio as pin

    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    start = np.radians([-90.0, -45.0, 120.0, -90.0, 0.0, 0.0])
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.configuration(start))
    tip = data.oMf[robot.end_effector_frame].translation  # spacecraft frame: base at identity
    body = f"""
[start]
joints = {{ {UR5_START.format(pan=-90.0)} }}
[goal]
joints = {{ {UR5_START.format(pan=-80.0)} }}
[[obstacles]]
name = "panel"
sphere = 0.05
xyz = [{tip[0]}, {tip[1]}, {tip[2]}]
"""
    out = tmp_path / "p.json"
    assert main(["plan", str(_scenario(tmp_path, body)), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("freefloat: error: ") and "\n" not in err
    assert "start configuration: " in err and "obstacle:panel" in err
    assert "below the clearance margin 0.01 m" in err
    assert not out.exists()


@pytest.mark.parametrize(
    "body, message",
    [
        ('[[obstacles]]\nname = "a"\nbox = [0.1, 0.1]\n', "box must be a list of 3 numbers"),
        (
            '[[obstacles]]\nname = "a"\nsphere = -0.1\n',
            "sphere = -0.1 m is outside the supported range [0, 1000] m",
        ),
        ('[[obstacles]]\nname = "a"\nsphere = 0\n', "sizes must be finite and > 0 m"),
        ('[[obstacles]]\nname = "a"\n', "give exactly one shape"),
        ("[safety]\nmargin_m = -1.0\n", "margin_m must be >= 0 m"),
        (
            "[safety]\nmargin_m = 1e9\n",
            "margin_m = 1e+09 m is outside the supported range [0, 1000]",
        ),
        ("[safety]\nspeed = 1.0\n", "unknown key in [safety] 'speed'"),
        ("[payload]\nmass = -3.0\ninertia = [1, 1, 1, 0, 0, 0]\n", "payload mass must be"),
        ("[payload]\nmass = 3.0\ninertia = [1, 1, 3, 0, 0, 0]\n", "triangle inequality"),
    ],
)
def test_bad_safety_tables_are_refused(tmp_path, body, message):
    text = f"""
[start]
joints = {{ {UR5_START.format(pan=0.0)} }}
[goal]
joints = {{ {UR5_START.format(pan=10.0)} }}
{body}"""
    with pytest.raises(ff.FreeFloatError) as info:
        ff.Scenario.from_toml(_scenario(tmp_path, text))
    assert message in str(info.value)


def test_payload_point_mass_on_the_planar_arm_equals_the_closed_form(tmp_path, monkeypatch):
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    mp, tiny = 20.0, 1e-4
    text = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    text = text.replace(
        'robot = "planar_2dof"', f'robot = "{ROOT / "robots" / "planar_2dof.urdf"}"'
    )
    text += f"\n[payload]\nmass = {mp}\ninertia = [{tiny}, {tiny}, {tiny}, 0.0, 0.0, 0.0]\n"
    path = tmp_path / "w.toml"
    path.write_text(text)
    scenario = ff.Scenario.from_toml(path)
    assert scenario.robot.end_effector == "ee"
    mmap = ff.MomentumMap(scenario.robot)
    # Body 2 with the point mass at its tip (1 m from joint 2): new mass, CM and inertia.
    m2 = ref.M2 + mp
    l2 = (ref.M2 * ref.L2 + mp * 1.0) / m2
    i2 = ref.I2 + ref.M2 * (ref.L2 - l2) ** 2 + mp * (1.0 - l2) ** 2 + tiny
    for q in ([0.3, 1.1], [-1.4, 2.0], [2.2, -0.7]):
        want = ref.planar_gains(
            *q,
            masses=(ref.M0, ref.M1, m2),
            inertias=(ref.I0, ref.I1, i2),
            lengths=(ref.R0, ref.L1, ref.R1, l2, 1.0 - l2),
        )
        assert mmap.f1(np.array(q))[2] == pytest.approx(want, abs=1e-10)
    # Planned with the payload: momentum stays zero, every check passes.
    plan = ff.plan(scenario)
    assert plan.verification["momentum"].value < 1e-9
    assert (
        "captured_payload" in (tmp_path / "cache").joinpath(Path(plan.robot.urdf).name).read_text()
    )


def test_clearance_check_of_a_plan_and_a_colliding_tamper(tmp_path):
    """A servicer plan records its clearance; a path pushed into the hull fails verify."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    plan = ff.plan(scenario)
    check = plan.verification["clearance"]
    assert plan.safety.checked and check.passed and check.unit == "m"
    assert "min clearance" in check.detail and check.value < 0.0  # clear by more than 1 cm
    robot = scenario.robot
    constraint = Clearance(CollisionModel(robot, known_srdf(robot)), 0.01)
    pan = ff.problem_from_scenario(
        ff.Scenario.from_toml(
            _scenario(
                tmp_path,
                f"""
[start]
joints = {{ {UR5_START.format(pan=-90.0)} }}
[goal]
joints = {{ {UR5_START.format(pan=90.0)} }}
""",
            )
        ),
        extra=[1, 1, 1, 0, 0, 0],
    )
    excess = constraint.violation(pan, np.zeros(3))
    assert excess.value > 0.02  # the plain quintic pan sweeps the arm 2-3 cm into the hull
    assert "spacecraft_0" in excess.detail


def ur5_pan_scenario(tmp_path) -> ff.Scenario:
    """Issue 13's case: a UR5 pan from -90 to 90 deg whose plain quintic path enters the hull."""
    body = f"""
[start]
joints = {{ {UR5_START.format(pan=-90.0)} }}
[goal]
joints = {{ {UR5_START.format(pan=90.0)} }}
base_zyx_deg = [-17.29, 1.5255, -33.449]
"""
    return ff.Scenario.from_toml(_scenario(tmp_path, body))


def test_the_ur5_pan_through_the_hull_plans_clear_of_it(tmp_path):
    """Issue 13's case: the plain quintic pan sweeps the arm into the hull; the plan does not."""
    scenario = ur5_pan_scenario(tmp_path)
    quintic = ff.problem_from_scenario(scenario, extra=[2] * 6)
    # The goal is a few tenths of a degree from the attitude the plain quintic pan reaches.
    offset = ff.geodesic_angle(quintic.achieved(np.zeros(12)), scenario.goal_attitude)
    assert 0.1 < math.degrees(offset) < 0.5
    plan = ff.plan(scenario)
    assert plan.base.attitude_error_rad < 1e-9
    check = plan.verification["clearance"]
    assert check.passed and plan.safety.margin_m == 0.01
    # The solver's hull model along the planned path, densely: at least 1 cm everywhere (the
    # original meshes against truth computed without coal: test_clearance_truth.py).
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    t = np.linspace(0.0, plan.duration, 801)
    q = plan.joint_positions(t)
    assert min(model.distances(x).values.min() for x in q) >= 0.01 - 1e-6


@pytest.mark.parametrize(
    ("name", "text", "said"),
    [
        ("garbage.srdf", "not xml at all <<<", "is not XML (syntax error: line 1, column 0)"),
        ("empty.srdf", "", "is not XML (no element found"),
        (
            "half.srdf",
            '<robot name="r"><disable_collisions link1="upper_arm_link"/></robot>',
            "<disable_collisions> number 1 lacks link1 or link2",
        ),
        ("other.srdf", '<urdf name="r"/>', "root element is <urdf>, expected <robot>"),
        ("pairs.toml", '<robot name="r"/>', "does not end in .srdf; give an SRDF file"),
        (
            "typed.srdf",
            '<!DOCTYPE robot [<!ENTITY a "x">]>\n<robot name="r"/>',
            "has a document type declaration; remove it",
        ),
    ],
)
def test_a_malformed_srdf_is_refused_in_one_line(tmp_path, capsys, name, text, said):
    """Pinocchio's SRDF reader raised a traceback (exit 1) on each of these."""
    (tmp_path / name).write_text(text)
    scenario = UR5_TOML.read_text().replace(
        'robot = "ur5_servicer"', f'robot = "{ROOT / "robots" / "ur5_servicer.urdf"}"'
    )
    (tmp_path / "s.toml").write_text(scenario + f'\n[safety]\nsrdf = "{name}"\n')
    assert main(["check", str(tmp_path / "s.toml")]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"freefloat: error: SRDF {tmp_path / name}") and said in err, err


def test_an_srdf_naming_links_the_robot_lacks_is_warned_and_the_rest_applies(tmp_path, capfd):
    """A typo or a missing arm prefix disabled nothing without a word."""
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    srdf = tmp_path / "typo.srdf"
    srdf.write_text(
        '<robot name="r"><disable_collisions link1="spacecraft" link2="upper_arm_lnk"/>'
        '<disable_collisions link1="spacecraft" link2="forearm_link"/></robot>'
    )
    everything = CollisionModel(robot)
    trimmed = CollisionModel(robot, srdf)
    err = capfd.readouterr().err
    assert "names links the robot does not have (upper_arm_lnk): their pairs disable nothing" in err
    removed = set(everything.names) - set(trimmed.names)
    assert removed and all("forearm_link" in n and "spacecraft" in n for n in removed)


def test_keep_out_objects_no_body_can_be_checked_against_are_refused(tmp_path, capsys):
    """The paper's planar robot has no collision geometry: a keep-out sphere its arm passes
    through was dropped from the plan (``safety.obstacles: []``) and ``check`` said "ok"."""
    text = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    text = text.replace(
        'robot = "planar_2dof"', f'robot = "{ROOT / "robots" / "planar_2dof.urdf"}"'
    )
    text = text.replace("check = false", "margin_m = 0.05")
    text += '\n[[obstacles]]\nname = "post"\nsphere = 0.3\nxyz = [1.5, 0.9, 0.0]\n'
    (tmp_path / "s.toml").write_text(text)
    for argv in (["check"], ["plan", "-o", str(tmp_path / "p.json")]):
        assert main([*argv, str(tmp_path / "s.toml")]) == 2
        _, err = capsys.readouterr()
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert err.startswith(
            "freefloat: error: keep-out object 'post' cannot be kept clear: no moving body of "
            "planar_2dof has collision geometry to check against it;"
        ), err
    assert not (tmp_path / "p.json").exists()


@pytest.mark.parametrize(
    ("shape", "said"),
    [
        (
            "sphere = 1e7",
            "[[obstacles]] #1 sphere = 1e+07 m is outside the supported range [0, 1000] m",
        ),
        ("box = [0.1, -2e3, 0.1]", "box[1] = -2000 m is outside the supported range [0, 1000] m"),
    ],
)
def test_an_obstacle_size_beyond_its_range_names_a_range_of_sizes(tmp_path, capsys, shape, said):
    """A radius was said to lie outside [-1000, 1000] m: no negative size is valid."""
    text = UR5_TOML.read_text().replace(
        'robot = "ur5_servicer"', f'robot = "{ROOT / "robots" / "ur5_servicer.urdf"}"'
    )
    (tmp_path / "s.toml").write_text(text + f'\n[[obstacles]]\nname = "o"\n{shape}\n')
    assert main(["check", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err, err


def test_a_known_arms_srdf_applies_only_to_its_own_shapes(tmp_path, capfd):
    """The shipped UR5 servicer with its wrist's collision mesh swapped for a 0.4 m sphere,
    its name kept: example-robot-data's UR5 SRDF (chosen by the name) disabled the wrist's
    pairs, and a wrist 0.35 m inside the forearm planned and verified."""
    wrist = "meshes/ur5/collision/wrist3.stl"
    urdf = (ROOT / "robots" / "ur5_servicer.urdf").read_text()
    start = urdf.index(
        f'<mesh filename="package://example-robot-data/robots/ur_description/{wrist}"/>'
    )
    end = urdf.index("/>", start) + 2
    (tmp_path / "r.urdf").write_text(urdf[:start] + '<sphere radius="0.4"/>' + urdf[end:])
    scenario = UR5_TOML.read_text().replace(
        'robot = "ur5_servicer"', f'robot = "{tmp_path / "r.urdf"}"'
    )
    (tmp_path / "s.toml").write_text(scenario)
    assert main(["check", str(tmp_path / "s.toml")]) == 1
    out, err = capfd.readouterr()
    assert "configuration: NOT OK" in out and "wrist_3_link_0" in out
    assert "the collision shapes or joints of its link 'wrist_3_link' are not that arm's" in err
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")  # the shipped one: applied
    assert known_srdf(robot) is not None


def test_a_plan_whose_srdf_is_a_fifo_is_refused_not_waited_on(tmp_path):
    """Its digest read a FIFO with nobody writing: verify, show, plot and export blocked."""
    import json
    import os
    import subprocess
    import sys

    plan = ff.plan(ff.Scenario.from_toml(UR5_TOML), samples=21)
    doc = json.loads(plan.to_json())
    os.mkfifo(tmp_path / "pairs.srdf")
    doc["safety"]["srdf"] = str(tmp_path / "pairs.srdf")
    (tmp_path / "p.json").write_text(json.dumps(doc))
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    done = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", "verify", str(tmp_path / "p.json")],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert (
        "pairs.srdf is not a regular file (a folder, a device or a FIFO); give an SRDF file"
        in done.stderr
    )


def test_a_known_arms_srdf_does_not_apply_to_a_reshaped_arm(tmp_path, caplog):
    """Its shapes alone matched: a UR5 servicer whose forearm is 9 cm shorter (the wrist
    joint's origin moved) kept the UR5's SRDF, and a pair it disables came within the margin
    unchecked."""
    urdf = (ROOT / "robots" / "ur5_servicer.urdf").read_text()
    start = urdf.index('<joint name="wrist_1_joint"')
    origin = urdf.index("<origin", start)
    end = urdf.index("/>", origin) + 2
    shorter = urdf[:origin] + '<origin xyz="0.0 0.0 0.30" rpy="0.0 1.5707963 0.0"/>' + urdf[end:]
    assert shorter != urdf
    (tmp_path / "r.urdf").write_text(shorter)
    with caplog.at_level("WARNING"):
        assert known_srdf(ff.load_robot(tmp_path / "r.urdf")) is None
    said = "the collision shapes or joints of its link 'wrist_1_link' are not that arm's"
    assert any(said in r.getMessage() for r in caplog.records)
    assert known_srdf(ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")) is not None


def test_an_srdf_never_disables_a_keep_out_object(tmp_path, capsys):
    """An SRDF pair naming the spacecraft (a user's spacecraft / forearm_link) disabled every
    keep-out object against that link too (they hang on the spacecraft's body): a sphere the
    forearm went 0.098 m into was accepted. With the pairs re-added in their own order, each
    pair keeps its own distance (the queries index them by that order)."""
    (tmp_path / "sc_fa.srdf").write_text(
        '<robot name="ur5_servicer"><disable_collisions link1="spacecraft" '
        'link2="forearm_link" reason="user"/></robot>'
    )
    text = UR5_TOML.read_text().replace(
        'robot = "ur5_servicer"', f'robot = "{ROOT / "robots" / "ur5_servicer.urdf"}"'
    )
    panel = '\n[[obstacles]]\nname = "panel"\nsphere = 0.05\nxyz = [0.814, 0.016, -0.2]\n'
    (tmp_path / "plain.toml").write_text(text + panel)
    (tmp_path / "srdf.toml").write_text(text + '\n[safety]\nsrdf = "sc_fa.srdf"\n' + panel)
    lines = {}
    for name in ("plain", "srdf"):
        assert main(["check", str(tmp_path / f"{name}.toml")]) == 1
        out = capsys.readouterr().out
        lines[name] = next(
            line for line in out.splitlines() if "forearm_link_0 / obstacle:panel" in line
        )
    assert lines["plain"] == lines["srdf"] and "-0.09" in lines["plain"]


def test_more_keep_out_objects_than_the_limit_are_refused_before_any_work(tmp_path, capsys):
    """15000 small spheres fit in a 1 MB scenario and took minutes per query batch."""
    text = UR5_TOML.read_text().replace(
        'robot = "ur5_servicer"', f'robot = "{ROOT / "robots" / "ur5_servicer.urdf"}"'
    )
    many = "".join(
        f'\n[[obstacles]]\nname = "o{k}"\nsphere = 0.01\nxyz = [5.0, {k * 0.05}, 0.0]\n'
        for k in range(65)
    )
    (tmp_path / "s.toml").write_text(text + many)
    assert main(["check", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "keep-out objects ([[obstacles]]) = 65 is outside the supported range [0, 64]" in err


def test_hull_volumes_are_qhulls_and_contain_their_meshes():
    """The volumes ``-v`` logs: each true hull's (coal's faces) is SciPy's qhull volume of the
    same points, and at least the volume its mesh encloses (a hull contains its mesh)."""
    from scipy.spatial import ConvexHull

    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    model = CollisionModel(s.robot, known_srdf(s.robot))
    infos = model.hulls()
    assert len(infos) >= 8  # the Panda's links are meshes
    objects = {o.name: o.geometry for o in model.geometry.geometryObjects}
    for info in infos:
        points = np.array(objects[info.name].points(), dtype=float).reshape(-1, 3)
        assert info.hull_volume == pytest.approx(ConvexHull(points).volume, rel=1e-9)
        assert info.mesh_volume <= info.hull_volume * (1 + 1e-9)
