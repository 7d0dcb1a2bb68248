"""The continuation's predictor and corrector programs against SciPy's SLSQP on the same data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from freefloat.solvers.predictor import MARGIN, newton_correction, tangent


def _slsqp(jac: np.ndarray, rhs: np.ndarray, g: np.ndarray, g_mat: np.ndarray) -> np.ndarray:
    """min |x|^2 with jac x = rhs and g + g_mat x <= -MARGIN, by SciPy's SLSQP (its own code)."""
    found = minimize(
        lambda x: x @ x,
        np.zeros(jac.shape[1]),
        jac=lambda x: 2.0 * x,
        method="SLSQP",
        constraints=[
            {"type": "eq", "fun": lambda x: jac @ x - rhs, "jac": lambda x: jac},
            {"type": "ineq", "fun": lambda x: -(g + g_mat @ x) - MARGIN, "jac": lambda x: -g_mat},
        ],
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert found.success, found.message
    return np.asarray(found.x)


def _data(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    jac = rng.normal(size=(3, 10))
    delta = rng.normal(size=3)
    g_mat = rng.normal(size=(6, 10))
    g = -np.abs(rng.normal(scale=0.05, size=6))  # inside, some rows nearly active
    g[:2] = 0.0  # two rows active now
    return jac, delta, g, g_mat


@pytest.mark.parametrize("seed", range(5))
def test_the_predicted_path_keeps_every_row_inside_as_slsqp_finds(seed: int) -> None:
    jac, delta, g, g_mat = _data(seed)
    step = 0.5
    t = tangent(jac, delta, g, g_mat, step)
    np.testing.assert_allclose(jac @ t, delta, atol=1e-10)
    assert np.all(g + step * g_mat @ t <= -MARGIN + 1e-12)
    # the same program solved by another library: the same smallest norm
    reference = _slsqp(jac, delta, g, step * g_mat)
    assert np.linalg.norm(t) == pytest.approx(np.linalg.norm(reference), rel=1e-6)
    np.testing.assert_allclose(t, reference, atol=1e-6)


def test_without_a_step_the_tangent_slides_along_the_active_rows_only() -> None:
    jac, delta, g, g_mat = _data(7)
    t = tangent(jac, delta, g, g_mat)
    np.testing.assert_allclose(jac @ t, delta, atol=1e-10)
    assert np.all(g_mat[:2] @ t <= 1e-12)  # the active rows are not crossed
    # a long step along it would cross a row that is near but not active: the step's
    # tangent does not
    assert np.any(g + 5.0 * g_mat @ t > 0.0)
    assert np.all(g + 5.0 * g_mat @ tangent(jac, delta, g, g_mat, 5.0) <= 0.0)


def test_an_impossible_step_slides_along_the_active_rows_then_predicts_freely() -> None:
    jac, delta = np.array([[1.0, 1.0]]), np.array([1.0])
    # row 0 active (t2 <= 0), row 1 forbids the step J asks for (t1 <= 0.01 over a whole step)
    g, g_mat = np.array([0.0, -0.01]), np.array([[0.0, 1.0], [1.0, 0.0]])
    t = tangent(jac, delta, g, g_mat, 1.0)
    np.testing.assert_allclose(t, [1.0, 0.0], atol=1e-12)  # the active row only, not [0.5, 0.5]
    # no row active now: the least-squares tangent, whatever the rows further in say
    t = tangent(jac[:, :1], delta, np.array([-0.01]), np.array([[1.0]]), 1.0)
    np.testing.assert_allclose(t, [1.0])


@pytest.mark.parametrize("seed", range(3))
def test_the_newton_correction_is_slsqps_minimum_norm_step(seed: int) -> None:
    jac, delta, g, g_mat = _data(seed)
    r = 0.1 * delta
    d = newton_correction(jac, r, g, g_mat)
    assert d is not None
    np.testing.assert_allclose(d, _slsqp(jac, -r, g, g_mat), atol=1e-6)
    assert (
        newton_correction(np.array([[1.0]]), np.array([-1.0]), np.array([0.0]), np.eye(1)) is None
    )


def test_a_correction_from_rows_that_are_not_finite_is_refused_not_solved() -> None:
    # quadprog may never return on such rows: None (infeasible) before it is called.
    jac, r, g = np.eye(2, 3), np.array([0.1, -0.2]), np.array([-0.1, -0.2])
    g_mat = np.ones((2, 3))
    assert newton_correction(jac, r, g, np.where([[True], [False]], np.nan, g_mat)) is None
    assert newton_correction(jac, r * np.inf, g, g_mat) is None
    assert newton_correction(np.where(jac > 0.0, np.inf, 0.0), r, g, g_mat) is None
    assert newton_correction(jac, r, g, g_mat) is not None  # finite: solved


def test_a_tangent_from_rows_that_are_not_finite_skips_the_programs() -> None:
    # The near rows are not finite: no program is solved; the least-squares tangent is what
    # numpy's lstsq gives for J t = delta (the corrector decides).
    jac, delta = np.eye(2, 3), np.array([0.3, -0.1])
    g, g_mat = np.array([-1e-9, -0.2]), np.array([[np.inf, 0.0, 0.0], [0.0, 1.0, 0.0]])
    t = tangent(jac, delta, g, g_mat, step=0.5)
    np.testing.assert_allclose(t, np.linalg.lstsq(jac, delta, rcond=None)[0], atol=1e-15)
