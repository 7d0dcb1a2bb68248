"""Polynomial joint paths: the orthonormal basis, boundary conditions, derivatives, time scaling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate
from scipy.special import eval_jacobi

from freefloat.problem.basis import basis_chebyshev, basis_scale
from freefloat.problem.paths import JointPolynomials, PathFamily, excursions
from freefloat.verify.path_records import monomial_basis


def _quintic(start, goal, s):
    """The quintic blend, written out (rad)."""
    return start + (goal - start) * (10 * s**3 - 15 * s**4 + 6 * s**5)


def test_basis_is_orthonormal_and_keeps_the_end_conditions():
    count = 26
    table = basis_chebyshev(count)
    cheb = np.polynomial.chebyshev
    # Independent reference: scipy's Jacobi polynomials, the closed-form factor, adaptive
    # quadrature for the inner products of a few pairs.
    for n in (0, 3, 11, 25):
        for m in (0, 4, n):
            value, _ = integrate.quad(
                lambda s, n=n, m=m: math.prod(
                    basis_scale(k) * s**3 * (1 - s) ** 3 * eval_jacobi(k, 6, 6, 2 * s - 1)
                    for k in (n, m)
                ),
                0.0,
                1.0,
                epsabs=1e-13,
                limit=200,
            )
            assert value == pytest.approx(float(n == m), abs=1e-10)
    x = np.linspace(-1, 1, 7)
    for n in range(count):
        s = 0.5 * (x + 1)
        want = basis_scale(n) * s**3 * (1 - s) ** 3 * eval_jacobi(n, 6, 6, x)
        np.testing.assert_allclose(cheb.chebval(x, table[n]), want, atol=1e-12)
        for order in range(3):
            d = cheb.chebder(table[n], order) if order else table[n]
            size = 1e-13 * max(1.0, float(np.abs(d).sum()))  # rounding of the coefficients
            assert abs(cheb.chebval(-1.0, d)) < size and abs(cheb.chebval(1.0, d)) < size


def test_norm_of_free_parameters_is_the_integrated_squared_deviation():
    rng = np.random.default_rng(3)
    start, goal = np.array([0.2, -1.0, 0.5]), np.array([1.0, 0.3, 0.5])
    family = PathFamily(start, goal, (5, 12, 25))
    beta = rng.normal(scale=0.3, size=family.n_free)
    path = family.polynomials(beta, 7.0)

    def squared(s: float) -> float:
        q = path.evaluate(np.array([7.0 * s])).q[0]
        return float(np.sum((q - _quintic(start, goal, s)) ** 2))

    integral, error = integrate.quad(squared, 0.0, 1.0, epsabs=1e-13, epsrel=1e-12, limit=500)
    assert error < 1e-9 * integral
    assert float(beta @ beta) == pytest.approx(integral, rel=1e-9)


def _gram(values: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return (values * weights[:, None]).T @ values


def test_conditioning_up_to_degree_25():
    """Gram matrices (L2 on [0, 1]) of the free basis, this one and the monomial one before it."""
    x, w = np.polynomial.legendre.leggauss(40)
    s, w = 0.5 * (x + 1), 0.5 * w
    report = []
    for degree in (8, 12, 16, 20, 25):
        family = PathFamily(np.zeros(1), np.ones(1), (degree,))
        values = family.affine_samples(s).dq[:, 0, :]
        new = np.linalg.cond(_gram(values, w))
        old_values = np.stack(
            [np.polynomial.polynomial.polyval(s, monomial_basis(p)) for p in range(6, degree + 1)],
            axis=1,
        )
        old = np.linalg.cond(_gram(old_values, w))
        report.append(f"degree {degree}: orthonormal {new:.3g}, monomial {old:.3g}")
        assert new < 1 + 1e-9
    print("; ".join(report))
    assert old > 1e15  # the old basis was numerically singular at degree 25


def test_family_boundary_conditions_and_derivatives():
    family = PathFamily(np.array([0.2, -1.0, 0.5]), np.array([1.0, 0.3, 0.5]), (5, 7, 27))
    rng = np.random.default_rng(0)
    beta = rng.normal(size=family.n_free)
    T = 60.0
    t = np.linspace(0.0, T, 7)
    at = family.at_times(beta, t, T)
    np.testing.assert_allclose(at.q[0], family.start, atol=1e-14)
    np.testing.assert_allclose(at.q[-1], family.goal, atol=1e-13)
    np.testing.assert_allclose(at.qd[[0, -1]] * T, 0.0, atol=1e-11)
    np.testing.assert_allclose(at.qdd[[0, -1]] * T**2, 0.0, atol=1e-9)
    # Derivatives against central differences in time.
    eps = 1e-4
    mid = np.array([21.1])
    plus, minus = family.at_times(beta, mid + eps, T), family.at_times(beta, mid - eps, T)
    here = family.at_times(beta, mid, T)
    np.testing.assert_allclose((plus.q - minus.q) / (2 * eps), here.qd, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose((plus.qd - minus.qd) / (2 * eps), here.qdd, rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("width", [1, 2, 6, 12, 28])
def test_every_derivative_is_the_series_differentiated_in_time(width):
    """Each order against numpy's own Chebyshev differentiation and, in time, against the
    monomial form differentiated term by term (two other routes)."""
    rng = np.random.default_rng(width)
    duration = 37.0
    path = JointPolynomials(rng.normal(size=(3, width)), duration)
    below = path.coefficients.T
    t = np.linspace(0.0, duration, 9)
    for order in range(width + 2):
        expected = np.zeros((3, width))
        if order < width:
            series = np.polynomial.chebyshev.chebder(below, order, scl=2.0 / duration)
            expected[:, : width - order] = np.asarray(series).T
        got = path.derivative(order)
        scale = max(1.0, float(np.abs(expected).max()))
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13 * scale, err_msg=str(order))
    np.testing.assert_array_equal(path.positions(t), path.evaluate(t).q)
    if width <= 12:  # monomials in t lose digits to cancellation beyond
        monomials = path.monomials()
        x = 2.0 * t / duration - 1.0
        vander = np.polynomial.chebyshev.chebvander(x, width - 1)
        for order in range(3):
            in_t = [np.polynomial.Polynomial(c).deriv(order)(t) for c in monomials]
            np.testing.assert_allclose(
                vander @ path.derivative(order).T, np.array(in_t).T, rtol=1e-8, atol=1e-9
            )


def test_projection_and_monomials_round_trip():
    family = PathFamily(np.array([0.0, 1.0]), np.array([1.0, -2.0]), (6, 9))
    beta = np.array([3.0, -2.0, 5.0, 0.5, -1.0])
    path = family.polynomials(beta, 4.0)
    np.testing.assert_allclose(family.beta_from_path(path), beta, atol=1e-13)
    again = JointPolynomials.from_monomials(path.monomials().tolist(), 4.0)
    np.testing.assert_allclose(again.coefficients, path.coefficients, atol=1e-12)
    np.testing.assert_allclose(family.beta_from_path(again), beta, atol=1e-11)


def test_extremes_and_excursions_match_dense_sampling():
    rng = np.random.default_rng(5)
    start, goal = np.array([0.0, 1.0, -0.3]), np.array([1.0, -2.0, -0.3])
    family = PathFamily(start, goal, (9, 14, 20))
    beta = rng.normal(scale=0.5, size=family.n_free)
    path = family.polynomials(beta, 30.0)
    dense = path.evaluate(np.linspace(0, 30.0, 200001)).q
    beyond = np.maximum.reduce(
        [
            np.zeros(3),
            dense.max(axis=0) - np.maximum(start, goal),
            np.minimum(start, goal) - dense.min(axis=0),
        ]
    )
    np.testing.assert_allclose(excursions(path, start, goal), beyond, atol=1e-8)
    assert beyond[2] > 0  # a joint that should not move at all moves


def test_linear_map_matches_evaluation():
    family = PathFamily(np.array([0.1, 0.4]), np.array([-0.3, 1.2]), (6, 8))
    s = np.linspace(0, 1, 11)
    base, dq, dqs = family.linear_map(s)
    beta = np.array([1.5, -0.5, 0.25, 2.0])
    direct = family.evaluate(beta, s)
    np.testing.assert_allclose(base.q + dq @ beta, direct.q, atol=1e-14)
    np.testing.assert_allclose(base.qd + dqs @ beta, direct.qd, atol=1e-13)


def test_embedding_keeps_the_path():
    small = PathFamily(np.zeros(2), np.ones(2), (7, 6))
    large = PathFamily(np.zeros(2), np.ones(2), (12, 10))
    beta = np.array([0.3, -0.2, 0.7])
    s = np.linspace(0, 1, 9)
    carried = large.embed(small, beta)
    np.testing.assert_allclose(large.evaluate(carried, s).q, small.evaluate(beta, s).q, atol=1e-14)
