"""Objectives: exact gradients, closed forms, duration scaling, and what they buy."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.physics.dynamics import inverse_dynamics_batch
from freefloat.physics.torque_derivatives import torques_and_derivatives

from conftest import worked_problem

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def ur5_scenario():
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    scenario = scenario.resolved()
    scenario.write_robot()
    return scenario


def _fd_gradient(fun, beta, h=1e-6):
    out = np.empty_like(beta)
    for k in range(len(beta)):
        step = np.zeros_like(beta)
        step[k] = h
        out[k] = (fun(beta + step) - fun(beta - step)) / (2 * h)
    return out


@pytest.mark.parametrize("name", sorted(ff.OBJECTIVES))
def test_objective_gradients_match_finite_differences(worked_scenario, name):
    problem = worked_problem(worked_scenario, {"q1": 2, "q2": 2})
    beta = np.array([0.3, -0.2, 0.5, 0.1])
    objective = ff.objective_named(name)
    found = objective.evaluate(problem, beta)
    fd = _fd_gradient(lambda b: objective.evaluate(problem, b).value, beta)
    np.testing.assert_allclose(found.gradient, fd, rtol=1e-6, atol=1e-9 * abs(found.value))


@pytest.mark.parametrize("name", ["min_effort", "min_length"])
def test_objective_gradients_on_a_spatial_servicer(ur5_scenario, name):
    problem = ff.problem_from_scenario(ur5_scenario, extra=[1] * ur5_scenario.robot.n)
    rng = np.random.default_rng(3)
    beta = 0.05 * rng.normal(size=problem.n_free)
    objective = ff.objective_named(name)
    found = objective.evaluate(problem, beta)
    fd = _fd_gradient(lambda b: objective.evaluate(problem, b).value, beta, h=1e-5)
    scale = np.abs(found.gradient).max()
    np.testing.assert_allclose(found.gradient, fd, rtol=1e-5, atol=1e-7 * scale)


def test_torque_derivatives_match_inverse_dynamics_and_finite_differences(ur5_scenario):
    """Torques equal the plan's inverse dynamics; derivatives equal central differences."""
    mmap = ff.MomentumMap(ur5_scenario.robot)
    rng = np.random.default_rng(0)
    n = ur5_scenario.robot.n
    q, qd, qdd = rng.uniform(-1, 1, (3, n)), rng.normal(size=(3, n)), rng.normal(size=(3, n))
    found = torques_and_derivatives(mmap, q, qd, qdd)
    reference = inverse_dynamics_batch(mmap, q, qd, qdd)
    np.testing.assert_allclose(found.tau, reference.tau, atol=1e-12)
    h = 1e-6
    for arg, derivative in ((0, found.d_q), (1, found.d_qd), (2, found.d_qdd)):
        for i in range(n):
            plus, minus = [q.copy(), qd.copy(), qdd.copy()], [q.copy(), qd.copy(), qdd.copy()]
            plus[arg][:, i] += h
            minus[arg][:, i] -= h
            fd = (
                torques_and_derivatives(mmap, *plus).tau - torques_and_derivatives(mmap, *minus).tau
            ) / (2 * h)
            np.testing.assert_allclose(derivative[:, :, i], fd, atol=1e-7)


def test_min_acceleration_of_a_quintic_is_its_closed_form(worked_scenario):
    """int |qddot|^2 dt of q0 + dq (10 s^3 - 15 s^4 + 6 s^5) is (120/7) dq^2 / T^3, exactly."""
    problem = worked_problem(worked_scenario, {"q2": 1})  # beta = 0: the plain quintic
    travel = problem.family.goal - problem.family.start
    expected = 120.0 / 7.0 * float(travel @ travel) / problem.duration**3
    found = ff.MinAcceleration().evaluate(problem, np.zeros(1)).value
    assert found == pytest.approx(expected, rel=1e-14)


def test_effort_scales_as_inverse_cube_of_duration(worked_scenario):
    """Independent truth: torques of the path run in T seconds, integrated in seconds."""
    beta = np.array([0.3, -0.2, 0.5, 0.1])
    problem = worked_problem(worked_scenario, {"q1": 2, "q2": 2})
    x, w = np.polynomial.legendre.leggauss(80)
    values = []
    for duration in (4.0, 10.0, 25.0):
        t = 0.5 * duration * (x + 1.0)
        path = problem.family.at_times(beta, t, duration)  # rad, rad/s, rad/s^2
        tau = inverse_dynamics_batch(problem.mmap, path.q, path.qd, path.qdd).tau
        direct = 0.5 * duration * float(w @ (tau**2).sum(axis=1))
        objective = ff.MinEffort().evaluate(problem.with_duration(duration), beta).value
        assert objective == pytest.approx(direct, rel=1e-10)
        values.append(direct * duration**3)
    np.testing.assert_allclose(values, values[0], rtol=1e-10)


def test_effort_quadrature_is_converged(worked_scenario):
    problem = worked_problem(worked_scenario, {"q1": 2, "q2": 2})
    beta = np.array([0.3, -0.2, 0.5, 0.1])
    objective = ff.MinEffort()
    value = objective.evaluate(problem, beta).value
    assert objective.error_estimate(problem, beta) < 1e-9 * value
    assert ff.MinEffort(nodes=256).evaluate(problem, beta).value == pytest.approx(value, rel=1e-9)


@pytest.fixture(scope="module")
def effort_plans(worked_scenario):
    return ff.plan(worked_scenario), ff.plan(worked_scenario, objective="min_effort")


def test_min_effort_lowers_the_effort_and_keeps_the_attitude_exact(effort_plans):
    plain, best = effort_plans
    assert plain.objective.name == "min_norm"
    assert best.objective.name == "min_effort"
    assert best.base.attitude_error_rad < 1e-9
    assert best.objective.value < 0.8 * best.objective.start_value
    assert sum(best.solver.freedom.values()) > sum(plain.solver.freedom.values())
    # the recorded value against the plan's own torque table (Simpson, independent grid)
    from scipy.integrate import simpson

    # (error estimated by Simpson on every other sample: the error falls as h^4)
    for p, value in ((plain, best.objective.start_value), (best, best.objective.value)):
        squared, t = (np.asarray(p.samples.tau) ** 2).sum(axis=1), np.asarray(p.samples.t)
        fine, coarse = simpson(squared, x=t), simpson(squared[::2], x=t[::2])
        assert abs(fine - value) <= abs(fine - coarse) / 15.0 * 2.0 + 1e-12 * value


def test_a_longer_duration_gives_the_same_best_path(worked_scenario, effort_plans):
    _, best = effort_plans
    slower = ff.plan(dataclasses.replace(worked_scenario, duration=20.0), objective="min_effort")
    # the minimisation runs at T = 1 s: the same path to rounding, whatever the duration
    assert slower.solver.freedom == best.solver.freedom
    assert slower.objective.value == pytest.approx(best.objective.value / 8.0, rel=1e-12)
    s = np.linspace(0.0, 1.0, 11)
    np.testing.assert_allclose(
        slower.joint_positions(20.0 * s), best.joint_positions(10.0 * s), atol=1e-12
    )


@pytest.mark.parametrize("name", ["min_acceleration", "min_length"])
def test_other_objectives_plan_and_do_not_lose_to_min_norm(worked_scenario, name):
    p = ff.plan(worked_scenario, objective=name)
    assert p.objective.value <= p.objective.start_value


def test_fixed_freedom_is_kept(worked_scenario):
    fixed = dataclasses.replace(worked_scenario, extra={"q1": 2, "q2": 2}, raise_freedom=False)
    p = ff.plan(fixed, objective="min_effort")
    assert p.solver.freedom == {"q1": 2, "q2": 2}
    assert [level.freedom for level in p.objective.levels] == [{"q1": 2, "q2": 2}]


def test_plan_file_keeps_the_objective(tmp_path, effort_plans):
    _, best = effort_plans
    path = best.save(tmp_path / "p.json")
    loaded = ff.Plan.load(path)
    assert loaded.objective == best.objective
    assert ff.Plan.from_dict({**best.to_dict(), "objective": None} | {}).objective.name == (
        "min_norm"
    )


def test_scenario_objective_errors(tmp_path):
    text = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    path = tmp_path / "s.toml"
    path.write_text(text.replace("[path]", '[path]\nobjective = "fastest"'))
    with pytest.raises(ff.ScenarioError) as info:
        ff.Scenario.from_toml(path)
    assert "[path] objective must be one of min_norm, min_effort" in str(info.value)
    path.write_text(text.replace("[path]", "[path]\nraise_freedom = 1"))
    with pytest.raises(ff.ScenarioError, match="raise_freedom must be true or false"):
        ff.Scenario.from_toml(path)
    with pytest.raises(ff.InputError, match="unknown objective 'x'; valid objectives: min_norm"):
        ff.objective_named("x")


def test_cli_objective_flag(tmp_path, capsys):
    scenario = ROOT / "robots" / "scenarios" / "worked_example.toml"
    out = tmp_path / "p.json"
    assert main(["plan", str(scenario), "--objective", "min_acceleration", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "objective       min_acceleration = " in text
    assert "% against the minimum-norm path" in text
    assert ff.Plan.load(out).objective.name == "min_acceleration"
    assert main(["plan", str(scenario), "--objective", "fastest"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "invalid choice: 'fastest'" in err
    assert math.isfinite(ff.Plan.load(out).objective.value)


def test_min_effort_keeps_clear_of_the_hull(tmp_path):
    """The UR5 pan that sweeps into the hull on the quintic path: min_effort keeps 1 cm.

    Truth: exact distances (quadratic programme) from the spacecraft's box to the convex hull
    of each link's STL vertices, which contains the link.
    """
    from freefloat.robot.collision import CollisionModel, known_srdf

    from geometry_truth import box_hull_distance, world_meshes
    from test_collision import ur5_pan_scenario

    scenario = ur5_pan_scenario(tmp_path)
    best = ff.plan(scenario, objective="min_effort")
    assert "clearance" in best.verification  # clearance was a constraint, and checked
    assert best.base.attitude_error_rad < 1e-9
    assert best.objective.value < best.objective.start_value
    model = CollisionModel(scenario.robot, known_srdf(scenario.robot))
    box = np.array([0.3, 0.3, 0.3])  # the servicer's 0.6 m cube, centred on its frame
    links = [i for i, o in enumerate(model.geometry.geometryObjects) if o.parentJoint > 2]
    q = best.joint_positions(np.linspace(0.0, best.duration, 201))
    nearest = min(
        box_hull_distance(np.zeros(3), np.eye(3), box, meshes[i].reshape(-1, 3))
        for meshes in (world_meshes(model, x) for x in q)
        for i in links
        if i in meshes
    )
    assert nearest >= 0.01


def test_verify_recomputes_the_objective(tmp_path, capsys, effort_plans):
    import json

    _, best = effort_plans
    path = best.save(tmp_path / "best.json")
    assert main(["verify", str(path)]) == 0
    capsys.readouterr()
    for field, change in (
        ("value", lambda o: {**o, "value": o["value"] * (1 + 1e-6)}),
        ("error_estimate", lambda o: {**o, "error_estimate": 1.0}),
        ("unit", lambda o: {**o, "unit": "N m"}),
        ("name", lambda o: {**o, "name": "min_acceleration"}),
    ):
        doc = json.loads(path.read_text())
        doc["objective"] = change(doc["objective"])
        tampered = tmp_path / f"{field}.json"
        tampered.write_text(json.dumps(doc))
        assert main(["verify", str(tampered)]) == 2, field
        err = capsys.readouterr().err.strip()
        assert "\n" not in err
        assert "objective." in err, err


def test_a_kept_minimum_norm_path_is_said_on_the_objective_line() -> None:
    """When no freedom level improved on the minimum-norm path (each kept it, with a note),
    the summary says so and why; an objective that improved it says nothing of the kind."""
    from freefloat.problem.objectives.base import Level
    from freefloat.viz.summary import objective_line

    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "worked_example.toml"))
    why = (
        "the minimised path breaks clearance (min clearance -1.17 m (a / b) at t = 3 s, "
        "margin 0.01 m)"
    )
    kept = dataclasses.replace(
        plan.objective,
        name="min_effort",
        value=2.0,
        start_value=2.0,
        levels=[Level({"j1": 1}, 2.0, 4, why), Level({"j1": 2}, 2.0, 3, why)],
    )
    line = objective_line(dataclasses.replace(plan, objective=kept))
    assert "+0.0 % against the minimum-norm path" in line
    assert line.endswith(f"; the minimum-norm path kept: {why}")
    improved = dataclasses.replace(
        kept, value=1.0, levels=[Level({"j1": 1}, 1.0, 4), kept.levels[0]]
    )
    assert "kept" not in objective_line(dataclasses.replace(plan, objective=improved))
