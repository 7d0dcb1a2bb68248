"""The plan's records of what it honours and how that was checked.

The constraints it honours (:class:`ConstraintRecord`, by registered name with parameters), its
objective (:class:`ObjectiveReport`), its clearance (:class:`SafetyReport`), its robustness to
mass-property errors (:class:`RobustnessReport`) and the independent checks of all of them
(:class:`Verification` of :class:`Check`, each with its own numerical error estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..problem.objectives.base import Level
from ..robot.collision import Obstacle

__all__ = [
    "Check",
    "ConstraintRecord",
    "ObjectiveReport",
    "RobustnessReport",
    "SafetyReport",
    "Verification",
]


@dataclass(frozen=True)
class Check:
    """One independent check of a plan.

    Attributes:
        name: the check's name (``momentum``, ``replay_attitude``, ``joint_position_limits``...).
        value: what was measured (in ``unit``).
        tolerance: the largest value the physics allows (in ``unit``).
        unit: unit of ``value``, ``tolerance`` and ``error_estimate`` (``rad``, ``m``,
            ``kg m^2/s``, ``1`` for relative figures...).
        error_estimate: the check's own numerical error (same unit): a plan is judged against
            ``tolerance + error_estimate``, so a coarse checker never refuses a valid plan.
        detail: where the worst value occurs (a joint, a time), for the reader.
    """

    name: str
    value: float
    tolerance: float
    unit: str
    error_estimate: float = 0.0
    detail: str = ""

    @property
    def passed(self) -> bool:
        """Whether ``value <= tolerance + error_estimate`` (NaN never passes)."""
        return math.isfinite(self.value) and self.value <= self.tolerance + self.error_estimate

    @property
    def verdict(self) -> str:
        """``"ok"``, ``"FAILED"``, or ``"no verdict"``.

        Ok: within the tolerance whatever the check's own error (``value + error_estimate <=
        tolerance``). No verdict: within its own error of the tolerance, on either side, so
        the check cannot tell (a forward-dynamics replay whose steps do not resolve a long
        motion, say); the plan is not refused for it (:attr:`passed`), and says so rather
        than "ok". FAILED: beyond the tolerance by more than its error.
        """
        if not self.passed:
            return "FAILED"
        return "ok" if self.value + self.error_estimate <= self.tolerance else "no verdict"


@dataclass(frozen=True)
class Verification:
    """Results of the independent checks of a plan; ``passed`` only if every check holds."""

    checks: tuple[Check, ...] = ()

    @property
    def passed(self) -> bool:
        """True when there are checks and every one passed."""
        return bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def failures(self) -> list[str]:
        """Names of the checks that failed."""
        return [c.name for c in self.checks if not c.passed]

    def __getitem__(self, name: str) -> Check:
        for check in self.checks:
            if check.name == name:
                return check
        raise KeyError(f"no check {name!r}; checks: {', '.join(c.name for c in self.checks)}")

    def __contains__(self, name: object) -> bool:
        return any(c.name == name for c in self.checks)


@dataclass(frozen=True)
class SafetyReport:
    """What the plan was kept clear of.

    Attributes:
        checked: whether clearance was a constraint (and so a verification check).
        margin_m: required clearance between checked bodies (m).
        srdf: the SRDF whose disabled pairs were not checked, if any.
        obstacles: keep-out objects fixed to the spacecraft (the collision model's own).
        note: why clearance was not checked (``[safety] check = false``, no collision
            geometry), or the movable bodies it could not check; empty when all were.
    """

    checked: bool = False
    margin_m: float = 0.01
    srdf: str | None = None
    obstacles: list[Obstacle] = field(default_factory=list)
    note: str = ""


@dataclass(frozen=True)
class ConstraintRecord:
    """One constraint a plan honours, as the registry rebuilds it.

    Attributes:
        name: its name in :data:`~freefloat.problem.constraints.CONSTRAINTS`.
        parameters: what its ``to_record()`` wrote (degrees for angles, metres).
    """

    name: str
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class ObjectiveReport:
    """Which of the paths that reach the goal the plan is, and how good it is.

    Attributes:
        name: the objective (``min_norm``, ``min_effort``, ``min_acceleration``, ``min_length``).
        unit: unit of the values.
        value: the objective along the plan, at its duration.
        error_estimate: numerical error of ``value`` (0 when exact).
        quadrature_nodes: Gauss-Legendre nodes of ``value`` (0 when exact).
        duration_power: ``p`` in ``value(T) = value(1 s) T^-p``: the value at another
            duration of the same path.
        start_value: the objective along the minimum-norm path the search found first.
        levels: the freedom levels tried, in order.
        parameters: what the objective's ``to_record()`` wrote (``freefloat.plan/4``).
    """

    name: str = "min_norm"
    unit: str = "rad^2"
    value: float | None = None
    error_estimate: float = 0.0
    quadrature_nodes: int = 0
    duration_power: int = 0
    start_value: float | None = None
    levels: list[Level] = field(default_factory=list)
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RobustnessReport:
    """First-order final attitude error under an uncertainty of the mass properties.

    Attributes:
        mass_fraction: uncertainty of every body's mass (fraction, 0.05 = 5 %).
        com_m: of every centre-of-mass coordinate (m).
        inertia_fraction: of every inertia component's scale (fraction).
        rms_rad: RMS final attitude error, the parameters independent with those standard
            deviations (rad).
        worst_rad: largest final attitude error, every parameter within those bounds (rad).
    """

    mass_fraction: float
    com_m: float
    inertia_fraction: float
    rms_rad: float
    worst_rad: float
