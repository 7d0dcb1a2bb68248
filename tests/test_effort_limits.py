"""Joint effort limits: exact Jacobian, dense peaks, exact shortest duration, clear refusals."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import EffortLimitError
from freefloat.problem.paths import JointPolynomials
from freefloat.verify.checks import joint_torque_function

from conftest import as_older_format

ROOT = Path(__file__).resolve().parents[1]


def _limited_example(tmp_path: Path, limit: float, extra: str = "{ q2 = 1 }") -> Path:
    """The worked example on a copy of its arm with effort limits of ``limit`` N m."""
    urdf = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    urdf = urdf.replace(
        '<axis xyz="0 0 1"/>',
        f'<axis xyz="0 0 1"/><limit effort="{limit}" velocity="10" lower="-3.1" upper="3.1"/>',
    )
    (tmp_path / "arm.urdf").write_text(urdf)
    scenario = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    scenario = scenario.replace('robot = "planar_2dof"', 'robot = "arm.urdf"')
    scenario = scenario.replace("extra = { q2 = 1 }", f"extra = {extra}")
    path = tmp_path / "limited.toml"
    path.write_text(scenario)
    return path


def test_effort_rows_jacobian_matches_finite_differences(tmp_path):
    scenario = ff.Scenario.from_toml(_limited_example(tmp_path, 3.0, "{ q1 = 2, q2 = 2 }"))
    problem = ff.problem_from_scenario(scenario)
    beta = np.array([0.3, -0.2, 0.5, 0.1])
    limits = ff.JointEffortLimits()
    instants = np.linspace(0.0, 1.0, 13)
    rows = limits.rows(problem, beta, instants)
    h = 1e-6
    for k in range(len(beta)):
        step = np.zeros_like(beta)
        step[k] = h
        fd = (
            limits.rows(problem, beta + step, instants).values
            - limits.rows(problem, beta - step, instants).values
        ) / (2 * h)
        np.testing.assert_allclose(rows.jacobian[:, k], fd, atol=1e-8)


def test_dense_peak_matches_a_fine_independent_grid(worked_plan, tmp_path):
    scenario = ff.Scenario.from_toml(_limited_example(tmp_path, 3.0))
    robot = scenario.robot
    path = worked_plan.path()
    peak, _, spread = ff.JointEffortLimits().peaks(robot, path)
    tau = joint_torque_function(worked_plan, ff.MomentumMap(robot))
    t = np.linspace(0.0, worked_plan.duration, 20001)
    fine = np.array([np.abs(tau(x)) for x in t])
    assert np.all(peak >= fine.max(axis=0) - 1e-12)
    # independent truth: SciPy's bounded Brent search on the torque around the fine peak
    from scipy.optimize import minimize_scalar

    step = t[1] - t[0]
    for i in range(robot.n):
        k = int(fine[:, i].argmax())
        best = minimize_scalar(
            lambda x, i=i: -abs(tau(x)[i]),
            bounds=(max(0.0, t[k] - step), min(worked_plan.duration, t[k] + step)),
            method="bounded",
            options={"xatol": 1e-12},
        )
        assert abs(peak[i] - (-best.fun)) <= spread + 1e-11
    assert spread < 1e-8


def test_shortest_duration_is_exact(worked_plan, tmp_path):
    scenario = ff.Scenario.from_toml(_limited_example(tmp_path, 2.0))
    robot = scenario.robot
    limits = ff.JointEffortLimits()
    path = worked_plan.path()
    shortest = limits.shortest_duration(robot, path)
    assert shortest > worked_plan.duration  # 2 N m is below the plan's peak
    # the same shape run in `shortest` seconds (coefficients in normalised time)
    scaled = JointPolynomials(path.coefficients, shortest)
    peak = limits.worst(robot, scaled)
    assert peak is not None and peak.joint.name == "q1"
    assert peak.fraction == pytest.approx(1.0, abs=1e-9)
    assert peak.peak == pytest.approx(2.0, abs=1e-9)
    assert peak.shortest_duration == pytest.approx(shortest, rel=1e-9)


def test_too_short_a_duration_names_the_shortest_one(tmp_path, capsys):
    path = _limited_example(tmp_path, 2.8)
    out = tmp_path / "p.json"
    assert main(["plan", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith("freefloat: error: joint 'q1' needs ")
    assert "above its effort limit 2.8 N m; the path found keeps every effort limit from " in err
    printed = re.search(r"every effort limit from ([0-9.]+) s on", err).group(1)
    assert err.endswith(f"s on; under {printed} s only another path can")
    assert not out.exists()
    with pytest.raises(EffortLimitError) as info:
        ff.plan(ff.Scenario.from_toml(path))
    shortest = info.value.shortest_duration
    assert shortest <= float(printed) <= shortest * (1 + 1e-3)  # rounded up: it holds as printed
    scenario = dataclasses.replace(ff.Scenario.from_toml(path), duration=shortest * 1.001)
    p = ff.plan(scenario)
    assert p.verification["joint_effort_limits"].value <= 0.0
    peak = np.abs(np.asarray(p.samples.tau)).max()
    assert peak == pytest.approx(2.8 / 1.001**2, rel=1e-3)
    assert math.isfinite(shortest)


@pytest.mark.parametrize("limit", [3.0, 2.9, 2.5])
def test_min_effort_finds_a_path_within_a_limit_the_minimum_norm_path_breaks(tmp_path, limit):
    """Down to limits below the peak of the unconstrained min_effort path (2.986 N m)."""
    scenario = ff.Scenario.from_toml(_limited_example(tmp_path, limit))
    with pytest.raises(EffortLimitError):
        ff.plan(scenario)
    p = ff.plan(scenario, objective="min_effort")
    assert np.abs(np.asarray(p.samples.tau)).max() <= limit
    assert p.verification["joint_effort_limits"].value <= 0.0


def test_a_plan_of_an_older_format_is_held_to_every_limit_of_its_urdf(tmp_path, capsys):
    """A freefloat.plan/2 file (no objective record, no effort check) still verifies, and is
    held to its URDF's effort limits all the same: relabelling a plan cannot escape them."""
    import json

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    current = ff.plan(scenario)
    assert "joint_effort_limits" in current.verification
    doc = as_older_format(json.loads(current.to_json()), "freefloat.plan/2")
    checks = doc["verification"]["checks"]
    doc["verification"]["checks"] = [c for c in checks if c["name"] != "joint_effort_limits"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc))
    assert main(["verify", str(old)]) == 0, capsys.readouterr().err
    loaded = ff.Plan.load(old)
    assert loaded.format == "freefloat.plan/2"
    assert "objective" not in json.loads(loaded.to_json())
    # the URDF's effort limits cut below the plan's peak torque: the /2 plan now fails
    peak = max(abs(v) for row in current.samples.tau for v in row)  # N m
    urdf = Path(doc["robot"]["urdf"]).read_text()
    cut = re.sub(r'effort="[0-9.e+-]+"', f'effort="{peak / 2:.6g}"', urdf)
    assert cut != urdf
    (tmp_path / "cut.urdf").write_text(cut)
    doc["robot"]["urdf"] = "cut.urdf"  # relative: read from the plan's folder
    relabelled = tmp_path / "relabelled.json"
    relabelled.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["verify", "-q", str(relabelled)]) == 1
    out = capsys.readouterr().out
    assert re.search(r"joint_effort_limits .* FAILED", out), out
    doc["robot"]["urdf"] = str(Path(current.robot.urdf))
    # a current plan without its effort check is refused, naming the check list
    doc["format"] = "freefloat.plan/3"
    doc["objective"] = as_older_format(json.loads(current.to_json()))["objective"]
    tampered = tmp_path / "tampered.json"
    tampered.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["verify", str(tampered)]) == 2
    assert "verification.checks" in capsys.readouterr().err


def test_the_shortest_duration_is_named_only_when_a_timed_limit_stood_in_the_way(tmp_path):
    """Which limits stood in the way is read from the error's ``blocked_by`` (filled where a
    continuation stopped at a constraint or a root broke one), not from its text: an error
    that merely mentions the effort limits explains nothing; one blocked by them names the
    shortest duration, the same as planning reports."""
    from freefloat.problem.constraints import scenario_constraints
    from freefloat.solvers.lazy_search import _explain_duration_limits

    scenario = ff.Scenario.from_toml(_limited_example(tmp_path, 2.8)).resolved()
    constraints = scenario_constraints(scenario)
    options = ff.SolveOptions()
    with pytest.raises(EffortLimitError) as planned:
        ff.plan(scenario)
    assert "joint_effort_limits" in planned.value.__cause__.blocked_by
    mention = ff.SolverError("a message that names joint_effort_limits in passing", 0.1)
    _explain_duration_limits(scenario, options, constraints, mention)  # nothing raised
    blocked = ff.SolverError("no root", 0.1, blocked_by=("joint_effort_limits",))
    with pytest.raises(EffortLimitError) as explained:
        _explain_duration_limits(scenario, options, constraints, blocked)
    assert explained.value.shortest_duration == pytest.approx(
        planned.value.shortest_duration, rel=1e-12
    )


def test_a_start_no_path_brings_within_the_effort_limits_names_the_shortest_duration():
    """The UR5 servicer with effort limits a thousandth of its URDF's, in 3 s: no path within
    them is found at the quintic path's own attitude, so the continuation stops at its start.
    The refusal says the effort limits stood in the way and names the shortest duration (it
    was a plain SolverError); planned 1 % slower than that, the plan's sampled torques (the
    sampling's inverse dynamics, not the limit's torque formula) stay within the limits."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    joints = tuple(
        dataclasses.replace(j, effort_limit=1e-3 * j.effort_limit) for j in scenario.robot.joints
    )
    robot = dataclasses.replace(scenario.robot, joints=joints)
    scenario = dataclasses.replace(scenario, robot=robot, duration=3.0)
    with pytest.raises(EffortLimitError) as info:
        ff.plan(scenario)
    assert "joint_effort_limits" in info.value.__cause__.blocked_by
    shortest = info.value.shortest_duration
    assert 3.0 < shortest < 60.0
    plan = ff.plan(dataclasses.replace(scenario, duration=1.01 * shortest))
    peaks = np.abs(np.asarray(plan.samples.tau, dtype=float)).max(axis=0)
    assert np.all(peaks <= np.array([j.effort_limit for j in joints]))
