"""The verification's fifth-order Runge-Kutta method (``freefloat.physics.runge_kutta``).

Truths: Butcher's order conditions in exact rational arithmetic, and SciPy's DOP853 on a
quaternion equation whose rates do not commute (a fixed axis would hide the order of the
matrix products).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy.integrate import solve_ivp

from freefloat.physics.attitude import geodesic_angle, ordered_product, quat_multiply
from freefloat.physics.runge_kutta import QUARTERS, STAGE_MATRIX, WEIGHTS, step_matrices


def _exact(values: np.ndarray) -> np.ndarray:
    """The entries as fractions (denominators up to 100), each equal to its float."""
    out = np.array([Fraction(float(v)).limit_denominator(100) for v in values.ravel()], object)
    assert all(float(f) == float(v) for f, v in zip(out, values.ravel(), strict=True))
    return out.reshape(values.shape)


def test_the_tableau_meets_every_order_condition_up_to_five_and_not_six() -> None:
    a, b = _exact(STAGE_MATRIX), _exact(WEIGHTS)
    one = np.array([Fraction(1)] * len(b), object)
    c = a.dot(one)
    assert list(c) == [Fraction(q, 4) for q in QUARTERS]  # the stages on the quarters

    def power(k: int) -> np.ndarray:
        return np.array([x**k for x in c], object)

    ac, ac2, ac3 = a.dot(c), a.dot(power(2)), a.dot(power(3))
    conditions = {  # sum of b times the tree's elementary weight = 1 / the tree's density
        (1,): (one, 1),
        (2,): (c, 2),
        (3, 1): (power(2), 3),
        (3, 2): (ac, 6),
        (4, 1): (power(3), 4),
        (4, 2): (c * ac, 8),
        (4, 3): (ac2, 12),
        (4, 4): (a.dot(ac), 24),
        (5, 1): (power(4), 5),
        (5, 2): (power(2) * ac, 10),
        (5, 3): (c * ac2, 15),
        (5, 4): (c * a.dot(ac), 30),
        (5, 5): (ac * ac, 20),
        (5, 6): (ac3, 20),
        (5, 7): (a.dot(c * ac), 40),
        (5, 8): (a.dot(ac2), 60),
        (5, 9): (a.dot(a.dot(ac)), 120),
    }
    for tree, (weight, density) in conditions.items():
        assert b.dot(weight) == Fraction(1, density), tree
    assert b.dot(a.dot(a.dot(a.dot(ac)))) != Fraction(1, 720)  # not sixth order (1/640)


def test_step_matrices_are_fifth_order_on_rates_that_do_not_commute() -> None:
    """``omega(t) = [sin 3t, cos 2t, t / 2]`` (rad/s, body frame) for 2 s, against DOP853
    (rtol 1e-13): within 1e-5 rad on 8 steps, the error falling more than 20-fold per
    doubling (a method of lower order, or the matrix products in the wrong order, falls
    less)."""

    def omega(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.stack([np.sin(3.0 * t), np.cos(2.0 * t), 0.5 * t], axis=-1)

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return 0.5 * quat_multiply(y, np.append(omega(t), 0.0))

    start, duration = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9]), 2.0
    end = solve_ivp(rhs, (0.0, duration), start, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
    end /= np.linalg.norm(end)
    errors = []
    for steps in (8, 16, 32):
        h = duration / steps
        stages = (np.arange(steps)[:, None] + np.array(QUARTERS)[None, :] / 4.0) * h
        phi = step_matrices(omega(stages), np.full(steps, h))
        got = ordered_product(phi) @ start
        errors.append(geodesic_angle(got / np.linalg.norm(got), end))
    assert 1e-11 < errors[0] < 1e-5
    assert errors[1] < errors[0] / 20.0 and errors[2] < errors[1] / 20.0
