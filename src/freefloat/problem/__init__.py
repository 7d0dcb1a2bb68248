"""The planning problem: scenario, joint paths, constraints, bounds and the residual h(beta)."""

from .bounds import PlanarBounds, planar_bounds
from .build import build_problem, problem_from_scenario
from .constraints import (
    Constraint,
    ConstraintRows,
    Excess,
    JointPositionLimits,
    JointVelocityLimits,
)
from .paths import JointPolynomials, PathFamily
from .residual import Problem
from .scenario import Scenario, default_scenario_path

__all__ = [
    "Constraint",
    "ConstraintRows",
    "Excess",
    "JointPolynomials",
    "JointPositionLimits",
    "JointVelocityLimits",
    "PathFamily",
    "PlanarBounds",
    "Problem",
    "Scenario",
    "build_problem",
    "default_scenario_path",
    "planar_bounds",
    "problem_from_scenario",
]
