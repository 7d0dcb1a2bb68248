"""How far a continuation got (:mod:`freefloat.solvers.continuation`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BranchPoint", "ContinuationResult"]


@dataclass(frozen=True)
class ContinuationResult:
    """How far the continuation got.

    Attributes:
        beta: free coefficients at the last solved point (rad or m).
        fraction: how far along the geodesic to the goal that point is (0-1).
        angle: the whole angle from the quintic attitude to the goal (rad).
        axis: unit rotation axis of that geodesic (base frame at the quintic attitude).
        residual: residual vector at ``beta`` for the target at ``fraction`` (rad).
        steps: continuation steps taken.
        iterations: Newton iterations in all correctors.
        stopped_by: why it stopped short ("" when it reached the goal).
        blocked_by: the name of the constraint that stopped it ("" when none did).
    """

    beta: np.ndarray
    fraction: float
    angle: float
    axis: np.ndarray
    residual: np.ndarray
    steps: int
    iterations: int
    stopped_by: str = ""
    blocked_by: str = ""

    @property
    def reached(self) -> bool:
        """Whether the goal itself was reached."""
        return not self.stopped_by

    @property
    def fraction_text(self) -> str:
        """``fraction`` as printed: three significant digits, more while short of 1.

        A stop short of the goal never prints as the whole way (0.9996 reads "0.9996", not "1").
        """
        digits = 3
        while digits < 17 and self.fraction < 1.0 and float(f"{self.fraction:.{digits}g}") >= 1:
            digits += 1
        return f"{self.fraction:.{digits}g}"


@dataclass(frozen=True)
class BranchPoint:
    """One accepted point of a continuation's branch (see ``track``'s ``trace``).

    Attributes:
        turn: angle from the start attitude along the geodesic to the goal (rad).
        beta: free coefficients of the solved path there (rad or m).
        next_step: the step the continuation tries next from here, as an angle (rad).
    """

    turn: float
    beta: np.ndarray
    next_step: float
