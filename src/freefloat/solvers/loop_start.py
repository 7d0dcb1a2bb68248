"""A start for paths whose joints end where they begin: a closed loop, from the quadratic turn.

When every joint's goal is its start (a pure reorientation, or the correcting motion of
:mod:`freefloat.robust.correction`), the quintic path ``beta = 0`` does not move: every free
coefficient's first-order effect on the attitude vanishes there, so ``h`` is singular at that
point and continuation has no tangent to follow. A closed loop in joint space still turns the
spacecraft, by the momentum map's curvature over the area it encloses (paper's example 5.2),
and to second order

    turn(beta) ~ 1/2 [beta^T H_k beta]_k,   H_k = d^2 h_k / d beta^2 at beta = 0

(``H`` from central differences of the exact Jacobian). On the way round, though, the
spacecraft swings to first order in ``beta``: by ``F1(q0) (q(t) - q0)``, the momentum map at
the start joints times the joints' displacement. A loop picked for its turn alone can swing the
spacecraft ten times further than it turns it (a Canadarm2 loop: a 10.4 deg swing for a
0.75 deg turn), out of a pointing cone a few degrees wide. :func:`loop_start` takes the loop
that turns the most for its swing: the top eigenvector of ``sum_k a_k H_k`` (``a``: the unit
direction of the turn wanted) against the swing's quadratic form ``W`` (:func:`_swing_form`,
the generalised symmetric eigenproblem ``A v = lambda W v``), scaled to the angle wanted, as
the solvers' start; the search continues from there. The same Canadarm2 loop then swings
0.53 deg for a 0.53 deg turn. That is the models' figure: such a loop has larger coefficients,
where the quadratic model of the turn is less exact (the worked example's loop for 2 deg
turns it 0.13 deg while swinging 5.9 deg), and its turn's direction is the model's top
eigenvector's, not the one asked. Each loop thus plans turns the other cannot, and the
searches start from this one and, when that fails, from the loop of the least joint motion
(``swing=False``, the top eigenvector of ``A`` alone).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import quat_exp, quat_multiply, relative_rotvec
from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .continuation import track
from .options import SolveOptions
from .restore import broken_constraint

__all__ = [
    "LOOP_TURN",
    "AxisLoop",
    "loop_on_axis",
    "loop_origin",
    "loop_start",
    "same_start",
    "stays_put",
]

#: Step of the central differences of the Jacobian that give ``H`` (rad of beta).
_STEP = 1e-3
#: Halvings of a loop that breaks a constraint before it is given up (a count).
_HALVINGS = 20
#: Instants (a count, evenly spaced over the path) at which a loop's swing is weighed.
_SWING_INSTANTS = 41
#: Weight of the joints' own squared displacement in a loop's swing form, as a fraction of
#: the largest squared gain of the momentum map (a ratio; rad of turn per rad or m of joint,
#: squared, times rad^2 or m^2 of displacement: rad^2 of turn, like the swing). It keeps the
#: joints bounded along moves that barely swing the spacecraft.
_TRAVEL_WEIGHT = 1e-2
#: Largest top eigenvalue of the turn's curvature (rad of turn per unit of beta squared) taken
#: as no curvature at all: the central differences of an exactly flat map (joints that all
#: move along one line and back) give about 1e-12; the heaviest real spacecraft tried
#: (Canadarm2) give 0.1.
_FLAT = 1e-8


def _curvature(problem: Problem) -> np.ndarray:
    """(equations, n_free, n_free) symmetric ``H`` of the quadratic turn at ``beta = 0``."""
    n = problem.n_free
    out = np.empty((problem.n_equations, n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = _STEP
        out[:, :, i] = (problem.jacobian(e) - problem.jacobian(-e)) / (2.0 * _STEP)
    return 0.5 * (out + out.transpose(0, 2, 1))


def _swing_form(problem: Problem) -> np.ndarray:
    """(n_free, n_free) positive definite ``W`` of a loop's first-order swing.

    ``beta^T W beta`` is the mean over the path (:data:`_SWING_INSTANTS` instants) of the
    spacecraft's first-order turn from its start attitude, ``|F1(q0) (q(s) - q0)|^2`` (rad^2;
    about the plane's axis alone for a planar problem), plus :data:`_TRAVEL_WEIGHT` times the
    largest squared gain of ``F1(q0)`` times ``|q(s) - q0|^2``. The paths are affine in
    ``beta``, so each free coefficient's displacement is the path at its unit vector less the
    quintic path (which stays put at ``q0``).
    """
    n = problem.n_free
    s = np.linspace(0.0, 1.0, _SWING_INSTANTS)
    still = problem.family.evaluate(np.zeros(n), s).q
    moves = np.stack([problem.family.evaluate(e, s).q - still for e in np.eye(n)], axis=-1)
    joints = still.shape[1]
    gains = problem.mmap.base_rates(np.repeat(still[:1], joints, axis=0), np.eye(joints)).omega.T
    if problem.planar:
        gains = problem.axis[None, :] @ gains
    swing = np.einsum("kj,sjn->skn", gains, moves)
    travel = _TRAVEL_WEIGHT * float(np.linalg.norm(gains, 2)) ** 2
    form = np.einsum("skn,skm->nm", swing, swing) + travel * np.einsum("sjn,sjm->nm", moves, moves)
    return np.asarray(form / len(s))


def _whitening(problem: Problem) -> np.ndarray | None:
    """``L^-1`` of the swing form's Cholesky factor ``W = L L^T``; None when W is singular.

    W is singular where the momentum map vanishes at the start joints (a sliding mass at the
    system's centre of mass: no first-order swing, and no travel weight either); the loop
    is then the one of the least joint motion.
    """
    try:
        return np.asarray(np.linalg.inv(np.linalg.cholesky(_swing_form(problem))))
    except np.linalg.LinAlgError:
        return None


def loop_start(
    problem: Problem, constraints: Sequence[Constraint], turn: np.ndarray, swing: bool = True
) -> np.ndarray | None:
    """A closed loop whose quadratic-model turn is ``turn`` (rad, equations' frame).

    With ``swing``, the loop that turns the most along ``turn`` for its swing (see the module
    docstring); without, the one that turns the most for the size of its free coefficients
    (the top eigenvector of ``A`` alone: the loop of the least joint motion, which may swing
    the spacecraft far on the way). The searches start from the first and fall back on the
    second: each plans some turns the other cannot reach (a 2 deg ETS-VII reorientation within
    a 2.1 deg swing bound plans from the second only; a 0.54 deg Canadarm2 correction from the
    first only). Halved while it breaks a constraint (at most 20 times); None when no loop
    turns that way.
    """
    hessian = _curvature(problem)
    size = float(np.linalg.norm(turn))
    direction = turn / size
    curvature = np.einsum("k,kij->ij", direction, hessian)
    values, vectors = np.linalg.eigh(curvature)
    if values[-1] <= _FLAT:  # no loop turns that way (or only the differences' noise does)
        return None
    inverse = _whitening(problem) if swing else None
    if inverse is not None:  # A v = lambda W v, W = L L^T: L^-1 A L^-T u = lambda u, v = L^-T u
        values, vectors = np.linalg.eigh(inverse @ curvature @ inverse.T)
        vectors = inverse.T @ vectors
    beta = math.sqrt(2.0 * size / values[-1]) * vectors[:, -1]
    for _ in range(_HALVINGS):
        if not broken_constraint(problem, constraints, beta):
            return np.asarray(beta)
        beta = 0.5 * beta
    return None


def stays_put(problem: Problem) -> bool:
    """Whether the problem's quintic path does not move (every joint's goal is its start)."""
    return bool(np.array_equal(problem.family.start, problem.family.goal))


def same_start(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """Whether two starts of a search (a loop's free coefficients, or None) are the same."""
    return (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))


def loop_origin(
    problem: Problem, constraints: Sequence[Constraint], swing: bool = True
) -> np.ndarray | None:
    """Where the solvers start when the quintic path stays put: a loop towards the goal.

    None when the quintic path moves (it is the start), when it already ends at the goal
    attitude, or when no loop within ``constraints`` turns that way. ``swing``: as
    :func:`loop_start`.
    """
    if not stays_put(problem) or problem.n_free == 0:
        return None
    zero = np.zeros(problem.n_free)
    if problem.planar:  # the loop turns the base frame at the end: the turn wanted there
        turn = -problem.residual(zero)
    else:
        turn = relative_rotvec(problem.achieved(zero), problem.goal_quaternion)
    if not np.any(turn):
        return None
    return loop_start(problem, constraints, turn, swing)


#: The turn (rad) a reach direction's loop is solved at before it heads on (a multiple of the
#: reported 0.01 deg, so that the turns reported from it are too).
LOOP_TURN = math.radians(1.0)


@dataclass(frozen=True)
class AxisLoop:
    """A loop solved onto a turn about one axis (:func:`loop_on_axis`).

    Attributes:
        turn: the turn it reaches about the axis from the quintic attitude (rad).
        beta: its free coefficients (rad or m); None when none was found.
        why_not: why none was found ("" when one was).
    """

    turn: float
    beta: np.ndarray | None
    why_not: str = ""


def loop_on_axis(
    problem: Problem,
    quintic: np.ndarray,
    axis: np.ndarray,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    turn: float = LOOP_TURN,
) -> AxisLoop:
    """A loop that turns the spacecraft exactly ``turn`` (rad) about ``axis``.

    ``axis``: unit, base frame at ``quintic``, the attitude ``[x, y, z, w]`` of the path that
    stays put. The quadratic model's loop (:func:`loop_origin`), then the planner's
    continuation from its own attitude onto that turn: the reach then heads on along the axis
    from an exact point.
    """
    target = problem.with_goal(quat_multiply(quintic, quat_exp(turn * axis)))
    loop = loop_origin(target, constraints)
    if loop is None:
        return AxisLoop(0.0, None, "no loop within the constraints turns it about this axis")
    found = track(target, constraints, options, loop)
    if not found.reached:
        return AxisLoop(0.0, None, f"the loop about this axis stopped: {found.stopped_by}")
    return AxisLoop(turn, found.beta)
