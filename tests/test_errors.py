"""Bad input: each gets a one-line FreeFloatError naming the problem and what is valid."""

from __future__ import annotations

import json

import pytest

import freefloat as ff
from test_schema import _broken

import urdfs
from conftest import ROOT


def _write(tmp_path, text, name="r.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _load_error(tmp_path, text, cls=ff.ModelError):
    with pytest.raises(cls) as info:
        ff.load_robot(_write(tmp_path, text))
    message = str(info.value)
    assert "\n" not in message
    return message


def _two_link(**kw):
    body = urdfs.BASE.format(mass=kw.get("base_mass", 100.0), i=10.0)
    body += urdfs.joint("j1", "base", "l1", kw.get("kind", "revolute"))
    body += kw.get("l1", urdfs.link("l1"))
    return urdfs.robot(body)


def test_missing_urdf(tmp_path):
    with pytest.raises(ff.ModelError, match="URDF file not found"):
        ff.load_robot(tmp_path / "nope.urdf")


def test_malformed_urdf(tmp_path):
    assert "malformed URDF XML" in _load_error(tmp_path, "<robot name='x'><link></robot>")


def test_not_a_robot(tmp_path):
    assert "expected <robot>" in _load_error(tmp_path, "<sdf/>")


def test_link_without_mass(tmp_path):
    msg = _load_error(tmp_path, _two_link(l1='<link name="l1"/>'))
    assert "the body moved by joint 'j1' has no mass" in msg


def test_negative_mass(tmp_path):
    msg = _load_error(tmp_path, _two_link(l1=urdfs.link("l1", mass=-1.0)))
    assert "link 'l1' has negative mass -1.0 kg" in msg


def test_zero_base_mass(tmp_path):
    """Named as the spacecraft (it read "the body moved by joint base 'base'")."""
    msg = _load_error(tmp_path, _two_link(base_mass=0.0))
    assert "the spacecraft (the root link 'base', with the links fixed to it) has no mass" in msg


def test_non_positive_definite_inertia(tmp_path):
    msg = _load_error(tmp_path, _two_link(l1=urdfs.link("l1", inertia=(0.1, -0.2, 0.1))))
    assert "link 'l1' inertia is not positive definite" in msg


def test_no_movable_joint(tmp_path):
    body = urdfs.BASE.format(mass=10.0, i=1.0) + urdfs.joint("f", "base", "l1", "fixed")
    body += urdfs.link("l1")
    msg = _load_error(tmp_path, urdfs.robot(body))
    assert "no movable joint" in msg


def test_closed_loop(tmp_path):
    body = urdfs.BASE.format(mass=10.0, i=1.0)
    body += urdfs.joint("j1", "base", "l1") + urdfs.link("l1")
    body += urdfs.joint("j2", "base", "l2") + urdfs.link("l2")
    body += urdfs.joint("j3", "l2", "l1")
    msg = _load_error(tmp_path, urdfs.robot(body))
    assert "closed loop: link 'l1' is the child of two joints" in msg


def test_unsupported_joint_type(tmp_path):
    msg = _load_error(tmp_path, _two_link(kind="floating"))
    assert "type 'floating'; supported: revolute, continuous, prismatic, fixed" in msg


def test_joint_with_unknown_link(tmp_path):
    body = urdfs.BASE.format(mass=10.0, i=1.0) + urdfs.joint("j1", "base", "ghost")
    with pytest.raises(ff.UnknownNameError) as info:
        ff.load_robot(_write(tmp_path, urdfs.robot(body)))
    assert info.value.name == "ghost" and "base" in info.value.valid


def test_unknown_end_effector(planar_robot):
    with pytest.raises(ff.UnknownNameError) as info:
        ff.load_robot(planar_robot.urdf, end_effector="gripper")
    assert str(info.value) == (
        "unknown end-effector frame 'gripper'; valid: base, link1, link2, ee"
    )


def test_unknown_joint_name(planar_robot):
    with pytest.raises(ff.UnknownNameError, match=r"unknown joint 'q3'; valid: q1, q2"):
        planar_robot.joint("q3")


SCENARIO = """
robot = "{robot}"
duration = {duration}
[start]
joints = {{ q1 = 80.0, q2 = 30.0 }}
base_zyx_deg = [-50.0, 0.0, 0.0]
[goal]
joints = {{ {goal} }}
base_zyx_deg = [{yaw}, 0.0, 0.0]
{path}
"""


def scenario_text(
    robot=str(ROOT / "robots" / "planar_2dof.urdf"),
    duration="10.0",
    goal="q1 = -60.0, q2 = 90.0",
    yaw="0.0",
    path="[path]\nextra = { q2 = 1 }",
):
    return SCENARIO.format(robot=robot, duration=duration, goal=goal, yaw=yaw, path=path)


def _scenario_error(tmp_path, text, cls=ff.FreeFloatError):
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(cls) as info:
        ff.Scenario.from_toml(path)
    message = str(info.value)
    assert "\n" not in message
    return message


def test_an_unknown_joint_is_named_with_the_table_it_was_read_in(tmp_path):
    start = scenario_text().replace("q1 = 80.0, q2 = 30.0", "q1 = 80.0, q9 = 30.0")
    message = _scenario_error(tmp_path, start, ff.UnknownNameError)
    assert message.endswith("[start] joints: unknown joint 'q9'; valid: q1, q2")
    extra = scenario_text(path="[path]\nextra = { q7 = 1 }")
    message = _scenario_error(tmp_path, extra, ff.UnknownNameError)
    assert message.endswith("[path] extra: unknown joint 'q7'; valid: q1, q2")


def test_a_locked_joint_in_path_extra_is_named_as_locked(tmp_path):
    robot = str(ROOT / "robots" / "planar_2dof.urdf")
    text = scenario_text(goal="q1 = -60.0", path="[path]\nextra = { q2 = 1 }")
    text = text.replace(f'robot = "{robot}"', "").replace(", q2 = 30.0", "")
    text += f'[robot]\nurdf = "{robot}"\nlock = ["q2"]\n'
    message = _scenario_error(tmp_path, text)
    assert message.endswith(
        "[path] extra: joint 'q2' is locked ([robot] lock): it has no path to shape; leave it "
        "out of extra"
    )


def test_an_empty_path_extra_says_it_may_be_left_out(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(scenario_text(path="[path]\nextra = {}"))
    with pytest.raises(ff.InputError) as info:
        ff.plan(ff.Scenario.from_toml(path))
    assert str(info.value).endswith("(or leave extra out to let the planner choose)")


def test_scenario_round_trip(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(scenario_text())
    scenario = ff.Scenario.from_toml(path)
    assert scenario.goal == pytest.approx([-1.0471975511965976, 1.5707963267948966])


def test_unknown_top_level_key(tmp_path):
    msg = _scenario_error(tmp_path, "colour = 'red'\n" + scenario_text(), ff.UnknownNameError)
    assert "unknown key in the scenario 'colour'; valid: robot, duration, end_effector" in msg


def test_unknown_key_in_goal(tmp_path):
    text = scenario_text().replace("base_zyx_deg = [0.0", "base_xyz = [0.0")
    msg = _scenario_error(tmp_path, text, ff.UnknownNameError)
    assert (
        "unknown key in [goal] 'base_xyz'; valid: joints, base_zyx_deg, base_quaternion_xyzw" in msg
    )


def test_unknown_joint_in_scenario(tmp_path):
    msg = _scenario_error(
        tmp_path, scenario_text(goal="q1 = 1.0, elbow = 2.0"), ff.UnknownNameError
    )
    assert "unknown joint 'elbow'; valid: q1, q2" in msg


def test_missing_joint_in_scenario(tmp_path):
    msg = _scenario_error(tmp_path, scenario_text(goal="q1 = 1.0"))
    assert "no value for joint(s) q2" in msg


def test_unknown_robot_name(tmp_path):
    msg = _scenario_error(tmp_path, scenario_text(robot="hubble"), ff.UnknownNameError)
    assert (
        "unknown robot 'hubble'; valid: dual_ur5_servicer, panda_servicer, planar_2dof, "
        "ur5_servicer" in msg
    )


def test_nan_in_scenario(tmp_path):
    msg = _scenario_error(tmp_path, scenario_text(yaw="nan"), ff.ScenarioError)
    assert "[goal] base_zyx_deg[0] must be finite, got nan" in msg


def test_infinite_joint_value(tmp_path):
    msg = _scenario_error(tmp_path, scenario_text(goal="q1 = inf, q2 = 0.0"), ff.ScenarioError)
    assert "[goal] joint 'q1' must be finite" in msg


@pytest.mark.parametrize("duration", ["0.0", "-3.0"])
def test_non_positive_duration(tmp_path, duration):
    msg = _scenario_error(tmp_path, scenario_text(duration=duration), ff.ScenarioError)
    assert f"duration must be > 0 s, got {float(duration):g}" in msg


def test_invalid_toml(tmp_path):
    msg = _scenario_error(tmp_path, "robot = [unclosed", ff.ScenarioError)
    assert "invalid TOML" in msg


def test_missing_scenario_file(tmp_path):
    with pytest.raises(ff.ScenarioError, match="scenario file not found"):
        ff.Scenario.from_toml(tmp_path / "none.toml")


def test_bad_extra(tmp_path):
    msg = _scenario_error(
        tmp_path, scenario_text(path="[path]\nextra = { q2 = -1 }"), ff.ScenarioError
    )
    assert "[path] extra for 'q2' must be an integer >= 0, got -1" in msg


def test_start_outside_joint_limits(tmp_path):
    body = urdfs.BASE.format(mass=100.0, i=10.0)
    body += urdfs.joint("q1", "base", "l1", limits=(-1.0, 1.0)) + urdfs.link("l1")
    body += urdfs.joint("q2", "l1", "l2", limits=(-2.0, 2.0)) + urdfs.link("l2")
    urdf = _write(tmp_path, urdfs.robot(body), "limited.urdf")
    path = tmp_path / "s.toml"
    path.write_text(scenario_text(robot=str(urdf), goal="q1 = 10.0, q2 = 20.0"))
    scenario = ff.Scenario.from_toml(path)
    with pytest.raises(ff.JointLimitError) as info:
        ff.plan(scenario)
    assert info.value.joint == "q1"
    assert str(info.value) == (
        "start: joint 'q1' = 80 deg is outside its limits [-57.2958, 57.2958] deg"
    )


def test_infinite_duration_in_api(planar_robot):
    with pytest.raises(ff.InputError, match="duration must be a finite number of seconds > 0"):
        ff.build_problem(planar_robot, [0, 0], [1, 1], [0, 0, 0, 1], [0, 0, 0, 1], float("inf"))


def test_nan_joint_in_api(planar_robot):
    with pytest.raises(ff.InputError, match="goal joints contains NaN or infinite values"):
        ff.build_problem(planar_robot, [0, 0], [float("nan"), 1], [0, 0, 0, 1], [0, 0, 0, 1], 1.0)


def test_corrupt_plan_file(tmp_path):
    path = tmp_path / "p.json"
    path.write_text('{"format": "freefloat.plan/1", "robot": ')
    with pytest.raises(ff.PlanFileError, match="corrupt JSON"):
        ff.Plan.load(path)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.pop("format"), "plan has no 'format' field; this freefloat reads"),
        (  # a plan writes its main end effector first; an edited file loaded and verified
            lambda d: d["robot"].__setitem__("end_effector", "link2"),
            "'robot.end_effector' ('link2') is not the first of 'robot.end_effectors'",
        ),
    ],
)
def test_an_edited_plan_record_is_named(tmp_path, worked_plan, change, message):
    with pytest.raises(ff.PlanFileError) as info:
        ff.Plan.load(_broken(worked_plan, tmp_path, change))
    assert message in str(info.value)


def test_plan_file_of_another_version(tmp_path, worked_plan):
    data = worked_plan.to_dict()
    data["format"] = "freefloat.plan/6"
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ff.PlanFileError) as info:
        ff.Plan.load(path)
    assert (
        "plan format 'freefloat.plan/6' is not supported; this freefloat reads "
        "'freefloat.plan/1' and 'freefloat.plan/2' and 'freefloat.plan/3' and "
        "'freefloat.plan/4' and 'freefloat.plan/5'" in str(info.value)
    )


def test_plan_file_missing_key(tmp_path, worked_plan):
    data = worked_plan.to_dict()
    del data["samples"]
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ff.PlanFileError, match="plan field 'samples' is missing"):
        ff.Plan.load(path)


def test_plan_round_trip(tmp_path, worked_plan):
    path = worked_plan.save(tmp_path / "sub" / "plan.json")
    assert ff.Plan.load(path) == worked_plan
    assert [p.name for p in path.parent.iterdir()] == ["plan.json"]  # no temporary left


def test_errors_share_one_root():
    for cls in (
        ff.ModelError,
        ff.UnknownNameError,
        ff.ScenarioError,
        ff.InputError,
        ff.JointLimitError,
        ff.InfeasibleError,
        ff.SolverError,
        ff.PlanFileError,
    ):
        assert issubclass(cls, ff.FreeFloatError)


def test_to_dict_is_a_copy(worked_plan):
    data = worked_plan.to_dict()
    data["path"]["coefficients"]["q2"][0] = 123.0
    assert worked_plan.coefficients["q2"][0] != 123.0


def test_bad_polynomial_degree():
    with pytest.raises(ff.InputError, match="polynomial degree 4 is invalid; each must be >= 5"):
        ff.PathFamily([0.0, 0.0], [1.0, 1.0], (5, 4))


def test_zero_quaternion_in_api(planar_robot):
    with pytest.raises(ff.InputError, match="start attitude must be a non-zero quaternion"):
        ff.build_problem(planar_robot, [0, 0], [1, 1], [0, 0, 0, 0], [0, 0, 0, 1], 1.0)


def test_both_attitude_forms_in_a_scenario(tmp_path):
    text = scenario_text().replace(
        "base_zyx_deg = [-50.0, 0.0, 0.0]",
        "base_zyx_deg = [-50.0, 0.0, 0.0]\nbase_quaternion_xyzw = [0.0, 0.0, 0.0, 1.0]",
    )
    msg = _scenario_error(tmp_path, text, ff.ScenarioError)
    assert "[start] gives both base_zyx_deg and base_quaternion_xyzw; give one" in msg


def test_goal_with_joints_and_cartesian_position(tmp_path):
    text = scenario_text().replace("[goal]\n", "[goal]\nend_effector_xyz = [1.0, 0.0, 0.0]\n")
    msg = _scenario_error(tmp_path, text, ff.ScenarioError)
    assert "[goal] gives both joints and end_effector_xyz; give one" in msg


@pytest.mark.parametrize(
    ("quaternion", "norm"),
    [("[0.0, 0.0, 0.0, 0.0]", "0"), ("[1e-300, 0.0, 0.0, 1e-300]", "1.41e-300")],
)
def test_zero_quaternion_in_a_scenario(tmp_path, quaternion, norm):
    """A tiny quaternion was said to be "non-zero"-less; its norm is named."""
    text = scenario_text().replace(
        "base_zyx_deg = [0.0, 0.0, 0.0]", f"base_quaternion_xyzw = {quaternion}"
    )
    assert "base_quaternion_xyzw" in text
    msg = _scenario_error(tmp_path, text, ff.ScenarioError)
    assert f"[goal] base_quaternion_xyzw has norm {norm}, too near zero to be an attitude" in msg


def test_cli_rejects_too_few_samples(capsys, tmp_path):
    from freefloat.cli import main

    assert main(["plan", "--samples", "1", "-o", str(tmp_path / "p.json")]) == 2
    assert "--samples must be at least 2, got 1" in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()


def test_a_refusal_under_another_headline_keeps_every_figure():
    error = ff.UnreachableAttitudeError(
        "reachable up to 1 deg",
        0.02,
        reached=0.01,
        asked=0.03,
        tried=("continuation",),
        per_axis=(0.01, -0.015, 0.005),
        hint="try a longer path",
        stopped_by="joint 'j1' limit",
        last_beta=(0.1, 0.2),
        axis=(0.0, 1.0, 0.0),
        problem="a problem",
    )
    renamed = error.with_headline("reachable up to 1 deg; clearance too")
    assert renamed.headline == "reachable up to 1 deg; clearance too"
    assert str(renamed).startswith("reachable up to 1 deg; clearance too (the path it stopped")
    assert str(renamed).endswith("; tried: continuation; try a longer path")
    for name in ("best_residual", "reached", "asked", "tried", "per_axis", "hint"):
        assert getattr(renamed, name) == getattr(error, name), name
    for name in ("stopped_by", "last_beta", "axis", "problem", "reached_fraction"):
        assert getattr(renamed, name) == getattr(error, name), name
    assert renamed.reached_fraction == pytest.approx(1 / 3)


@pytest.mark.parametrize(
    ("reached_deg", "asked_deg"),
    [
        (10.0, 60.0),
        (46.7864, 46.8),
        (46.79996, 46.8),
        (46.8 - 1e-10, 46.8),
        (0.636, 0.636),
        (29.3, 47.9),
        (47.9, 29.3),
    ],
)
def test_a_refusals_turns_never_print_a_turn_short_of_the_goal_as_the_goal(
    reached_deg: float, asked_deg: float
) -> None:
    """``reachable up to X of the Y deg asked``: X and Y read back (the message's own text)
    lie within their printed precision of the turns, and a turn short of the goal never
    prints as the goal's figure; three digits where those already differ."""
    import math
    import re

    phrase = ff.UnreachableAttitudeError.turn_phrase(
        math.radians(reached_deg), math.radians(asked_deg)
    )
    found = re.fullmatch(r"reachable up to (\S+) deg of the (\S+) deg asked", phrase)
    assert found is not None, phrase
    shown_reached, shown_asked = found.groups()
    for shown, truth in ((shown_reached, reached_deg), (shown_asked, asked_deg)):
        digits = len(shown.replace(".", "").lstrip("0"))
        assert abs(float(shown) - truth) <= 0.5 * 10 ** (math.floor(math.log10(truth)) - digits + 1)
    if math.radians(reached_deg) < math.radians(asked_deg):
        assert shown_reached != shown_asked
    if f"{reached_deg:.3g}" != f"{asked_deg:.3g}" or reached_deg == asked_deg:
        assert (shown_reached, shown_asked) == (f"{reached_deg:.3g}", f"{asked_deg:.3g}")
