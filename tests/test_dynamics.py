"""Torques, replay and verification."""

from __future__ import annotations

import importlib
import json

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.verify.checks import joint_torque_function

from conftest import ROOT


def test_torques_balance_kinetic_energy(worked_plan, planar_robot):
    """Independent truth: with no external force, dE/dt = tau . qdot (E from Pinocchio's M)."""
    mmap = ff.MomentumMap(planar_robot)
    model, data = planar_robot.model, planar_robot.model.createData()
    tau = joint_torque_function(worked_plan, mmap)
    coeffs = worked_plan.path().monomials()  # low degree: monomials are exact enough
    poly = np.polynomial.polynomial

    def energy(t):
        q = np.array([poly.polyval(t, c) for c in coeffs])
        qd = np.array([poly.polyval(t, poly.polyder(c)) for c in coeffs])
        v = mmap.velocity(q, qd)
        config = mmap.configuration(q, np.array([0.0, 0.0, 0.0, 1.0]))
        return 0.5 * v @ pin.crba(model, data, config) @ v, qd

    for t in (1.3, 4.0, 7.7):
        h = 1e-4
        power = (energy(t + h)[0] - energy(t - h)[0]) / (2 * h)
        assert power == pytest.approx(tau(t) @ energy(t)[1], rel=1e-6, abs=1e-9)


def test_torques_scale_with_inverse_square_duration(worked_scenario, worked_plan):
    other = ff.plan(ff.Scenario(**{**worked_scenario.__dict__, "duration": 5.0}))
    np.testing.assert_allclose(
        np.array(other.samples.tau),
        4.0 * np.array(worked_plan.samples.tau),
        rtol=1e-9,
        atol=1e-12,
    )
    assert other.verification["base_wrench"].value < 1e-12
    assert worked_plan.verification["base_wrench"].value < 1e-12


def test_replay_of_the_worked_example_reaches_the_goal(worked_plan):
    v = worked_plan.verification
    assert v.passed and v.failures == []
    assert v["replay_attitude"].value < 1e-4
    assert v["replay_joints"].value < 1e-4
    assert v["attitude_independent"].value < 1e-9
    assert v["momentum"].value < 1e-9


def test_replay_without_torque_stays_still(planar_robot):
    mmap = ff.MomentumMap(planar_robot)
    start = np.array([0.3, -0.2])
    result = ff.replay(mmap, start, ff.quat_from_zyx(0.5), lambda t: np.zeros(2), 3.0, 50)
    np.testing.assert_allclose(result.joints, start, atol=1e-15)
    assert ff.geodesic_angle(result.quaternion_xyzw, ff.quat_from_zyx(0.5)) < 1e-15


def _tampered(tmp_path, plan, edit):
    data = plan.to_dict()
    edit(data)
    path = tmp_path / "tampered.json"
    path.write_text(json.dumps(data))
    return path


def test_verify_cli_passes_a_good_plan(tmp_path, worked_plan, capsys):
    path = worked_plan.save(tmp_path / "p.json")
    assert main(["verify", str(path)]) == 0
    out = capsys.readouterr().out
    assert "verification                            passed" in out
    assert "negative where" not in out  # no path constraint: no note on how to read one


def test_verify_cli_says_how_to_read_a_path_constraints_row(tmp_path, capsys):
    """The UR5 servicer's limits and clearance hold, so their rows are negative (the worst
    excess over the limit): the table ends with a note that says so."""
    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    path = plan.save(tmp_path / "p.json")
    assert main(["verify", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split() for line in lines[2:-4]}
    assert float(rows["joint_position_limits"][2]) < 0.0 and float(rows["clearance"][2]) < 0.0
    assert "negative where" in lines[-3] and "beyond the margin" in lines[-2]
    assert lines[-1].startswith("  clearance       min clearance ")


def test_verify_cli_fails_a_tampered_free_parameter(tmp_path, worked_plan, capsys):
    def edit(data):
        data["path"]["coefficients"]["q2"][0] *= 1.001

    path = _tampered(tmp_path, worked_plan, edit)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("freefloat: error: plan field 'free_parameters.q2' disagrees"), err
    # Consistent free parameters too: the checks alone fail the changed path.
    data = json.loads(path.read_text())
    data["free_parameters"]["q2"][0] = data["path"]["coefficients"]["q2"][0]
    verdict = ff.verify_plan(ff.Plan.from_dict(data), recompute=False)
    # (every coefficient of the basis keeps the end conditions: only the attitude misses)
    assert "attitude_independent" in verdict.failures
    assert "boundary" not in verdict.failures


def test_verify_cli_fails_tampered_samples(tmp_path, worked_plan, capsys):
    def edit(data):
        data["samples"]["base_angular_velocity"][50][2] += 1e-3

    path = _tampered(tmp_path, worked_plan, edit)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "plan field 'samples.base_angular_velocity' disagrees" in err
    assert "at t = 2.5 s (z)" in err
    verdict = ff.verify_plan(ff.Plan.load(path), recompute=False)  # the checks alone
    assert verdict.failures == ["momentum"]


def test_verify_cli_corrupt_file_exits_2(tmp_path, capsys):
    path = tmp_path / "bad.json"
    path.write_text("{")
    assert main(["verify", str(path)]) == 2
    assert "corrupt JSON" in capsys.readouterr().err


def test_a_plan_failing_verification_is_never_written(tmp_path, monkeypatch, capsys):
    plan_module = importlib.import_module("freefloat.pipeline")

    real = plan_module.verify_plan

    def failing(plan, robot=None, constraints=None, **options):
        result = real(plan, robot, constraints=constraints, **options)
        wrong = ff.Check("replay_attitude", 1.0, 1e-4, "rad")
        return ff.Verification((*[c for c in result.checks if c.name != wrong.name], wrong))

    monkeypatch.setattr(plan_module, "verify_plan", failing)
    out = tmp_path / "p.json"
    assert main(["plan", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert (
        "the plan fails verification (replay_attitude: 1 rad against a tolerance of 0.0001)" in err
    )
    assert not out.exists()


def test_a_blown_up_state_on_a_continuous_joint_gives_nan_not_a_traceback(tmp_path):
    """A replay whose state overflowed to inf on a continuous joint: ``math.cos(inf)`` raises
    where numpy would give NaN. The replay's configurations must hold NaN there (the
    step-doubling checks read such a level as differing by inf), the other joints as given."""
    from freefloat.physics.replay import _Configurations

    import urdfs

    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm(kinds=("continuous", "revolute", "prismatic")))
    robot = ff.load_robot(path)
    configuration = _Configurations(ff.MomentumMap(robot))
    for blown in (np.inf, -np.inf, np.nan):
        q = configuration(np.array([blown, 0.25, 0.1]))
        assert np.isnan(q[robot.joints[0].idx_q : robot.joints[0].idx_q + 2]).all()
        assert q[robot.joints[1].idx_q] == 0.25 and q[robot.joints[2].idx_q] == 0.1
    q = configuration(np.array([0.5, 0.25, 0.1]))
    assert q[robot.joints[0].idx_q : robot.joints[0].idx_q + 2].tolist() == [
        np.cos(0.5),
        np.sin(0.5),
    ]


def test_the_cm_check_does_not_share_the_planners_cm(worked_scenario, monkeypatch):
    """The planner reads the CM off the centroidal maps (``centre_of_mass``) to place the base;
    verification takes Pinocchio's own CM at each sample. A CM formula gone wrong on the
    planner's side (here scaled by 1.5) moves the base, and the ``cm_offset`` check sees the
    CM drift and refuses the plan."""
    import sys

    import freefloat.physics.dynamics as dynamics

    right = dynamics.centre_of_mass
    for module in [m for name, m in sys.modules.items() if name.startswith("freefloat")]:
        if getattr(module, "centre_of_mass", None) is right:  # wherever the formula is used
            monkeypatch.setattr(module, "centre_of_mass", lambda ag: 1.5 * right(ag))
    with pytest.raises(ff.VerificationError) as info:
        ff.plan(worked_scenario)
    assert "cm_offset" in info.value.failures
