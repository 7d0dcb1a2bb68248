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
    GAUSS3_NODES,
    magnus_increment_jacobian,
    magnus_increments,
    propagate,
    quat_exp,
    quat_multiply,
    quat_to_matrix,
    relative_quat,
    so3_right_jacobian,
    step_nodes,
)
from ..physics.swing import quaternion_turn
from .residual import Problem

__all__ = ["SwingRows", "swing_peaks", "swing_rows"]

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

    Returns the edges and, per instant of ``s`` (in its order), the index of its edge. Each
    interval between two instants is split evenly, its inner ends computed and its last end
    the instant itself, to the bit (``a + (b - a) sub / sub`` may round below ``b``).
    """
    points = np.unique(np.concatenate([[0.0], s]))
    pieces, ends = [points[:1]], [0]
    for a, b in zip(points[:-1].tolist(), points[1:].tolist(), strict=True):
        sub = max(1, math.ceil((b - a) * problem.steps - 1e-9))
        pieces.append(np.append(a + (b - a) * np.arange(1, sub) / sub, b))
        ends.append(ends[-1] + sub)
    return np.concatenate(pieces), np.asarray(ends)[np.searchsorted(points, s)]


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
    omega = rates.omega
    if problem.planar:  # about the one axis, as the problem integrates it
        axis = problem.axis
        omega = np.outer(omega @ axis, axis)
        domega = np.einsum("i,kif,j->kjf", axis, domega, axis)
    omega = omega.reshape(steps, 3, 3)
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
    body = np.einsum("mji,mjf->mif", attitudes[at], summed[at])
    return SwingRows(quaternion_turn(chosen), np.einsum("mi,mif->mf", _unit_axes(chosen), body))


def _unit_axes(r: np.ndarray) -> np.ndarray:
    """(M, 3) unit rotation axes of quaternions (zeros at the identity, where the turn is least).

    The axis of ``[v, w]`` is ``v / |v|``, turned over when ``w < 0`` (``-r`` is the same
    rotation, by the angle the turn takes, at most pi).
    """
    norms = np.linalg.norm(r[:, :3], axis=1, keepdims=True)
    sign = np.where(r[:, 3:] < 0.0, -1.0, 1.0)
    return np.divide(sign * r[:, :3], norms, out=np.zeros((len(r), 3)), where=norms > 0.0)


def swing_peaks(problem: Problem, beta: np.ndarray, count: int) -> np.ndarray:
    """Normalised instants of the largest turns, found cheaply.

    The turn on the problem's own grid; each of its ``count`` largest interior maxima
    refined twice (the end's turn is the goal's, which no path changes): the turn at
    :data:`_REFINE_POINTS` instants across the two steps about it (each reached by one
    Magnus step from the grid point before them), then the vertex of the parabola through the
    largest and its neighbours.
    """
    beta = np.asarray(beta, dtype=float)
    s = np.linspace(0.0, 1.0, problem.steps + 1)
    relative = relative_quat(problem.start_quaternion, problem.attitudes(beta, s))
    turns = quaternion_turn(relative)
    found = []  # not the end: its turn is the goal's
    inner = np.flatnonzero((turns[1:-1] >= turns[:-2]) & (turns[1:-1] >= turns[2:])) + 1
    for k in inner[np.argsort(turns[inner])[::-1][:count]].tolist():
        low, high = float(s[k - 1]), float(s[k + 1])
        for _ in range(2):
            points = np.linspace(low, high, _REFINE_POINTS)
            near = quaternion_turn(_stepped(problem, beta, s[k - 1], relative[k - 1], points))
            j = int(np.clip(np.argmax(near), 1, _REFINE_POINTS - 2))
            low, high = float(points[j - 1]), float(points[j + 1])
        left, middle, right = near[j - 1], near[j], near[j + 1]
        curve = left - 2.0 * middle + right
        shift = 0.5 * (left - right) / curve if curve < 0.0 else 0.0
        found.append(float(points[j] + np.clip(shift, -1.0, 1.0) * (points[1] - points[0])))
    return np.array(found)


#: Instants of each refinement round of :func:`swing_peaks` (a count).
_REFINE_POINTS = 17


def _stepped(
    problem: Problem, beta: np.ndarray, s0: float, r0: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """(K, 4) relative attitudes at ``points``, each one Magnus step from ``r0`` at ``s0``."""
    edges = np.stack([np.full(len(points), s0), points], axis=1)
    nodes = (edges[:, :1] + (edges[:, 1:] - edges[:, :1]) * GAUSS3_NODES[None, :]).ravel()
    path = problem.family.evaluate(beta, nodes)
    omega = problem.mmap.base_rates(path.q, path.qd).omega.reshape(len(points), 3, 3)
    step = quat_exp(magnus_increments(omega, points - s0))
    return quat_multiply(np.broadcast_to(r0, step.shape), step)
