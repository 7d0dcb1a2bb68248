"""The constraint interface: what every path constraint tells the solvers and the checker.

A constraint is a small object with a name, a unit and a tolerance. It gives the solvers its
values ``g`` (``g <= 0`` is feasible, in its unit) and their exact Jacobian with respect to
the free path coefficients ``beta`` at a set of normalised instants; and it gives verification
a dense, independent measure of how far a finished path goes beyond it, computed from the
path's time polynomials alone (no solver data). Solvers receive constraints as a list; adding
one means one new module with a subclass, plus its name in :mod:`.registry`.

A constraint writes and reads its own parameters (:meth:`Constraint.to_record` and
:meth:`Constraint.from_record`): the same table is a scenario's ``[constraints.<name>]`` and a
plan's ``constraints`` record, so a plan names every constraint it honours and
``freefloat verify`` rebuilds them from the registry (docs/developers.md).
"""

from __future__ import annotations

import abc
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import DurationLimitError, InputError, excerpt
from ...robot.model import Joint, Robot
from ..paths import JointPolynomials
from ..residual import Problem

__all__ = [
    "DEFAULT_INSTANTS",
    "Constraint",
    "ConstraintRows",
    "DurationScaledLimit",
    "Excess",
    "LimitPeak",
    "check_record_keys",
]

#: Normalised instants at which solvers impose constraints by default (s = t / T in [0, 1]).
DEFAULT_INSTANTS = np.linspace(0.0, 1.0, 97)


@dataclass(frozen=True)
class ConstraintRows:
    """Constraint values ``g(beta) <= 0`` and their Jacobian at a set of instants.

    Attributes:
        values: (M,) values in the constraint's unit; feasible where ``<= 0``.
        jacobian: (M, n_free) exact ``dg/dbeta``.
    """

    values: np.ndarray
    jacobian: np.ndarray

    @property
    def count(self) -> int:
        """Number of rows M."""
        return len(self.values)


@dataclass(frozen=True)
class Excess:
    """How far a path goes beyond a constraint, and where.

    Attributes:
        value: the largest excess (in the constraint's unit; <= 0 when inside everywhere).
        error_estimate: numerical error of ``value`` (same unit); 0 when exact.
        detail: where the worst value occurs (joint and time), for the reader.
    """

    value: float
    error_estimate: float = 0.0
    detail: str = ""


class Constraint(abc.ABC):
    """One path constraint (see the module docstring).

    Attributes:
        name: identifier, also the name of its check in a plan's verification.
        unit: unit of the values, the tolerance and the excess.
        tolerance: the largest excess verification accepts (unit), beyond rounding.
        affine: whether ``g`` is affine in ``beta`` (then its Jacobian is constant).
        lazy: whether planning first ignores it and imposes it only when the path found
            breaks it (for constraints whose rows are costly and rarely bind).
        own_instants: whether its rows sit at instants it picks itself: the solvers ask it
            only at those and at its :meth:`critical_times` where a path they found breaks
            it between them (:func:`~freefloat.solvers.rows.with_dips`), not at the other
            constraints' instants.
    """

    name: str = "constraint"
    unit: str = "1"
    tolerance: float = 1e-9
    affine: bool = False
    lazy: bool = False
    own_instants: bool = False

    @abc.abstractmethod
    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """Values ``g(beta)`` (feasible ``<= 0``) and exact Jacobian at normalised instants."""

    @abc.abstractmethod
    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """Dense, independent measure of the largest excess along a finished path."""

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) where the constraint is tightest along a finished path.

        Solvers that impose the constraint at instants add these, so that a path inside at the
        instants is inside everywhere. Default: none.
        """
        return np.zeros(0)

    def tight_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """Normalised instants near where the path at ``beta`` is tightest, found cheaply.

        Solvers impose the rows there too at every step, so that the path they correct is
        inside between their instants as well. Default: none.
        """
        return np.zeros(0)

    def picked_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """Normalised instants a constraint with its own instants picks for its rows at ``beta``.

        Beyond those every path shares (a refinement about the path's tightest instants): a
        Newton corrector keeps rows at those of every iterate, so that the rows do not jump
        from one iterate to the next. Default: none.
        """
        return np.zeros(0)

    def end_rows(self, problem: Problem, beta: np.ndarray) -> ConstraintRows:
        """Rows at the end of a path that need not reach the goal (``g <= 0``, its unit).

        :meth:`rows` leave out an end no path at the goal changes (the goal attitude's,
        judged before any search); a start path found with the attitude ignored
        (:func:`~freefloat.solvers.restore.feasible_start`) ends anywhere, and these rows hold
        that end inside. Default: none.
        """
        return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))

    def solver_slack(self, problem: Problem, instants: np.ndarray) -> np.ndarray:
        """(K,) how far inside its rows ask a path to be at ``instants`` (its unit).

        Rows at instants hold a path there, not between them: a constraint whose rows have
        no :meth:`critical_times` in some solver's use (a start path found with fixed
        instants) asks for a little room, so that the dense check passes between them
        (:func:`.slack.tapered_slack`). Default: none (0, a 0-d array, whatever its rows).
        """
        return np.zeros(())

    def violation(self, problem: Problem, beta: np.ndarray) -> Excess:
        """:meth:`excess` of the problem's path at ``beta`` (for solvers filtering roots)."""
        return self.excess(problem.robot, problem.polynomials(beta))

    def applies_to(self, robot: Robot) -> bool:
        """Whether the constraint has anything to check on this robot (default: yes)."""
        return True

    def at_rest(self, robot: Robot, joints: np.ndarray) -> Excess | None:
        """Its excess at one configuration held at rest (rad or m), or None.

        Every path of the family starts and ends at rest at the scenario's start and goal, so
        a constraint of the configuration alone that either breaks holds on no path: ``plan``
        refuses it before any search (:func:`freefloat.problem.endpoints.check_endpoints`)
        and ``check`` reports it. None (the default): the constraint judges more than the
        configuration (rates, torques) or is checked on its own (joint limits, clearance).
        """
        return None

    def at_attitude(self, relative: np.ndarray) -> Excess | None:
        """Its excess at a rest attitude, or None (the default: it does not judge attitudes).

        ``relative``: the attitude relative to the start, ``q(0)^-1 q`` (``[x, y, z, w]``;
        the identity is the start's). Every path starts and ends at rest at the start and
        goal attitudes: a constraint of the spacecraft's attitude that either breaks holds on
        no path, and ``plan`` refuses it before any search
        (:func:`freefloat.problem.endpoints.check_end_attitudes`).
        """
        return None

    def restarted(self, turn: np.ndarray) -> Constraint:
        """The same constraint for a motion that starts at another attitude (a correction).

        ``turn``: the new start attitude relative to the old one, ``q_old^-1 q_new``
        (``[x, y, z, w]``). What is fixed in space stays where it was: a direction given in the
        old start frame is given in the new one (``base_pointing``). Default: the constraint
        itself (it does not depend on the spacecraft's attitude, or it measures from the
        motion's own start, as ``base_swing`` does).
        """
        return self

    def to_record(self) -> dict[str, Any]:
        """The constraint's parameters, JSON-ready, as a plan and a scenario write them.

        Angles in degrees (keys ending ``_deg``), lengths in metres. Default: no parameters.
        ``type(self).from_record(self.to_record())`` is the same constraint.
        """
        return {}

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> Constraint:
        """The constraint its parameters describe (as :meth:`to_record` writes them).

        Raises:
            InputError: an unknown, missing or bad parameter, named, with what is valid.
        """
        if record:
            raise InputError(
                f"constraint {cls.name!r} takes no parameters, got {', '.join(map(repr, record))}"
            )
        return cls()

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def check_record_keys(
    name: str, record: Mapping[str, Any], keys: tuple[str, ...], required: tuple[str, ...]
) -> None:
    """Refuse a constraint record with a key not in ``keys`` or without one of ``required``.

    Raises:
        InputError: the first unknown or missing key, named with the valid ones.
    """
    unknown = [k for k in record if k not in keys]
    missing = [k for k in required if k not in record]
    if unknown or missing:
        what = f"unknown key {excerpt(unknown[0])}" if unknown else f"missing {missing[0]!r}"
        listed = f"its keys are {', '.join(keys)}" if len(keys) > 1 else f"its key is {keys[0]}"
        raise InputError(f"{name}: {what}; {listed}")


@dataclass(frozen=True)
class LimitPeak:
    """The joint that comes closest to (or goes furthest beyond) its limit along a path.

    Attributes:
        joint: the joint.
        peak: its largest value of the limited quantity (the limit's unit).
        limit: its URDF limit.
        fraction: ``peak / limit`` (above 1: beyond the limit).
        shortest_duration: the shortest duration (s) at which the same path shape respects
            every limit of this kind.
        least_duration: no path between the same start and goal respects every limit of
            this kind in less (s; 0 when not known).
    """

    joint: Joint
    peak: float
    limit: float
    fraction: float
    shortest_duration: float
    least_duration: float = 0.0


class DurationScaledLimit(Constraint):
    """A limit on a quantity that scales as ``T^-power`` for a fixed path shape.

    Rates (power 1) and torques (power 2) of a path run in ``T`` seconds are those of the same
    path run in one second times ``T^-power``; the path shape does not depend on ``T``, so the
    shortest duration that respects the limits is exact:
    ``T_min = T * max_i(peak_i / limit_i)^(1 / power)``.
    """

    power: int = 1

    @abc.abstractmethod
    def worst(self, robot: Robot, path: JointPolynomials) -> LimitPeak | None:
        """The joint whose peak is the largest fraction of its limit; None when none has one."""

    @abc.abstractmethod
    def error(self, peak: LimitPeak) -> DurationLimitError:
        """The error that names ``peak`` and the shortest duration."""

    def shortest_duration(self, robot: Robot, path: JointPolynomials) -> float:
        """The shortest duration (s) at which this path shape respects every such limit."""
        peak = self.worst(robot, path)
        return 0.0 if peak is None else peak.shortest_duration
