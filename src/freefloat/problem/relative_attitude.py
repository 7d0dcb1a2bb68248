"""The spacecraft's attitude relative to its start at chosen instants, and its exact Jacobian.

The planner's own integration (:class:`~.residual.Problem`'s sixth-order Magnus scheme on
Gauss nodes) carried to every instant asked: the interval from 0 to each instant is split into
steps no longer than the problem's, and the relative attitude ``r(s) = q(0)^-1 q(s)`` (it
does not depend on the start attitude) is chained step by step. A perturbation of step
``j``'s Magnus vector ``W_j`` reaches instant ``m`` as the body-frame perturbation
``delta_m = R_m^T sum_{j <= m} R_j Jr(W_j) dW_j`` of ``r`` (``R`` the attitudes after each
step): a running sum, so every instant costs about what the residual's Jacobian does. A
quantity of the attitude then differentiates through ``delta``: the turn ``theta = |log r|``
as ``d theta = u . delta`` (``u`` the unit rotation axis: the SO(3) right Jacobian's inverse
leaves ``u`` unchanged), a body axis ``v = R a`` as ``dv = R (delta x a)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
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
from ..physics.turn_track import quaternion_turn
from .residual import Problem

__all__ = ["RelativeRows", "SwingRows", "attitude_peaks", "relative_rows", "swing_rows"]

_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


@dataclass(frozen=True)
class RelativeRows:
    """The attitude relative to the start at normalised instants.

    Attributes:
        relative: (M, 4) ``q(0)^-1 q(s)``, ``[x, y, z, w]``.
        body: (M, 3, n_free) exact body-frame perturbation of each per unit of beta (rad).
    """

    relative: np.ndarray
    body: np.ndarray


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
    found = relative_rows(problem, beta, s)
    axes = _unit_axes(found.relative)
    return SwingRows(quaternion_turn(found.relative), np.einsum("mi,mif->mf", axes, found.body))


def relative_rows(problem: Problem, beta: np.ndarray, s: np.ndarray) -> RelativeRows:
    """The attitude relative to the start at normalised instants ``s`` in [0, 1].

    With its exact body-frame perturbation per unit of ``beta`` (rad).
    """
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
    return RelativeRows(relative[at], np.einsum("mji,mjf->mif", attitudes[at], summed[at]))


def _unit_axes(r: np.ndarray) -> np.ndarray:
    """(M, 3) unit rotation axes of quaternions (zeros at the identity, where the turn is least).

    The axis of ``[v, w]`` is ``v / |v|``, turned over when ``w < 0`` (``-r`` is the same
    rotation, by the angle the turn takes, at most pi).
    """
    norms = np.linalg.norm(r[:, :3], axis=1, keepdims=True)
    sign = np.where(r[:, 3:] < 0.0, -1.0, 1.0)
    return np.divide(sign * r[:, :3], norms, out=np.zeros((len(r), 3)), where=norms > 0.0)


def attitude_peaks(
    problem: Problem, beta: np.ndarray, count: int, value: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """Normalised instants of the largest values of the relative attitude, found cheaply.

    ``value`` maps (K, 4) relative attitudes to K values (the turn, say). It is taken on the
    problem's own grid; each of its ``count`` largest interior maxima is refined twice (the
    ends are fixed: the start's and the goal's attitude, which no path changes): the value at
    :data:`_REFINE_POINTS` instants across the two steps about it (each reached by one Magnus
    step from the grid point before them), then the vertex of the parabola through the
    largest and its neighbours.
    """
    beta = np.asarray(beta, dtype=float)
    s = np.linspace(0.0, 1.0, problem.steps + 1)
    relative = relative_quat(problem.start_quaternion, problem.attitudes(beta, s))
    turns = value(relative)
    found = []  # not the end: its turn is the goal's
    inner = np.flatnonzero((turns[1:-1] >= turns[:-2]) & (turns[1:-1] >= turns[2:])) + 1
    for k in inner[np.argsort(turns[inner])[::-1][:count]].tolist():
        low, high = float(s[k - 1]), float(s[k + 1])
        for _ in range(2):
            points = np.linspace(low, high, _REFINE_POINTS)
            near = value(_stepped(problem, beta, s[k - 1], relative[k - 1], points))
            j = int(np.clip(np.argmax(near), 1, _REFINE_POINTS - 2))
            low, high = float(points[j - 1]), float(points[j + 1])
        left, middle, right = near[j - 1], near[j], near[j + 1]
        curve = left - 2.0 * middle + right
        shift = 0.5 * (left - right) / curve if curve < 0.0 else 0.0
        found.append(float(points[j] + np.clip(shift, -1.0, 1.0) * (points[1] - points[0])))
    return np.array(found)


#: Instants of each refinement round of :func:`attitude_peaks` (a count).
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
