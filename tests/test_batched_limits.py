"""Batched limit checks and the scaled minimisation, against truth computed another way.

- joint torques alone (base rows of the inertia from the centroidal map) against the
  centroidal-rate inverse dynamics, their base twist too, and against Pinocchio's forward
  dynamics (ABA), which they must drive along the motion;
- the CM read from the centroidal maps against Pinocchio's, at any base pose;
- the effort peaks of a 7-joint servicer against dense per-instant inverse dynamics and
  SciPy's bounded Brent search about each dense peak;
- every joint's polynomial extremes at once against brute-force dense evaluation;
- the scaled coordinates of the minimisation: the Hessian of a quadratic objective there is
  the identity, by finite differences of its gradient.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import minimize_scalar

import freefloat as ff
from freefloat.physics.attitude import quat_to_matrix
from freefloat.physics.dynamics import centre_of_mass, inverse_dynamics, inverse_dynamics_batch
from freefloat.physics.joint_torques import joint_torques_and_twist, joint_torques_batch
from freefloat.problem.objectives import objective_named
from freefloat.problem.paths import JointPolynomials
from freefloat.solvers.scaled import scaled_coordinates

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "robots" / "scenarios"


@pytest.fixture(scope="module")
def panda_plan() -> tuple[ff.Scenario, ff.Plan]:
    scenario = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")
    return scenario, ff.plan(scenario)


def test_joint_torques_alone_agree_with_the_centroidal_inverse_dynamics():
    scenario = ff.Scenario.from_toml(SCENARIOS / "dual_ur5_servicer.toml")
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    beta = 0.3 * np.random.default_rng(3).standard_normal(problem.n_free)
    path = problem.polynomials(beta)
    samples = path.evaluate(np.linspace(0.0, path.duration, 57))
    mmap = ff.MomentumMap(scenario.robot)
    fast = joint_torques_batch(mmap, samples.q, samples.qd, samples.qdd)
    other = inverse_dynamics_batch(mmap, samples.q, samples.qd, samples.qdd)
    scale = np.abs(other.tau).max()
    assert scale > 0.0
    np.testing.assert_allclose(fast, other.tau, rtol=0.0, atol=1e-12 * scale)


@pytest.mark.parametrize("name", ["worked_example", "dual_ur5_servicer"])
def test_joint_torques_come_with_the_base_twist_and_drive_the_forward_dynamics(name):
    """The twist equals the inverse dynamics' to rounding; ABA driven by the torques (base
    unforced) gives back the joint accelerations and a momentum rate of zero."""
    scenario = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    beta = 0.3 * np.random.default_rng(5).standard_normal(problem.n_free)
    samples = problem.polynomials(beta).evaluate(np.linspace(0.0, problem.duration, 23))
    mmap = ff.MomentumMap(scenario.robot)
    found = joint_torques_and_twist(mmap, samples.q, samples.qd, samples.qdd)
    tau, twist = found.tau, found.twist
    other = inverse_dynamics_batch(mmap, samples.q, samples.qd, samples.qdd)
    np.testing.assert_allclose(tau, joint_torques_batch(mmap, samples.q, samples.qd, samples.qdd))
    np.testing.assert_allclose(twist, other.base_twist, rtol=0.0, atol=1e-13)
    model, data = mmap.model, mmap.model.createData()
    jv = [j.idx_v for j in scenario.robot.joints]
    for k, config in enumerate(mmap.configurations(samples.q)):
        v = np.zeros(model.nv)
        v[:6], v[jv] = twist[k], samples.qd[k]
        force = np.zeros(model.nv)
        force[jv] = tau[k]
        a = pin.aba(model, data, config, v, force)
        scale = 1.0 + np.abs(samples.qdd[k]).max()
        np.testing.assert_allclose(a[jv], samples.qdd[k], rtol=0.0, atol=1e-10 * scale)
        rate = pin.computeCentroidalMomentumTimeVariation(model, data, config, v, a)
        assert np.abs(rate.vector).max() < 1e-10 * scale


def test_the_cm_read_from_the_centroidal_maps_is_pinocchios():
    """At random joints and base poses (turned, moved), to rounding."""
    robot = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml").robot
    model, data = robot.model, robot.model.createData()
    rng = np.random.default_rng(8)
    maps, truth, origins = [], [], []
    for _ in range(12):
        quat = rng.standard_normal(4)
        quat /= np.linalg.norm(quat)
        origin = rng.uniform(-2.0, 2.0, 3)
        config = robot.configuration(rng.uniform(-1.5, 1.5, robot.n), None, quat)
        config[0:3] = origin
        maps.append(pin.computeCentroidalMap(model, data, config).copy())
        truth.append(pin.centerOfMass(model, data, config).copy())
        origins.append(origin)
        assert np.allclose(maps[-1][0:3, 0:3], robot.total_mass * quat_to_matrix(quat))
    got = np.array(origins) + centre_of_mass(np.array(maps))
    np.testing.assert_allclose(got, np.array(truth), rtol=0.0, atol=1e-14)


def test_servicer_effort_peaks_match_a_dense_independent_search(panda_plan):
    scenario, plan = panda_plan
    robot, path = scenario.robot, plan.path()
    peak, where, spread = ff.JointEffortLimits().peaks(robot, path)
    mmap = ff.MomentumMap(robot)

    def tau(t: float) -> np.ndarray:  # one instant at a time, the centroidal-rate formula
        s = path.evaluate(np.array([t]))
        return np.abs(inverse_dynamics(mmap, s.q[0], s.qd[0], s.qdd[0]).tau)

    t = np.linspace(0.0, path.duration, 2001)
    dense = np.array([tau(x) for x in t])
    scale = dense.max()
    assert np.all(peak >= dense.max(axis=0) - 1e-14 * scale)
    step = t[1] - t[0]
    for i in range(robot.n):
        k = int(dense[:, i].argmax())
        best = minimize_scalar(
            lambda x, i=i: -tau(x)[i],
            bounds=(max(0.0, t[k] - step), min(path.duration, t[k] + step)),
            method="bounded",
            options={"xatol": 1e-10},
        )
        truth = max(-best.fun, dense[k, i])
        assert abs(peak[i] - truth) <= spread + 1e-14 * scale
        assert abs(tau(where[i])[i] - peak[i]) <= 1e-14 * scale  # the time is the peak's
    assert spread < 1e-12 * scale


def test_extremes_of_every_joint_match_dense_evaluation():
    rng = np.random.default_rng(7)
    for _ in range(40):
        coefficients = rng.standard_normal((6, 9))
        for row, degree in zip(coefficients, rng.integers(0, 9, 6), strict=True):
            row[degree + 1 :] = 0.0  # joints of different degrees, constants among them
        path = JointPolynomials(coefficients, float(rng.uniform(1.0, 30.0)))
        t = np.linspace(0.0, path.duration, 20001)
        x = 2.0 * t / path.duration - 1.0
        for order in range(3):
            for i in range(6):
                # NumPy's own series derivative and evaluation, densely
                series = np.polynomial.Chebyshev(coefficients[i]).deriv(order)
                gain = (2.0 / path.duration) ** order
                column = gain * series(x)
                (lo, t_lo), (hi, t_hi) = path.extremes(i, order)
                slack = 1e-12 * max(1.0, np.abs(column).max())
                assert lo <= column.min() + slack and hi >= column.max() - slack
                # what the grid can miss: bounded by its largest second difference
                reach = np.abs(np.diff(column, 2)).max() + slack
                assert column.min() - lo <= reach and hi - column.max() <= reach
                at = gain * series(2.0 * np.array([t_lo, t_hi]) / path.duration - 1.0)
                np.testing.assert_allclose(at, [lo, hi], rtol=0.0, atol=slack)


def test_scaled_coordinates_make_a_quadratic_objective_s_hessian_the_identity():
    scenario = ff.Scenario.from_toml(SCENARIOS / "worked_example.toml")
    problem = ff.problem_from_scenario(scenario, extra=[3, 2]).with_duration(1.0)
    objective = objective_named("min_acceleration")
    beta0 = np.full(problem.n_free, 0.05)
    value = objective.evaluate(problem, beta0).value
    s_mat = scaled_coordinates(problem, objective, beta0, value)

    def gradient(z: np.ndarray) -> np.ndarray:  # of J / value in z
        return s_mat.T @ objective.evaluate(problem, beta0 + s_mat @ z).gradient / value

    h = 1e-4
    eye = np.eye(problem.n_free)
    hessian = np.column_stack([(gradient(h * e) - gradient(-h * e)) / (2 * h) for e in eye])
    np.testing.assert_allclose(hessian, eye, atol=1e-5)


def test_rate_rows_left_out_while_far_do_not_change_the_least_effort_path(tmp_path, monkeypatch):
    import freefloat.solvers.optimise as optimise_module

    urdf = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    limit = '<limit effort="100" velocity="1.0" lower="-3.1" upper="3.1"/>'
    (tmp_path / "arm.urdf").write_text(
        urdf.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/>' + limit)
    )
    text = (SCENARIOS / "worked_example.toml").read_text()
    (tmp_path / "s.toml").write_text(text.replace('robot = "planar_2dof"', 'robot = "arm.urdf"'))
    scenario = ff.Scenario.from_toml(tmp_path / "s.toml")
    left_out = ff.plan(scenario, objective="min_effort")  # peak rate 0.46 of 1 rad/s: far
    monkeypatch.setattr(optimise_module, "FAR_FRACTION", 0.0)  # every rate row imposed
    imposed = ff.plan(scenario, objective="min_effort")
    assert left_out.objective.value < 0.7 * left_out.objective.start_value
    assert left_out.objective.value == pytest.approx(imposed.objective.value, rel=1e-12)
    path = left_out.path()
    rates = path.evaluate(np.linspace(0.0, path.duration, 4001)).qd
    assert np.abs(rates).max() < 1.0


@pytest.mark.parametrize("name", ["worked_example", "dual_ur5_servicer", "mixed_arm"])
def test_the_batch_takes_the_map_rate_at_the_joint_rates_alone(name, tmp_path):
    """Along a zero-momentum motion (base at the identity) the rate term of the centroidal
    map at the whole velocity equals the one at the joint rates alone (Pinocchio at both),
    and the batch agrees with the one-instant inverse dynamics, which uses the whole; on
    shipped robots and on an arm with a continuous, a revolute and a prismatic joint."""
    scenario = _scenario_named(name, tmp_path)
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    beta = 0.3 * np.random.default_rng(7).standard_normal(problem.n_free)
    inside = np.linspace(0.05, 0.95, 19) * problem.duration  # moving: not at rest
    samples = problem.polynomials(beta).evaluate(inside)
    mmap = ff.MomentumMap(scenario.robot)
    model, data = mmap.model, mmap.model.createData()
    batch = inverse_dynamics_batch(mmap, samples.q, samples.qd, samples.qdd)
    for k, config in enumerate(mmap.configurations(samples.q)):
        whole = mmap.velocity(samples.q[k], samples.qd[k])
        alone = whole.copy()
        alone[:6] = 0.0
        assert np.abs(whole[:6]).max() > 1e-6  # the base does move
        rate_whole = pin.computeCentroidalMapTimeVariation(model, data, config, whole) @ whole
        rate_alone = pin.computeCentroidalMapTimeVariation(model, data, config, alone) @ whole
        scale = 1.0 + np.abs(rate_whole).max()
        np.testing.assert_allclose(rate_alone, rate_whole, rtol=0.0, atol=1e-12 * scale)
        one = inverse_dynamics(mmap, samples.q[k], samples.qd[k], samples.qdd[k])
        scale = 1.0 + np.abs(one.tau).max()
        np.testing.assert_allclose(batch.tau[k], one.tau, rtol=0.0, atol=1e-11 * scale)


def _scenario_named(name: str, folder: Path) -> ff.Scenario:
    """A shipped scenario, or ``mixed_arm``: a continuous, a revolute and a prismatic joint."""
    if name != "mixed_arm":
        return ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    import urdfs

    urdf = folder / "mixed.urdf"
    urdf.write_text(urdfs.spatial_arm(kinds=("continuous", "revolute", "prismatic")))
    return ff.Scenario(
        robot=ff.load_robot(urdf),
        duration=4.0,
        start_joints={"j1": 0.1, "j2": -0.4, "j3": 0.05},
        goal_joints={"j1": 1.2, "j2": 0.5, "j3": 0.2},
    )
