"""What a search's failed levels leave: every attempt, the first error, the nearest goal.

:func:`freefloat.solvers.search.search` records each freedom level that stops here and builds
its refusal from the record: the figures of the goal whose levels got closest, counted from
where its first level started (the quintic path's attitude, or a loop's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import FreeFloatError, SolverError, UnreachableAttitudeError

__all__ = ["GoalTurns", "SearchRecord"]


@dataclass
class SearchRecord:
    """What the search's failed levels leave: every attempt, the first error, the nearest.

    Attributes:
        tried: every attempt, in order.
        first_error: the first error met.
        best: the smallest residual of a level (rad), ``best_axes`` its vector and
            ``best_error`` its error (or the level that got furthest along its way).
        turns: per goal tried (its label: ``goal as stated``, or its joints' turns), the
            unreachable-attitude errors of its first level (the turn asked from the quintic
            path's attitude) and of the level that got closest.
        blocked: the names of the constraints that stood in the way of some level.
        looped: per goal (its label) whose levels started from a loop (its quintic path
            stays put), the first such loop's free coefficients: the goal's figures count
            from a loop's attitude.
    """

    tried: list[str] = field(default_factory=list)
    first_error: FreeFloatError | None = None
    best: float = math.inf
    best_axes: tuple[float, ...] | None = None
    best_error: SolverError | None = None
    turns: dict[str, list[UnreachableAttitudeError | None]] = field(default_factory=dict)
    blocked: list[str] = field(default_factory=list)
    looped: dict[str, np.ndarray] = field(default_factory=dict)

    def failed(self, exc: SolverError, freedom: str, continued: bool, goal: str = "") -> None:
        """Record a level (``freedom``: its label, ``goal`` its goal's) stopped with ``exc``."""
        self.blocked += exc.blocked_by
        if isinstance(exc, UnreachableAttitudeError):
            pair = self.turns.setdefault(goal, [None, None])
            if not continued:
                pair[0] = exc  # the turn asked from the quintic path's attitude
            if pair[1] is None or exc.best_residual < pair[1].best_residual:
                pair[1] = exc
        self.first_error = self.first_error or exc
        if continued:  # its reach counts from a later point: keep the first
            self.tried.append(f"{freedom} (continued): " + _short(exc))
            return
        breaks = [item for item in exc.tried if " breaks " in item]
        self.tried.append(f"{freedom}: " + _short(exc) + (f" ({breaks[0]})" if breaks else ""))
        further = self.best_error is not None and exc.reached_fraction > max(
            self.best_error.reached_fraction, 0.0
        )
        if exc.best_residual < self.best or further:
            self.best, self.best_axes, self.best_error = exc.best_residual, exc.per_axis, exc

    def nearest_goal(self) -> GoalTurns:
        """The goal tried whose levels got closest, its first level's and its closest error.

        Its label as the search names it (``goal as stated``, or its joints' turns); "" and
        no errors when no level stopped on the way to its goal.
        """
        known = [(g, o, c) for g, (o, c) in self.turns.items() if o is not None and c is not None]
        if not known:
            return GoalTurns("", None, None)
        goal, origin, closest = min(known, key=lambda item: item[2].best_residual)
        return GoalTurns(goal, origin, closest, goal in self.looped)


@dataclass(frozen=True)
class GoalTurns:
    """A goal's label, its first level's and closest level's refusals (:class:`SearchRecord`).

    ``looped``: whether its first level started from a loop (the turn asked counts from it).
    """

    goal: str
    origin: UnreachableAttitudeError | None
    closest: UnreachableAttitudeError | None
    looped: bool = False


def _short(error: SolverError) -> str:
    """A level's figure for the list of attempts (the same figure as the error's)."""
    if error.last_beta is not None:
        return (
            f"stopped {math.degrees(error.best_residual):.3g} deg "
            f"({error.best_residual:.3g} rad) short of the goal"
        )
    return f"best residual {error.best_residual:.3g} rad"
