"""Polynomial joint paths: boundary conditions, derivatives, time scaling."""

from __future__ import annotations

import numpy as np
import pytest

from freefloat.problem.paths import PathFamily, basis_coefficients


@pytest.mark.parametrize("power", [6, 7, 9, 12])
def test_basis_keeps_the_six_boundary_conditions(power):
    c = basis_coefficients(power)
    poly = np.polynomial.polynomial
    for order in range(3):
        d = poly.polyder(c, order) if order else c
        assert abs(poly.polyval(0.0, d)) < 1e-12
        assert abs(poly.polyval(1.0, d)) < 1e-12
    assert c[power] == 1.0


def test_family_boundary_conditions_and_derivatives():
    family = PathFamily(np.array([0.2, -1.0, 0.5]), np.array([1.0, 0.3, 0.5]), (5, 7, 8))
    assert family.n_free == 2 + 3
    beta = np.array([0.7, -1.3, 2.0, 0.1, -0.4])
    T = 3.0
    t = np.linspace(0.0, T, 7)
    at = family.at_times(beta, t, T)
    np.testing.assert_allclose(at.q[0], family.start, atol=1e-15)
    np.testing.assert_allclose(at.q[-1], family.goal, atol=1e-13)
    for arr in (at.qd, at.qdd):
        np.testing.assert_allclose(arr[[0, -1]], 0.0, atol=1e-12)
    # Derivatives against central differences in time.
    eps = 1e-6
    mid = np.array([1.1])
    plus, minus = family.at_times(beta, mid + eps, T), family.at_times(beta, mid - eps, T)
    here = family.at_times(beta, mid, T)
    np.testing.assert_allclose((plus.q - minus.q) / (2 * eps), here.qd, rtol=1e-7)
    np.testing.assert_allclose((plus.qd - minus.qd) / (2 * eps), here.qdd, rtol=1e-7)


def test_free_parameters_are_time_coefficients():
    family = PathFamily(np.zeros(2), np.ones(2), (6, 7))
    beta = np.array([3.0, -2.0, 5.0])
    T = 4.0
    coeffs = family.time_coefficients(beta, T)
    free = family.free_time_coefficients(beta, T)
    assert free[0] == [coeffs[0][6]]
    assert free[1] == [coeffs[1][6], coeffs[1][7]]
    np.testing.assert_allclose(family.beta_from_time_coefficients(free, T), beta)


def test_linear_map_matches_evaluation():
    family = PathFamily(np.array([0.1, 0.4]), np.array([-0.3, 1.2]), (6, 8))
    s = np.linspace(0, 1, 11)
    base, dq, dqs = family.linear_map(s)
    beta = np.array([1.5, -0.5, 0.25, 2.0])
    direct = family.evaluate(beta, s)
    np.testing.assert_allclose(base.q + dq @ beta, direct.q, atol=1e-14)
    np.testing.assert_allclose(base.qd + dqs @ beta, direct.qd, atol=1e-13)
