"""Solvers of the attitude equations: strategies behind one dispatcher."""

from .dispatch import STRATEGIES, choose_strategy, solve
from .options import DEFAULT_TOLERANCE, Attempt, Root, Solution, SolveOptions, Strategy

__all__ = [
    "DEFAULT_TOLERANCE",
    "STRATEGIES",
    "Attempt",
    "Root",
    "Solution",
    "SolveOptions",
    "Strategy",
    "choose_strategy",
    "solve",
]
