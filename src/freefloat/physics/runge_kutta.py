"""Butcher's fifth-order Runge-Kutta method, for the verification's integrations.

Six stages at the fractions ``0, 1/4, 1/4, 1/2, 3/4, 1`` of a step (the six-stage
fifth-order method in J. C. Butcher's *Numerical Methods for Ordinary Differential
Equations*; the tests check its order on an equation with a known solution). All stages lie
on the quarters of the step, so a step-doubling sequence of uniform grids of M, 2 M, 4 M ...
steps evaluates its inputs (torques, angular velocities) at instants ``k T / (4 M)`` that the
finer levels reuse to the bit. Its error falls about 32-fold per doubling of the steps where
classical RK4's falls 16-fold, so a step-doubling check settles on fewer steps.

:func:`step_matrices` applies the method to the linear quaternion equation
``y' = 0.5 y (x) [omega(t), 0]``: every step is then one 4 x 4 matrix, built in one batch from
the stages' angular velocities.
"""

from __future__ import annotations

import numpy as np

from .attitude import quat_rate_matrices

__all__ = ["QUARTERS", "STAGE_MATRIX", "WEIGHTS", "step_matrices"]

#: The stages' instants in quarters of the step (indices into a table at the quarters):
#: 0, 1/4, 1/4, 1/2, 3/4, 1 of the step, each row of :data:`STAGE_MATRIX` summing to its own.
QUARTERS = (0, 1, 1, 2, 3, 4)
#: Butcher's ``a_ij``: stage i's state is ``y + h sum_j a_ij k_j`` (strictly lower triangular).
STAGE_MATRIX = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 4.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 8.0, 1.0 / 8.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, -1.0 / 2.0, 1.0, 0.0, 0.0, 0.0],
        [3.0 / 16.0, 0.0, 0.0, 9.0 / 16.0, 0.0, 0.0],
        [-3.0 / 7.0, 2.0 / 7.0, 12.0 / 7.0, -12.0 / 7.0, 8.0 / 7.0, 0.0],
    ]
)
#: Butcher's ``b_i``: the step is ``y + h sum_i b_i k_i``.
WEIGHTS = np.array([7.0, 0.0, 32.0, 12.0, 32.0, 7.0]) / 90.0


def step_matrices(stage_omega: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """(M, 4, 4) step matrices of the quaternion equation, one per step.

    The equation ``y' = A(t) y`` is linear, so the stage slopes are ``K_i y`` with
    ``K_i = A_i (I + h sum_j a_ij K_j)`` and the step is ``y -> (I + h sum_i b_i K_i) y``.

    Args:
        stage_omega: (M, 6, 3) base angular velocity at each step's stages (rad/s).
        widths: (M,) the steps' widths (s).
    """
    a = quat_rate_matrices(stage_omega)  # (M, 6, 4, 4), 1/s
    h = widths[:, None, None]
    eye = np.eye(4)
    slopes = np.empty_like(a)
    for i in range(len(WEIGHTS)):
        inner = eye + h * np.einsum("j,mjab->mab", STAGE_MATRIX[i, :i], slopes[:, :i])
        slopes[:, i] = a[:, i] @ inner
    return eye + h * np.einsum("i,miab->mab", WEIGHTS, slopes)
