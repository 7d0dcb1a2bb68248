"""Where the reach estimate's directions start: a path at the drift attitude within the constraints.

The drift attitude is where the plain quintic path (``beta = 0``) leaves the spacecraft. When
that path keeps every constraint imposed from the start, each direction starts from it. When it
breaks one (its wrist sweeps through a keep-out plate, say), the planner starts from the
nearest path within the constraints instead (:func:`.restore.feasible_start`, attitude ignored)
and brings the attitude to its goal from there; so does the estimate: from that path, the
planner's continuation towards the drift attitude itself gives a path there within the
constraints, and every direction starts from it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .continuation import track
from .options import SolveOptions
from .restore import feasible_start, first_broken

__all__ = [
    "RESTORED_SHORT",
    "RESTORED_TRIES",
    "Confirmed",
    "DriftStart",
    "confirmed_from",
    "drift_start",
    "rounded_down",
]

#: Tries to confirm a direction's turn from the restored start (a count; halved each time).
RESTORED_TRIES = 3


@dataclass(frozen=True)
class DriftStart:
    """The path every direction starts from, or why there is none.

    Attributes:
        beta: free coefficients of a path reaching the drift attitude within the constraints
            (rad or m; zeros: the quintic path itself), None when none was found.
        why_not: why none was found ("" when one was): the directions report it.
        restored: the nearest path within the constraints the planner starts from when the
            quintic path breaks one (rad or m), None when it does not: a goal is then
            confirmed from there, as plan heads for it.
    """

    beta: np.ndarray | None
    why_not: str = ""
    restored: np.ndarray | None = None


def drift_start(
    problem: Problem, constraints: Sequence[Constraint], options: SolveOptions
) -> DriftStart:
    """The quintic path, or else a path at its attitude within ``constraints`` (the eager ones).

    The evaluation budget is ``options.max_evaluations``, as for one pass of a direction.
    """
    zero = np.zeros(problem.n_free)
    broken = first_broken(problem, constraints, zero)
    if broken is None:
        return DriftStart(zero)
    found = feasible_start(problem, list(constraints), options)
    if found is None:
        return DriftStart(
            None,
            f"the plain quintic path breaks {broken} and no path within the constraints was "
            "found to start from (as plan would start)",
        )
    drift = problem.achieved(zero)
    result = track(problem.with_goal(drift), constraints, options, found)
    if not result.reached:
        return DriftStart(
            None,
            f"the plain quintic path breaks {broken}; from the nearest path within the "
            f"constraints, continuation did not reach the drift attitude ({result.stopped_by})",
            found,
        )
    return DriftStart(result.beta, "", found)


def rounded_down(turn: float, step: float) -> float:
    """``turn`` (rad) rounded down to a multiple of ``step`` (rad; 0: not rounded).

    The precision a turn is reported at, so that the goal printed is the one confirmed.
    """
    return math.floor(turn / step + 1e-9) * step if step > 0.0 else turn


#: Why a direction stops where plan's own start confirms it (:func:`confirmed_from`); with
#: "no turn about this axis" when it confirms none.
RESTORED_SHORT = (
    "plan's continuation from its restored start (the plain quintic path breaks a "
    "constraint) confirmed {}"
)


@dataclass(frozen=True)
class Confirmed:
    """A direction's turn as plan's continuation from its restored start confirms it.

    Attributes:
        turn: the turn confirmed (rad; 0 when none was).
        beta: its path (rad or m).
        halved: whether it is short of the turn asked (beyond the rounding step).
    """

    turn: float
    beta: np.ndarray
    halved: bool


def confirmed_from(
    restored: np.ndarray,
    target: Callable[[float], Problem],
    reached: float,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    step: float,
) -> Confirmed:
    """The turn up to ``reached`` (rad) that plan's continuation confirms from ``restored``.

    When the quintic path breaks a constraint, plan starts from the nearest path within the
    constraints and heads straight for the goal, not along a direction's branch from the
    drift attitude: each turn is confirmed so (the reported goal is one plan solves), halved
    up to :data:`RESTORED_TRIES` times (rounded down to a multiple of ``step``, rad; 0: not
    rounded). ``target(turn)``: the problem heading for that turn.
    """
    turn = reached
    for _ in range(RESTORED_TRIES):
        turn = rounded_down(turn, step)
        if turn <= 0.0:
            break
        result = track(target(turn), constraints, options, restored)
        if result.reached:
            return Confirmed(turn, result.beta, turn < reached - max(step, 1e-12))
        turn *= 0.5
    return Confirmed(0.0, restored, True)  # the caller reports the drift path for turn 0
