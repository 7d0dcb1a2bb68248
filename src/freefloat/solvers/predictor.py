"""The continuation's two small quadratic programs: the predictor's tangent, the corrector's step.

Both are minimum-norm changes of the free coefficients ``beta`` (rad or m) with the attitude
residual's Jacobian ``J`` (rad per unit of ``beta``) as equality rows and the constraints
linearised as inequality rows ``g + G d <= 0`` (``g`` in each constraint's unit), solved by
quadprog. Rows far inside (``g <= -0.5``, :data:`FAR_INSIDE`) are left out of both programs:
they cannot become active in one step of a few rad. (Taking in those a predicted path would
cross, checked after the program, made the Panda servicer's 10 deg y goal 0.80 -> 1.18 s for
no gain: left out.)
"""

from __future__ import annotations

import numpy as np
import quadprog

__all__ = ["FAR_INSIDE", "MARGIN", "newton_correction", "tangent"]

#: Constraints are imposed at the instants this far inside (their unit: rad, rad/s, m...),
#: so that the path between instants stays inside too.
MARGIN = 1e-7
#: Rows with ``g`` at most this far inside are left out of the programs (each row's unit: rad,
#: rad/s, m).
FAR_INSIDE = -0.5


def _least_norm_qp(c_mat: np.ndarray, b: np.ndarray, equalities: int) -> np.ndarray | None:
    """``min |x|^2`` with ``C^T x = b`` (first ``equalities``) and ``C^T x >= b`` (the rest).

    None when the rows admit no such ``x``, or when they are not all finite (quadprog may not
    return on such rows).
    """
    if not (np.isfinite(c_mat).all() and np.isfinite(b).all()):
        return None
    n = c_mat.shape[0]
    try:
        return np.asarray(quadprog.solve_qp(np.eye(n), np.zeros(n), c_mat, b, equalities)[0])
    except ValueError:
        return None


def newton_correction(
    jac: np.ndarray, r: np.ndarray, g: np.ndarray, g_mat: np.ndarray
) -> np.ndarray | None:
    """Minimum-norm ``d`` with ``J d = -r`` and ``g + G d <= 0``; None when infeasible."""
    near = g > FAR_INSIDE
    c_mat = np.vstack([jac, -g_mat[near]]).T
    return _least_norm_qp(c_mat, np.concatenate([-r, g[near] + MARGIN]), len(r))


def tangent(
    jac: np.ndarray,
    delta: np.ndarray,
    g: np.ndarray,
    g_mat: np.ndarray,
    step: float | None = None,
) -> np.ndarray:
    """Minimum-norm ``t = dbeta/dlam`` with ``J t = delta`` that slides along active rows.

    ``delta``: the residual's change per unit of the continuation parameter (rad). With
    ``step`` (the fraction of the way the next step takes), the predicted path
    ``beta + step t`` also keeps every linearised row near its limit inside
    (``g + step G t <= 0`` for ``g > FAR_INSIDE``), so that a long step does not predict a path
    deep through a constraint that is near but not yet active (a clearance row a few
    millimetres from its margin, say): the corrector then starts inside. When no such
    tangent exists, the rows active now only; when none keeps those, the least-squares
    tangent (the corrector decides).
    """
    near = g > FAR_INSIDE
    if step is not None and step > 0.0 and np.any(near):
        c_mat = np.vstack([jac, -step * g_mat[near]]).T
        found = _least_norm_qp(c_mat, np.concatenate([delta, g[near] + MARGIN]), len(delta))
        if found is not None:
            return found
        # no predicted path keeps every near row: slide along the active ones
    active = g > -10.0 * MARGIN
    if np.any(active):
        c_mat = np.vstack([jac, -g_mat[active]]).T
        b = np.concatenate([delta, np.zeros(int(active.sum()))])
        found = _least_norm_qp(c_mat, b, len(delta))
        if found is not None:
            return found
        # no tangent keeps every active row: predict freely, the corrector decides
    return np.asarray(np.linalg.lstsq(jac, delta, rcond=None)[0])
