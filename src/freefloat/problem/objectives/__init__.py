"""Objectives: which of the paths that reach the goal is best (docs/method.md section 13)."""

from .base import Level, Objective, ObjectiveValue, gauss_legendre
from .min_acceleration import MinAcceleration
from .min_effort import MinEffort
from .min_length import MinLength
from .min_norm import MinNorm
from .registry import DEFAULT_OBJECTIVE, OBJECTIVES, objective_named

__all__ = [
    "DEFAULT_OBJECTIVE",
    "OBJECTIVES",
    "Level",
    "MinAcceleration",
    "MinEffort",
    "MinLength",
    "MinNorm",
    "Objective",
    "ObjectiveValue",
    "gauss_legendre",
    "objective_named",
]
