"""Errors of motions that cannot be made: limits that need a longer duration, goals out of reach.

Units as in every message: rad, rad/s, N m (m, m/s, N for prismatic joints), s.
"""

from __future__ import annotations

import decimal
import math
from collections.abc import Callable, Sequence

from .base import FreeFloatError, SolverError


class DurationLimitError(FreeFloatError):
    """A joint beyond a URDF limit that a longer duration would respect.

    Attributes:
        joint: the joint's name.
        peak: its largest value along the path (the limit's unit).
        limit: the URDF limit.
        shortest_duration: the shortest duration (s) at which the path found respects the
            limits (its shape does not depend on the duration; another path may respect them
            at a shorter one).
        least_duration: no path with the same start and goal respects the limits in less (s;
            0 when not known).
        unit: the unit of the joint's value (rad or m).
        reached: the largest turn towards the goal attitude that the search within every
            limit reached (rad; NaN when not known, see :meth:`within_reach`).
        asked: the turn the goal asks for from where that search started (rad; NaN when not
            known).
    """

    #: What is limited ("velocity", "effort").
    kind = ""

    def __init__(
        self,
        joint: str,
        peak: float,
        limit: float,
        shortest_duration: float,
        unit: str,
        least_duration: float = 0.0,
    ) -> None:
        self.joint = joint
        self.peak = float(peak)
        self.limit = float(limit)
        self.shortest_duration = float(shortest_duration)
        self.least_duration = float(least_duration)
        self.unit = unit
        self.reached = self.asked = math.nan
        super().__init__(self.message_in(1.0, unit))

    def within_reach(self, reached: float, asked: float) -> DurationLimitError:
        """This error, saying how far the search within every limit got.

        ``reached`` of ``asked`` (rad) towards the goal attitude; its message says it too.
        """
        self.reached, self.asked = float(reached), float(asked)
        self.args = (self.message_in(1.0, self.unit),)
        return self

    def _exceeds(self, scale: float, unit: str) -> str:
        """The joint's peak against its limit, values times ``scale`` in ``unit``."""
        return f"joint {self.joint!r} at {scale * self.peak:.4g} {unit}, beyond {self.limit:.4g}"

    def message_in(self, scale: float, unit: str) -> str:
        """The message with the joint's values times ``scale``, in ``unit`` (deg, say).

        Durations to four figures, rounded so that each claim holds as printed: the
        shortest duration the path keeps its limits at up, the least any path needs down.
        """
        shortest = _rounded(self.shortest_duration, math.ceil)
        message = (
            f"{self._exceeds(scale, unit)}; the path found keeps every {self.kind} limit from "
            f"{shortest} s on"
        )
        if self.least_duration > 0.0:
            message = (
                f"{message}, no path can in under {_rounded(self.least_duration, math.floor)} s "
                "(each joint's travel at its limit), and a duration between may plan with "
                "another path"
            )
        else:
            message = f"{message}; under {shortest} s only another path can"
        if 0.0 <= self.reached < self.asked < math.inf:  # a figure that says something
            turned = UnreachableAttitudeError.turn_phrase(self.reached, self.asked)
            message += f"; at this duration and within every limit, {turned}"
        return message


def _rounded(seconds: float, way: Callable[[float], float]) -> str:
    """``seconds`` to four significant figures, rounded ``way`` (math.ceil or math.floor).

    In decimal, from the float's shortest form: 0.7 rounded down stays 0.7.
    """
    if not (math.isfinite(seconds) and seconds > 0.0):
        return f"{seconds:.4g}"
    exact = decimal.Decimal(repr(float(seconds)))
    rounding = decimal.ROUND_CEILING if way is math.ceil else decimal.ROUND_FLOOR
    step = decimal.Decimal(1).scaleb(exact.adjusted() - 3)
    return f"{float(exact.quantize(step, rounding=rounding)):.4g}"


class VelocityLimitError(DurationLimitError):
    """Joint rates above a URDF velocity limit; carries the shortest admissible duration."""

    kind = "velocity"

    def __init__(
        self,
        joint: str,
        peak: float,
        limit: float,
        shortest_duration: float,
        unit: str = "rad",
        least_duration: float = 0.0,
    ) -> None:
        super().__init__(joint, peak, limit, shortest_duration, unit, least_duration)

    def _exceeds(self, scale: float, unit: str) -> str:
        """The joint's peak rate against its limit, times ``scale`` in ``unit`` per second."""
        return (
            f"joint {self.joint!r} reaches {scale * self.peak:.4g} {unit}/s, above its "
            f"velocity limit {scale * self.limit:.4g} {unit}/s"
        )


class EffortLimitError(DurationLimitError):
    """Joint torques above a URDF effort limit; carries the shortest admissible duration."""

    kind = "effort"

    def __init__(
        self, joint: str, peak: float, limit: float, shortest_duration: float, unit: str = "N m"
    ) -> None:
        super().__init__(joint, peak, limit, shortest_duration, unit)

    def _exceeds(self, scale: float, unit: str) -> str:
        """Torques and forces are not converted (``scale`` and ``unit`` are for angles)."""
        return (
            f"joint {self.joint!r} needs {self.peak:.4g} {self.unit}, above its effort limit "
            f"{self.limit:.4g} {self.unit}"
        )


class UnreachableGoalError(FreeFloatError):
    """A goal out of reach: no configuration reaches a Cartesian goal, or no path an attitude.

    Raised as is for a Cartesian goal (with the miss and the workspace radius); an attitude
    goal beyond where the planner's search got raises the subclass
    :class:`UnreachableAttitudeError`.

    Attributes:
        distance: Cartesian goals: the smallest distance to the goal found (m); NaN otherwise.
        radius: Cartesian goals: the workspace radius (m); NaN otherwise.
    """

    def __init__(
        self, message: str, distance: float = float("nan"), radius: float = float("nan")
    ) -> None:
        self.distance = float(distance)
        self.radius = float(radius)
        super().__init__(message)


class UnreachableAttitudeError(SolverError, UnreachableGoalError):
    """A goal attitude beyond where the planner's search got.

    A :class:`SolverError` that is also an :class:`UnreachableGoalError`.
    Its message and its figures agree: ``reached`` of ``asked`` (rad, about ``axis``) is where
    the search stopped, ``best_residual`` the rest of the way (the attitude error of the path
    it stopped on, rad), ``reached_fraction = reached / asked``.

    Attributes:
        reached: the largest turn towards the goal reached by a solved path (rad).
        asked: the turn the goal asks for, from where the search started (rad).
        axis: the unit axis of that turn (base frame at the search's starting attitude).
        problem: the planning problem of the search level that stopped there (a
            :class:`~freefloat.Problem`; with ``last_beta``, the path it stopped on), when
            known.
    """

    def __init__(
        self,
        message: str,
        best_residual: float,
        reached: float,
        asked: float,
        tried: Sequence[str] = (),
        per_axis: Sequence[float] | None = None,
        hint: str = "",
        stopped_by: str = "",
        last_beta: Sequence[float] | None = None,
        axis: Sequence[float] = (0.0, 0.0, 1.0),
        problem: object | None = None,
        blocked_by: Sequence[str] = (),
    ) -> None:
        self.reached = float(reached)
        self.problem = problem
        self.asked = float(asked)
        self.axis = tuple(float(a) for a in axis)
        SolverError.__init__(
            self,
            message,
            best_residual,
            tried,
            per_axis=per_axis,
            hint=hint,
            stopped_by=stopped_by,
            reached_fraction=self.reached / self.asked if self.asked > 0.0 else 0.0,
            last_beta=last_beta,
            blocked_by=blocked_by,
        )
        self.distance = self.radius = float("nan")

    @staticmethod
    def turn_phrase(reached: float, asked: float) -> str:
        """``"reachable up to X deg of the Y deg asked"`` from turns in rad.

        Three significant digits, more (both figures alike, up to the 17 that tell any two
        floats apart) while a turn short of the one asked would print the same as it (46.8 of
        46.8 reads as reached; 46.79 of 46.8 does not).
        """
        out, goal = math.degrees(reached), math.degrees(asked)
        digits = 3
        while digits < 17 and out < goal and f"{out:.{digits}g}" == f"{goal:.{digits}g}":
            digits += 1
        return f"reachable up to {out:.{digits}g} deg of the {goal:.{digits}g} deg asked"

    def with_hint(self, more: str) -> UnreachableAttitudeError:
        """The same refusal with ``more`` added to its hint: every figure kept."""
        return self._copy(self.headline, f"{self.hint}; {more}" if self.hint else more)

    def with_headline(self, headline: str) -> UnreachableAttitudeError:
        """The same refusal under another headline: every figure and attribute kept."""
        return self._copy(headline, self.hint)

    def _copy(self, headline: str, hint: str) -> UnreachableAttitudeError:
        """This refusal with ``headline`` and ``hint``: every figure and attribute kept."""
        return UnreachableAttitudeError(
            headline,
            self.best_residual,
            reached=self.reached,
            asked=self.asked,
            tried=self.tried,
            per_axis=self.per_axis,
            hint=hint,
            stopped_by=self.stopped_by,
            last_beta=self.last_beta,
            axis=self.axis,
            problem=self.problem,
            blocked_by=self.blocked_by,
        )
