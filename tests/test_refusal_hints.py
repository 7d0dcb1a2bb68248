"""The clauses a refused search adds where the cause points at a change to the scenario."""

from __future__ import annotations

import pytest

import freefloat as ff
from freefloat.solvers.hints import REACH_CLAUSE, extra_hint, finger_hint, reach_hint

import urdfs


def _scenario(tmp_path, extra: str = "") -> ff.Scenario:
    """A base, two arm joints and two gripper fingers (tight limits), from its own URDF."""
    body = urdfs.BASE.format(mass=100.0, i=16.0)
    body += urdfs.joint("shoulder", "base", "l1", axis=(0, 0, 1))
    body += urdfs.link("l1")
    body += urdfs.joint("elbow", "l1", "l2", axis=(0, 1, 0))
    body += urdfs.link("l2")
    for side in ("left", "right"):
        body += urdfs.joint(f"gripper_{side}_finger_joint", "l2", side, limits=(-0.1, 0.1))
        body += urdfs.link(side, mass=0.2)
    (tmp_path / "arm.urdf").write_text(urdfs.robot(body, "fingered"))
    zeros = "{ shoulder = 0.0, elbow = 0.0, gripper_left_finger_joint = 0.0, "
    zeros += "gripper_right_finger_joint = 0.0 }"
    text = (
        f'robot = "arm.urdf"\nduration = 10.0\n{extra}[start]\njoints = {zeros}\n'
        f"[goal]\njoints = {zeros.replace('shoulder = 0.0', 'shoulder = 30.0')}\n"
        "base_zyx_deg = [1.0, 0.0, 0.0]\n"
    )
    (tmp_path / "s.toml").write_text(text)
    return ff.Scenario.from_toml(tmp_path / "s.toml")


def test_a_finger_joints_limit_suggests_holding_the_fingers(tmp_path):
    scenario = _scenario(tmp_path)
    stopped = "joint_position_limits ahead: joint 'gripper_right_finger_joint' at t = 4 s"
    assert finger_hint(scenario.robot, stopped) == (
        "joint 'gripper_right_finger_joint', whose limit stopped it, looks like a finger or "
        "gripper joint: to turn the spacecraft with the arm alone, lock the fingers ([robot] "
        'lock = ["gripper_left_finger_joint", "gripper_right_finger_joint"], in a [robot] '
        'table with urdf = "..." for a robot from its own URDF; a composed servicer locks '
        "them unless keep_gripper = true)"
    )
    # an arm joint's limit, another constraint, or no name: nothing to say
    assert (
        finger_hint(scenario.robot, "joint_position_limits ahead: joint 'elbow' at t = 4 s") == ""
    )
    assert finger_hint(scenario.robot, "clearance ahead: gripper_right_finger_joint") == ""
    assert finger_hint(scenario.robot, "a singular map (dh/dbeta loses rank)") == ""


def test_a_fixed_path_freedom_is_named_only_when_the_scenario_fixes_it(tmp_path):
    refusal = ff.SolverError("no path reaches the goal attitude", 0.01)
    assert extra_hint(_scenario(tmp_path), refusal) == ""
    fixed = _scenario(tmp_path, "[path]\nextra = { shoulder = 2, elbow = 1 }\n")
    assert extra_hint(fixed, refusal).startswith(
        "the scenario fixes [path] extra (3 free coefficient(s) in all)"
    )
    assert extra_hint(fixed, None) == ""


def test_reach_names_the_outer_bound_and_a_finger_that_stopped_a_direction(tmp_path):
    """``freefloat reach``'s rows: a direction that stopped at nothing reached the outer bound
    it headed for; a finger joint's limit in some row adds the finger clause once, below."""
    import dataclasses

    from freefloat.reachable import reachable
    from freefloat.viz.reach_text import reach_lines

    scenario = _scenario(tmp_path)
    report = reachable(scenario, budget=0)  # the drift attitude and outer bound alone
    first, second, *rest = report.directions
    stopped = "joint_position_limits ahead: joint 'gripper_left_finger_joint' at t = 2 s"
    report = dataclasses.replace(
        report,
        budget=30,  # as if the inner estimate had run, these rows its results
        directions=(
            dataclasses.replace(first, inner=first.outer, stopped_by=""),
            dataclasses.replace(second, inner=0.001, stopped_by=stopped),
            *(dataclasses.replace(d, inner=0.001, stopped_by=stopped) for d in rest),
        ),
    )
    lines = reach_lines(report, scenario.robot)
    rows = [line for line in lines if line.startswith("  +") or line.startswith("  -")]
    assert rows[0].endswith("its outer bound (heads no further)")
    assert rows[1].endswith(stopped)
    notes = [line for line in lines if line.startswith("note: ")]
    assert notes == [f"note: {finger_hint(scenario.robot, stopped)}"]
    assert "gripper_left_finger_joint" in notes[0]


def test_a_joint_limit_detail_gives_the_value_and_the_limit(tmp_path):
    """The joint's extreme on the path against the limit it comes nearest, in degrees (a
    turning joint). On the plain quintic the fingers, held at 0, are the nearest: 0.1 rad
    (5.7296 deg) below their upper limit, the left one named first."""
    import numpy as np

    from freefloat.problem.constraints.joint_position import JointPositionLimits

    scenario = _scenario(tmp_path)
    problem = ff.problem_from_scenario(scenario)
    path = problem.polynomials(np.zeros(problem.n_free))
    plain = JointPositionLimits().excess(scenario.robot, path)
    assert plain.value == pytest.approx(-0.1, abs=1e-12)
    assert plain.detail.startswith("joint 'gripper_left_finger_joint' at t = ")
    assert plain.detail.endswith(" s (0 deg, upper limit 5.7296 deg)")


def test_a_refused_search_asks_for_the_finger_hint_with_what_stopped_it(tmp_path, monkeypatch):
    """The wiring: a refusal passes the stop it reports to the finger hint and keeps its
    clause (a stand-in hint here; the real one is tested above), after the others."""
    import freefloat.solvers.search as search_module

    asked: list[str] = []

    def stand_in(robot, stopped_by: str) -> str:
        asked.append(stopped_by)
        return "STAND-IN CLAUSE"

    monkeypatch.setattr(search_module, "finger_hint", stand_in)
    _scenario(tmp_path, "[safety]\ncheck = false\n")  # writes s.toml
    text = (tmp_path / "s.toml").read_text().replace("[1.0, 0.0, 0.0]", "[0.0, 0.0, 60.0]")
    (tmp_path / "s.toml").write_text(text)  # 60 deg about z: beyond this arm
    with pytest.raises(ff.UnreachableAttitudeError) as refused:
        ff.plan(ff.Scenario.from_toml(tmp_path / "s.toml"))
    assert refused.value.stopped_by in asked  # each refused search level asks with its stop
    assert "STAND-IN CLAUSE" in refused.value.hint
    # and a refused goal attitude ends by pointing at what does plan
    assert refused.value.hint.endswith(REACH_CLAUSE)
    assert reach_hint(refused.value.hint) == ""  # named once
    assert reach_hint("") == REACH_CLAUSE


def test_a_sliding_joints_detail_is_in_metres_at_its_lower_limit(tmp_path):
    """A prismatic joint driven below its lower limit: value and limit in m."""
    import numpy as np

    from freefloat.problem.constraints.joint_position import JointPositionLimits

    (tmp_path / "slider.urdf").write_text(urdfs.slider_arm())
    (tmp_path / "s.toml").write_text(
        'robot = "slider.urdf"\nduration = 4.0\n[start]\njoints = { slide = 0.0, turn = 0.0 }\n'
        "[goal]\njoints = { slide = 0.0, turn = 10.0 }\nbase_zyx_deg = [0.2, 0.0, 0.0]\n"
    )
    scenario = ff.Scenario.from_toml(tmp_path / "s.toml")
    problem = ff.problem_from_scenario(scenario)
    path = problem.polynomials(np.zeros(problem.n_free))
    limits = JointPositionLimits()
    plain = limits.excess(scenario.robot, path)  # the slide held at 0: 0.2 m above -0.2 m
    assert plain.value == pytest.approx(-0.2, abs=1e-12)
    assert plain.detail.endswith(" s (0 m, lower limit -0.2 m)")
