"""The replay from a moving start, and the replay in segments each from the path's state.

Truth: SciPy's DOP853 on Pinocchio's ABA (another integrator), momentum conservation, the
whole replay where it converges, and plans whose torques are known wrong."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

import freefloat as ff
from freefloat.physics.attitude import quat_multiply
from freefloat.verify import integrating, segmented
from freefloat.verify.along import PathDynamics
from freefloat.verify.checks import Subject
from freefloat.verify.path_eval import file_path
from freefloat.verify.segmented import (
    SEGMENT_COUNTS,
    _doubling,
    _figures,
    _shot,
    segmented_replay,
)
from freefloat.verify.stepping import _rk5_attitude
from freefloat.viz.summary import summary

from conftest import ROOT


def _zero_momentum_start(robot: ff.Robot, joints: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """[v_base; qdot] whose total momentum is zero: the base twist from the centroidal map."""
    model, data = robot.model, robot.model.createData()
    ag = pin.computeCentroidalMap(model, data, robot.configuration(joints))
    v = np.zeros(model.nv)
    slots = [j.idx_v for j in robot.joints]
    v[slots] = rates
    v[:6] = -np.linalg.solve(ag[:, :6], ag[:, slots] @ rates)
    return v


def test_a_replay_from_a_moving_start_matches_dop853_and_keeps_zero_momentum():
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mmap = ff.MomentumMap(robot)
    joints = np.array([0.3, -1.2, 1.1, -0.4, 0.8, 0.2])
    rates = np.array([0.2, -0.1, 0.15, 0.3, -0.25, 0.1])
    tau = np.array([0.5, -1.0, 0.3, 0.05, -0.02, 0.01])
    start = _zero_momentum_start(robot, joints, rates)
    quaternion = ff.quat_from_zyx(0.1, -0.2, 0.05)
    found = ff.replay(mmap, joints, quaternion, lambda t: tau, 0.5, 64, start_velocity=start)

    model, data = robot.model, robot.model.createData()
    slots = [j.idx_v for j in robot.joints]
    forces = np.zeros(model.nv)
    forces[slots] = tau

    def rhs(_t, y):
        x, v, quat = y[:6], y[6 : 6 + model.nv], y[6 + model.nv :]
        a = pin.aba(model, data, robot.configuration(x), v, forces)
        turn = 0.5 * quat_multiply(quat, np.concatenate([v[3:6], [0.0]]))
        return np.concatenate([v[slots], a, turn])

    y0 = np.concatenate([joints, start, quaternion])
    truth = solve_ivp(rhs, (0.0, 0.5), y0, method="DOP853", rtol=1e-12, atol=1e-13).y[:, -1]
    np.testing.assert_allclose(found.joints, truth[:6], atol=1e-9)
    np.testing.assert_allclose(found.rates, truth[6 + 6 : 6 + model.nv], atol=1e-8)
    end = truth[6 + model.nv :] / np.linalg.norm(truth[6 + model.nv :])
    assert ff.geodesic_angle(found.quaternion_xyzw, end) < 1e-9
    assert found.momentum_max < 1e-9  # the start had none, and no external force acts


def _forced_to_segments(monkeypatch):
    """The replay from rest made to report no convergence: the segments decide."""
    whole = integrating._replay

    def unresolved(subject):
        level = whole(subject)
        return integrating._Replay(
            level.attitude, level.joints, np.inf, np.inf, level.steps, False, None
        )

    monkeypatch.setattr(integrating, "_replay", unresolved)


def _subject(plan: ff.Plan, replay_steps: int = 8192) -> Subject:
    robot = ff.load_robot(plan.robot.urdf)
    return Subject(plan, robot, ff.MomentumMap(robot), file_path(plan), replay_steps)


def test_a_genuine_plan_passes_in_segments(worked_plan, monkeypatch):
    pieces = segmented_replay(_subject(worked_plan))
    assert pieces.converged and pieces.segments == 8
    assert pieces.attitude + pieces.attitude_estimate <= 1e-4
    assert pieces.joints + pieces.joint_estimate <= 1e-4
    _forced_to_segments(monkeypatch)
    checked = ff.verify_plan(worked_plan, recompute=False)["replay_joints"]
    assert checked.verdict == "ok" and checked.detail.startswith("RK5 in 8 segments of ")


@pytest.mark.parametrize("count", SEGMENT_COUNTS)
def test_segments_see_a_torque_bias_as_the_whole_replay_does(worked_plan, monkeypatch, count):
    """Torques 1e-4 too large: the replay from rest (which converges here) ends 9.8e-5 rad
    and 2.5e-4 rad off; every segment count's figures, scaled to the whole motion, are of
    that order and never below it (the scaling is conservative), and they refuse the joints
    as it does."""
    true_torques = PathDynamics.torques
    monkeypatch.setattr(PathDynamics, "torques", lambda self, t: 1.0001 * true_torques(self, t))
    whole = ff.verify_plan(worked_plan, recompute=False)
    level = _doubling(_subject(worked_plan), count)
    assert level.converged
    for figure, name in ((level.attitude, "replay_attitude"), (level.joints, "replay_joints")):
        truth = whole[name]  # from rest: it converged, so it is the one made
        assert "segments" not in truth.detail and truth.error_estimate < 1e-2 * truth.value
        assert truth.value <= figure <= 10.0 * truth.value
    assert whole["replay_joints"].verdict == "FAILED" and level.joints - level.joint_estimate > 1e-4


def test_segments_are_not_tried_beyond_what_the_cap_resolves(worked_plan):
    """Two levels of 8 segments need 128 steps: a cap of 64 tries none."""
    pieces = segmented_replay(_subject(worked_plan, replay_steps=64))
    assert not pieces.converged and pieces.steps == 0


def test_segments_that_blow_up_decide_nothing(worked_plan, monkeypatch):
    """Torques a billion times too large: every count overflows; the replay from rest's own
    answer (not a number: it fails, and says why) stands."""
    true_torques = PathDynamics.torques
    monkeypatch.setattr(PathDynamics, "torques", lambda self, t: 1e9 * true_torques(self, t))
    assert not segmented_replay(_subject(worked_plan)).converged
    joints = ff.verify_plan(worked_plan, recompute=False)["replay_joints"]
    assert joints.verdict == "FAILED" and "blew up" in joints.detail


def test_segments_refuse_torques_that_do_not_drive_the_path(worked_plan, monkeypatch):
    """Every torque 1 % too large: each segment ends off the path, and the plan fails."""
    true_torques = PathDynamics.torques
    monkeypatch.setattr(PathDynamics, "torques", lambda self, t: 1.01 * true_torques(self, t))
    _forced_to_segments(monkeypatch)
    verdict = ff.verify_plan(worked_plan, recompute=False)
    joints = verdict["replay_joints"]
    assert joints.verdict == "FAILED" and not verdict.passed
    assert " segments of " in joints.detail
    assert joints.value - joints.error_estimate > 10 * joints.tolerance


@pytest.fixture(scope="module")
def kinova_plan():
    """A light arm on a 500 kg spacecraft for 20 s: its replay from rest cannot converge."""
    scenario = ff.Scenario.from_toml(ROOT / "examples" / "kinova_servicer.toml")
    goal = np.array([-0.00099725133, -0.00378116414, -0.00171438778, 0.99999088454])
    goal /= np.linalg.norm(goal)
    return ff.plan(ff.Scenario(**{**scenario.__dict__, "goal_attitude": goal}), samples=41)


def test_a_replay_from_rest_that_cannot_converge_is_decided_in_segments(kinova_plan):
    joints = kinova_plan.verification["replay_joints"]
    assert joints.verdict == "ok" and " segments of " in joints.detail
    # whether the replay from rest converges (and its perturbed torques then move its end as
    # far) or not depends on the host's rounding; either way it cannot decide
    assert "8192 steps did not converge" in joints.detail or "perturbed by 1e-12" in joints.detail
    assert joints.value + joints.error_estimate <= joints.tolerance
    said = summary(kinova_plan)
    assert "segments, each from the path's state" in said and "no verdict" not in said


def test_a_file_whose_replay_from_rest_said_no_verdict_still_verifies(kinova_plan, tmp_path):
    """A file written before replays were segmented states the Kinova replay as the replay
    from rest found it (no verdict, its estimate covering its value): another quantity than
    the segments' figures, so verify does not compare them and the replay made now decides.
    A figure stated as made the same way (8 segments) that no such replay could give (the
    attitude 9e-5 rad off, estimate 1e-9) still disagrees with its recomputation."""
    data = json.loads(kinova_plan.to_json())
    checks = {c["name"]: c for c in data["verification"]["checks"]}
    made_in_segments = checks["replay_attitude"]["detail"]
    assert made_in_segments.startswith("RK5 in 8 segments of ")
    for name, value in (("replay_attitude", 2.8e-6), ("replay_joints", 0.0173)):
        checks[name].update(
            value=value,
            error_estimate=max(value, 1e-4),
            detail="RK5, 8192 steps, not converged: no verdict",
        )
    path = tmp_path / "before.json"
    path.write_text(json.dumps(data))
    made = ff.verify_plan(ff.Plan.load(path))
    assert made.passed and " segments of " in made["replay_joints"].detail
    checks["replay_attitude"].update(value=0.9e-4, error_estimate=1e-9, detail=made_in_segments)
    path.write_text(json.dumps(data))
    with pytest.raises(ff.PlanMismatchError, match=r"verification\.checks"):
        ff.verify_plan(ff.Plan.load(path))


def test_segment_turns_compose_to_the_paths_attitude(kinova_plan):
    """The path's own turns over the segments, composed in order from the start, end where
    the attitude equation integrated over the whole path in one run ends (the Kinova motion
    turns about every axis, so the order of the composition matters)."""
    subject = _subject(kinova_plan)
    shot = _shot(subject, 8, 64)
    start = np.asarray(kinova_plan.base.start_quaternion_xyzw, dtype=float)
    composed = dataclasses.replace(shot, turns=shot.path_turns).end(start)
    grid = np.linspace(0.0, kinova_plan.duration, 4 * 8 * 64 + 1)
    whole = _rk5_attitude(start, subject.dynamics.omega(grid), kinova_plan.duration)
    assert ff.geodesic_angle(composed, whole) < 1e-12
    reversed_order = dataclasses.replace(shot, turns=shot.path_turns[::-1]).end(start)
    assert ff.geodesic_angle(reversed_order, whole) > 1e-9  # the check can tell the order


def test_a_segmented_levels_estimates_bound_a_finer_level(kinova_plan):
    """The figures on four times the steps differ from the decided level's by no more than
    its error estimates (both terms of the attitude figure move)."""
    subject = _subject(kinova_plan)
    level = _doubling(subject, 8)
    assert level.converged
    finer = _figures(subject, 8, _shot(subject, 8, 4 * level.steps))
    assert abs(level.attitude - finer[0]) <= level.attitude_estimate
    assert abs(level.joints - finer[1]) <= level.joint_estimate


@pytest.mark.parametrize("error", [1e-3, 1e-5])
def test_segments_find_torques_a_little_wrong_on_a_sensitive_motion(
    kinova_plan, monkeypatch, error
):
    """The Kinova motion, its replay from rest made unable to decide: torques off by a
    thousandth or a hundred-thousandth are still refused by the segments (their figures are
    scaled to the whole motion: re-anchoring each segment hides most of a wrong torque)."""
    true_torques = PathDynamics.torques
    monkeypatch.setattr(
        PathDynamics, "torques", lambda self, t: (1.0 + error) * true_torques(self, t)
    )
    _forced_to_segments(monkeypatch)
    joints = ff.verify_plan(kinova_plan, recompute=False)["replay_joints"]
    assert " segments of " in joints.detail and joints.verdict == "FAILED"


def test_a_file_replayed_in_another_number_of_segments_still_verifies(kinova_plan, tmp_path):
    """Another host's rounding may decide at another count: its figures, stated as 32
    segments found them, are compared with this host's 8 within both estimates."""
    data = json.loads(kinova_plan.to_json())
    for check in data["verification"]["checks"]:
        if check["name"].startswith("replay_"):
            assert check["detail"].startswith("RK5 in 8 segments of ")
            check["detail"] = check["detail"].replace("in 8 segments", "in 32 segments")
            check["value"] = 0.5 * check["value"]
            check["error_estimate"] = 1e-12
    path = tmp_path / "other_host.json"
    path.write_text(json.dumps(data))
    assert ff.verify_plan(ff.Plan.load(path)).passed


def test_a_count_whose_differences_grow_is_left_early(worked_plan, monkeypatch):
    """Ends that move further from the path at each doubling (a diverging count, as 8
    segments of the 24-joint chain): the count is left at its third doubling, not run to
    the cap (1024 steps a segment for 8 segments)."""
    subject = _subject(worked_plan)
    knots = subject.path(np.linspace(0.0, worked_plan.duration, 9)[1:])[0]
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (8, 1))
    asked = []

    def diverging(subject, count, steps, perturbed=False):
        asked.append(steps)
        return segmented._Shot(identity, identity, knots + 1e-3 * steps, knots)

    monkeypatch.setattr(segmented, "_shot", diverging)
    level = _doubling(subject, 8)
    assert not level.converged and max(asked) == 64 < 1024


def test_verify_says_when_the_replay_was_made_in_segments(kinova_plan, worked_plan, tmp_path):
    from freefloat.cli import main

    for plan, segmented_expected in ((kinova_plan, True), (worked_plan, False)):
        path = plan.save(tmp_path / "p.json")
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["verify", str(path)]) == 0
        said = "the replay was made in 8 segments, each from the path's state" in out.getvalue()
        assert said is segmented_expected


def test_a_continuous_joint_across_pi_is_compared_wrapped(tmp_path, monkeypatch):
    """A continuous joint from 2.9 to 3.6 rad: the replay holds it as an angle in (-pi, pi],
    the path past pi; its defects at the segments' ends are wrapped (else about 2 pi, and
    the plan would fail)."""
    import urdfs

    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm(kinds=("continuous", "revolute", "prismatic")))
    robot = ff.load_robot(path)
    names = robot.joint_names
    start = dict(zip(names, (2.9, 0.1, 0.0), strict=True))
    goal = dict(zip(names, (3.6, 0.3, 0.05), strict=True))
    scenario = ff.Scenario(robot, 10.0, start, goal)
    problem = ff.problem_from_scenario(scenario)
    drift = problem.achieved(np.zeros(problem.n_free))  # a goal the plain path reaches
    plan = ff.plan(dataclasses.replace(scenario, goal_attitude=drift), samples=41)
    _forced_to_segments(monkeypatch)
    joints = ff.verify_plan(plan, recompute=False)["replay_joints"]
    assert " segments of " in joints.detail and joints.verdict == "ok"
    assert joints.value < 1e-6
