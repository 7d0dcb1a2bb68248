"""Quaternions, Euler angles and the Magnus integrator against independent references."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from freefloat.physics import attitude as att


@pytest.mark.parametrize("seed", range(5))
def test_zyx_matches_pinocchio_rpy(seed):
    rng = np.random.default_rng(seed)
    yaw, pitch, roll = rng.uniform(-3, 3), rng.uniform(-1.5, 1.5), rng.uniform(-3, 3)
    quat = att.quat_from_zyx(yaw, pitch, roll)
    # Pinocchio's rpyToMatrix(r, p, y) = Rz(y) Ry(p) Rx(r): the same ZYX convention.
    expected = pin.rpy.rpyToMatrix(roll, pitch, yaw)
    np.testing.assert_allclose(att.quat_to_matrix(quat), expected, atol=1e-14)
    np.testing.assert_allclose(att.zyx_from_quat(quat), [yaw, pitch, roll], atol=1e-12)


@pytest.mark.parametrize("pitch", [math.pi / 2, -math.pi / 2])
def test_gimbal_lock_round_trip_keeps_the_attitude(pitch):
    quat = att.quat_from_zyx(0.7, pitch, 0.3)
    angles = att.zyx_from_quat(quat)
    assert angles[1] == pytest.approx(pitch)
    assert att.geodesic_angle(att.quat_from_zyx(*angles), quat) < 1e-7


def test_geodesic_angle_on_floats_is_the_quaternion_products():
    """Against the angle of ``conj(a) (x) b`` by the batched numpy product and SciPy's
    rotation magnitude, on random attitudes (lists too), tiny and near-pi rotations."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(4)
    a = rng.standard_normal((40, 4))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    turns = np.vstack([rng.standard_normal((20, 3)), 1e-9 * rng.standard_normal((10, 3))])
    turns[:10] *= 3.1 / np.linalg.norm(turns[:10], axis=1, keepdims=True)  # near pi
    b = np.vstack([att.quat_multiply(a[:30], att.quat_exp(turns)), -a[30:]])
    rel = att.quat_multiply(att.quat_conjugate(a), b)
    products = 2.0 * np.arctan2(np.linalg.norm(rel[:, :3], axis=1), np.abs(rel[:, 3]))
    scipy = (Rotation.from_quat(a).inv() * Rotation.from_quat(b)).magnitude()
    got = np.array([att.geodesic_angle(x, y) for x, y in zip(a, b, strict=True)])
    np.testing.assert_allclose(got, products, rtol=1e-15, atol=1e-16)
    np.testing.assert_allclose(got, scipy, rtol=1e-12, atol=1e-15)
    assert got[30:].max() < 1e-15  # the same attitude, the other sign
    assert att.geodesic_angle(a[0].tolist(), b[0].tolist()) == got[0]


def test_geodesic_angle_and_log_exp():
    a = att.quat_from_zyx(0.1, 0.2, 0.3)
    rotvec = np.array([0.3, -0.2, 0.5])
    b = att.quat_multiply(a, att.quat_exp(rotvec))
    assert att.geodesic_angle(a, b) == pytest.approx(np.linalg.norm(rotvec), abs=1e-15)
    assert att.geodesic_angle(a, -a) == pytest.approx(0.0, abs=1e-15)  # double cover
    np.testing.assert_allclose(att.quat_log(att.quat_exp(rotvec)), rotvec, atol=1e-15)
    np.testing.assert_allclose(att.quat_log(att.quat_exp(1e-9 * rotvec)), 1e-9 * rotvec, atol=1e-24)


def _omega(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return np.stack([np.sin(3 * t) + 0.5, np.cos(2 * t) * t, 1.5 * np.exp(-t) - 0.2 * t], -1)


def _reference(quat0: np.ndarray) -> np.ndarray:
    def rhs(_t, y):
        w = _omega(np.array(_t))
        return 0.5 * att.quat_multiply(y, np.concatenate([w, [0.0]]))

    sol = solve_ivp(rhs, (0.0, 2.0), quat0, method="DOP853", rtol=1e-13, atol=1e-14)
    end = sol.y[:, -1]
    return end / np.linalg.norm(end)


def _magnus(quat0: np.ndarray, steps: int) -> np.ndarray:
    nodes, h = att.step_nodes(np.linspace(0.0, 2.0, steps + 1))
    return att.propagate(quat0, att.magnus_increments(_omega(nodes).reshape(-1, 3, 3), h))[-1]


def test_magnus_matches_an_adaptive_reference():
    quat0 = att.quat_from_zyx(0.3, -0.2, 0.1)
    assert att.geodesic_angle(_magnus(quat0, 200), _reference(quat0)) < 1e-11


def test_magnus_is_sixth_order():
    quat0 = att.IDENTITY
    exact = _magnus(quat0, 2000)
    e1 = att.geodesic_angle(_magnus(quat0, 10), exact)
    e2 = att.geodesic_angle(_magnus(quat0, 20), exact)
    assert math.log2(e1 / e2) == pytest.approx(6.0, abs=0.6)


def test_fixed_axis_reduces_to_gauss_legendre():
    nodes, h = att.step_nodes(np.linspace(0.0, 1.0, 5))
    rates = np.zeros((len(nodes), 3))
    rates[:, 2] = np.cos(4 * nodes)
    inc = att.magnus_increments(rates.reshape(-1, 3, 3), h)
    quad = np.sum(h[:, None] * att.GAUSS3_WEIGHTS * rates[:, 2].reshape(-1, 3), axis=1)
    np.testing.assert_allclose(inc[:, 2], quad, atol=1e-16)
    assert np.abs(inc[:, :2]).max() == 0.0


def test_relative_rotation_against_scipy_and_pinocchio():
    """``relative_rotvec(a, b)`` is SciPy's rotation vector of ``inv(a) b`` and Pinocchio's
    ``log3`` of ``R(a)^T R(b)``; ``relative_quat`` turns ``a`` into ``b`` (batched rows too)."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(11)
    a = rng.standard_normal((30, 4))
    b = rng.standard_normal((30, 4))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    got = att.relative_rotvec(a, b)
    expected = (Rotation.from_quat(a).inv() * Rotation.from_quat(b)).as_rotvec()
    np.testing.assert_allclose(got, expected, atol=1e-12)
    for qa, qb, rotvec in zip(a, b, got, strict=True):
        r_a, r_b = Rotation.from_quat(qa).as_matrix(), Rotation.from_quat(qb).as_matrix()
        np.testing.assert_allclose(rotvec, pin.log3(r_a.T @ r_b), atol=1e-10)
    turned = att.quat_multiply(a, att.relative_quat(a, b))
    np.testing.assert_allclose(turned * np.sign(turned[:, 3:] * b[:, 3:]), b, atol=1e-14)
