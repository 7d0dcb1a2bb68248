"""The batched zero-momentum base rate against Pinocchio, one configuration at a time."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.physics.centroidal_batch import BatchedCentroidal
from freefloat.physics.momentum import MomentumMap

import urdfs
from conftest import ROOT

SCENARIOS = ROOT / "robots" / "scenarios"

#: Slanted axes: a continuous joint, a prismatic one and a revolute one (an unaligned each).
MIXED = urdfs.spatial_arm(
    kinds=("continuous", "prismatic", "revolute"),
    axes=((0, 0.6, 0.8), (0.6, 0, 0.8), (0.48, 0.6, 0.64)),
)


@pytest.fixture(scope="module", params=["panda", "dual_ur5", "mixed", "slider"])
def robot(request, tmp_path_factory) -> ff.Robot:
    if request.param == "panda":
        return ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml").robot
    if request.param == "dual_ur5":
        return ff.Scenario.from_toml(SCENARIOS / "dual_ur5_servicer.toml").robot
    path = tmp_path_factory.mktemp("arm") / f"{request.param}.urdf"
    path.write_text(MIXED if request.param == "mixed" else urdfs.slider_arm())
    robot = ff.load_robot(path)
    kinds = {joint.kind for joint in robot.joints}
    assert kinds >= ({"continuous", "prismatic"} if request.param == "mixed" else {"prismatic"})
    return robot


def _samples(robot: ff.Robot, count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Joint values within the limits (continuous joints over a full turn) and joint rates."""
    rng = np.random.default_rng(seed)
    lower = np.array([j.lower if math.isfinite(j.lower) else -math.pi for j in robot.joints])
    upper = np.array([j.upper if math.isfinite(j.upper) else math.pi for j in robot.joints])
    joints = rng.uniform(lower, upper, (count, robot.n))
    return joints, rng.uniform(-1.0, 1.0, (count, robot.n))


def _pinocchio_rates(robot: ff.Robot, joints: np.ndarray, rates: np.ndarray) -> tuple:
    """(K, 3) omega and (K, 3, N) F1 from Pinocchio's centroidal map, one instant at a time."""
    model, data, mmap = robot.model, robot.model.createData(), MomentumMap(robot)
    columns = [joint.idx_v for joint in robot.joints]
    f1 = np.empty((len(joints), 3, robot.n))
    for k, q in enumerate(mmap.configurations(joints)):
        ag = pin.computeCentroidalMap(model, data, q)
        f1[k] = -np.linalg.solve(ag[:, :6], ag[:, columns])[3:6]
    return np.einsum("kij,kj->ki", f1, rates), f1


def _pinocchio_derivative(robot: ff.Robot, joints: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """(K, 3, N) d omega / dq from Pinocchio's centroidal map and derivatives, one at a time.

    At the zero-momentum base twist ``v``, ``d omega / dq = -I_c^-1 dh/dq[3:6, joints]`` (the
    base block of the map is block triangular with ``I_c`` its angular corner).
    """
    model, data, mmap = robot.model, robot.model.createData(), MomentumMap(robot)
    out = np.empty((len(joints), 3, robot.n))
    for k, q in enumerate(mmap.configurations(joints)):
        ag = pin.computeCentroidalMap(model, data, q)
        base = np.linalg.solve(ag[:, :6], -ag[:, 6:] @ rates[k])  # zero total momentum
        v = np.concatenate([base, rates[k]])
        dh = pin.computeCentroidalDynamicsDerivatives(model, data, q, v, np.zeros(model.nv))[0]
        columns = [joint.idx_v for joint in robot.joints]
        out[k] = -np.linalg.solve(ag[3:6, 3:6], dh[3:6][:, columns])
    return out


def _close(got: np.ndarray, want: np.ndarray, rtol: float) -> None:
    """Agreement to ``rtol`` of the largest entry (entries near zero have no relative scale)."""
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=0.0, atol=rtol * np.abs(want).max())


def test_rates_and_map_are_pinocchios(robot):
    joints, rates = _samples(robot, 40, 1)
    omega, f1 = _pinocchio_rates(robot, joints, rates)
    got = BatchedCentroidal(robot).base_rates(joints, rates)
    _close(got.omega, omega, 1e-12)
    _close(got.f1, f1, 1e-12)
    assert got.domega_dq is None
    # the momentum map's rates are these, the same bits with or without derivatives
    used = MomentumMap(robot).base_rates(joints, rates)
    np.testing.assert_array_equal(used.omega, got.omega)
    with_derivatives = MomentumMap(robot).base_rates(joints, rates, derivatives=True)
    np.testing.assert_array_equal(with_derivatives.omega, got.omega)
    # the verification's rates (Pinocchio's map, another formula) agree
    _close(MomentumMap(robot).pinocchio_rates(joints, rates), got.omega, 1e-12)


def test_derivative_is_pinocchios(robot):
    joints, rates = _samples(robot, 40, 2)
    got = BatchedCentroidal(robot).base_rates(joints, rates, derivatives=True)
    assert got.domega_dq is not None
    _close(got.domega_dq, _pinocchio_derivative(robot, joints, rates), 1e-10)
    _close(got.omega, _pinocchio_rates(robot, joints, rates)[0], 1e-12)
    # the momentum map's own derivatives are these
    used = MomentumMap(robot).base_rates(joints, rates, derivatives=True)
    assert used.domega_dq is not None
    np.testing.assert_array_equal(used.domega_dq, got.domega_dq)


def test_derivative_is_the_finite_difference_of_pinocchios_rates(robot):
    """Central differences (step 1e-6 rad or m) of Pinocchio's omega, one joint at a time."""
    joints, rates = _samples(robot, 12, 3)
    step = 1e-6
    got = BatchedCentroidal(robot).base_rates(joints, rates, derivatives=True).domega_dq
    assert got is not None
    want = np.empty_like(got)
    for i in range(robot.n):
        shift = np.zeros(robot.n)
        shift[i] = step
        ahead = _pinocchio_rates(robot, joints + shift, rates)[0]
        behind = _pinocchio_rates(robot, joints - shift, rates)[0]
        want[:, :, i] = (ahead - behind) / (2.0 * step)
    _close(got, want, 1e-6)


def test_one_configuration_and_the_shipped_grid():
    """A single joint vector is a batch of one; the Panda plan grid (K nodes) agrees too."""
    scenario = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")
    problem = ff.problem_from_scenario(scenario)
    _, q0, qs0, dq, dqs = problem._grid
    beta = 0.05 * np.random.default_rng(4).standard_normal(problem.n_free)
    joints, rates = q0 + dq @ beta, qs0 + dqs @ beta
    batch = BatchedCentroidal(scenario.robot)
    got = batch.base_rates(joints, rates, True)
    assert got.domega_dq is not None
    _close(got.domega_dq, _pinocchio_derivative(scenario.robot, joints, rates), 1e-10)
    single = batch.base_rates(joints[5], rates[5], True)
    assert single.omega.shape == (1, 3) and single.f1.shape == (1, 3, scenario.robot.n)
    np.testing.assert_allclose(single.omega[0], got.omega[5], rtol=1e-14, atol=1e-16)


def test_a_heavy_spacecraft_and_a_badly_conditioned_inertia(tmp_path):
    """A 1e6 kg base under a light arm agrees with Pinocchio; an inertia whose principal
    moments span 1e8 is inverted by LAPACK (the cofactors would lose six digits)."""
    from freefloat.physics.centroidal_batch import _inverse

    path = tmp_path / "heavy.urdf"
    path.write_text(urdfs.spatial_arm(base_mass=1e6))
    robot = ff.load_robot(path)
    joints, rates = _samples(robot, 10, 8)
    got = BatchedCentroidal(robot).base_rates(joints, rates, derivatives=True)
    assert got.domega_dq is not None
    _close(got.omega, _pinocchio_rates(robot, joints, rates)[0], 1e-11)
    _close(got.domega_dq, _pinocchio_derivative(robot, joints, rates), 1e-9)
    rotation = np.linalg.qr(np.random.default_rng(9).normal(size=(3, 3)))[0]
    matrix = rotation @ np.diag([1e4, 1.0, 1e-4]) @ rotation.T
    inverse = _inverse(np.repeat(matrix[:, :, None], 4, axis=2))[:, :, 0]
    np.testing.assert_allclose(matrix @ inverse, np.eye(3), rtol=0.0, atol=1e-9)
