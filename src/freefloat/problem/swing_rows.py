"""The spacecraft's turn from its start attitude at chosen instants, and its exact Jacobian.

The planner's own integration (:class:`~.residual.Problem`'s sixth-order Magnus scheme on
Gauss nodes) carried to every instant asked: the interval from 0 to each instant is split into
steps no longer than the problem's, and the relative attitude ``r(s) = q(0)^-1 q(s)`` (it
does not depend on the start attitude) is chained step by step. Its angle ``theta = |log r|``
has the derivative ``d theta = u . delta`` for a body-frame perturbation ``delta`` of ``r``
(``u`` the unit rotation axis: the SO(3) right Jacobian's inverse leaves ``u`` unchanged), and
a perturbation of step ``j``'s Magnus vector ``W_j`` reaches instant ``m`` as
``delta_m = R_m^T sum_{j <= m} R_j Jr(W_j) dW_j`` (``R`` the attitudes after each step): a
running sum, so every instant costs about what the residual's Jacobian does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import (
    magnus_increment_jacobian,
    magnus_increments,
    propagate,
    quat_log,
    quat_to_matrix,
    relative_quat,
    so3_right_jacobian,
    step_nodes,
)
from ..physics.swing import quaternion_turn
from .residual import Problem

__all__ = ["SwingRows", "swing_profile", "swing_rows"]

_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


@dataclass(frozen=True)
class SwingRows:
    """The turn from the start attitude at normalised instants.

    Attributes:
        turns: (M,) rotation angle of ``q(0)^-1 q(s)`` at each instant (rad).
        jacobian: (M, n_free) exact ``d turn / d beta`` (rad per unit of beta).
    """

    turns: np.ndarray
    jacobian: np.ndarray


def _edges(problem: Problem, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step ends from 0 through every instant (none longer than the problem's steps).

    Returns the edges and, per instant of ``s`` (in its order), the index of its edge.
    """
    points = np.unique(np.concatenate([[0.0], s]))
    pieces = [points[:1]]
    for a, b in zip(points[:-1].tolist(), points[1:].tolist(), strict=True):
        sub = max(1, math.ceil((b - a) * problem.steps - 1e-9))
        pieces.append(a + (b - a) * np.arange(1, sub + 1) / sub)
    edges = np.concatenate(pieces)
    edges[np.searchsorted(edges, points)] = points  # the instants themselves, to the bit
    return edges, np.searchsorted(edges, s)


def swing_rows(problem: Problem, beta: np.ndarray, s: np.ndarray) -> SwingRows:
    """The turn (rad) at normalised instants ``s`` in [0, 1] and its Jacobian in ``beta``."""
    s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
    beta = np.asarray(beta, dtype=float)
    edges, at = _edges(problem, s)
    nodes, h = step_nodes(edges)
    base, dq, dqs = problem.family.linear_map(nodes)
    rates = problem.mmap.base_rates(base.q + dq @ beta, base.qd + dqs @ beta, derivatives=True)
    assert rates.domega_dq is not None
    steps, n_free = len(h), len(beta)
    domega = np.einsum("kij,kjf->kif", rates.domega_dq, dq) + np.einsum(
        "kij,kjf->kif", rates.f1, dqs
    )
    omega = rates.omega.reshape(steps, 3, 3)
    increments = magnus_increments(omega, h)
    dw = np.einsum(
        "mck,mkf->mcf",
        magnus_increment_jacobian(omega, h),
        domega.reshape(steps, 9, n_free),
    )
    relative = propagate(_IDENTITY, increments)
    attitudes = quat_to_matrix(relative)  # (steps + 1, 3, 3)
    spatial = np.einsum("mij,mjk,mkf->mif", attitudes[1:], so3_right_jacobian(increments), dw)
    summed = np.concatenate([np.zeros((1, 3, n_free)), np.cumsum(spatial, axis=0)])
    chosen = relative[at]
    turns = quaternion_turn(chosen)
    axes = np.array([_unit_axis(r) for r in chosen])
    body = np.einsum("mji,mjf->mif", attitudes[at], summed[at])
    return SwingRows(turns, np.einsum("mi,mif->mf", axes, body))


def _unit_axis(r: np.ndarray) -> np.ndarray:
    """Unit rotation axis of a quaternion (zeros at the identity: the turn is smallest there)."""
    phi = quat_log(r)
    norm = float(np.linalg.norm(phi))
    return phi / norm if norm > 0.0 else np.zeros(3)


def swing_profile(problem: Problem, beta: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The turn (rad) at ``count`` uniform normalised instants from 0 to 1 (no derivatives)."""
    s = np.linspace(0.0, 1.0, count)
    quaternions = problem.attitudes(np.asarray(beta, dtype=float), s)
    return s, quaternion_turn(relative_quat(problem.start_quaternion, quaternions))
