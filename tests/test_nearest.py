"""The root nearest the quintic: first-order optimality, against SciPy's SLSQP."""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

import freefloat as ff
from freefloat.solvers.nearest import _least_norm_root


def test_least_norm_root_is_a_kkt_point_and_matches_slsqp(worked_scenario):
    scenario = worked_scenario.resolved()
    problem = ff.problem_from_scenario(scenario, extra=[2, 2])
    start = ff.solve(problem, ff.SolveOptions(), []).beta
    beta = _least_norm_root(problem, start, ff.SolveOptions())
    residual, jac = problem.residual_and_jacobian(beta)
    assert np.linalg.norm(residual) < 1e-9
    # KKT of min |beta|^2 s.t. h = 0: beta lies in the row space of the Jacobian
    null = np.linalg.svd(jac)[2][jac.shape[0] :]
    assert np.linalg.norm(null @ beta) < 1e-6 * np.linalg.norm(beta)
    assert beta @ beta <= start @ start
    # independent optimiser from the same start
    other = minimize(
        lambda b: b @ b,
        start,
        jac=lambda b: 2 * b,
        method="SLSQP",
        constraints=[{"type": "eq", "fun": problem.residual, "jac": problem.jacobian}],
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert other.success
    np.testing.assert_allclose(beta @ beta, other.x @ other.x, rtol=1e-6)
