"""The plan file format (typed records, JSON, schema version)."""

from .format import (
    FORMAT,
    BaseReport,
    Check,
    Feasibility,
    Plan,
    Request,
    RobotRef,
    Samples,
    SolutionRecord,
    SolverReport,
    Verification,
)

__all__ = [
    "FORMAT",
    "BaseReport",
    "Check",
    "Feasibility",
    "Plan",
    "Request",
    "RobotRef",
    "Samples",
    "SolutionRecord",
    "SolverReport",
    "Verification",
]
