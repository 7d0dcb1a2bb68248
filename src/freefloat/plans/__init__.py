"""The plan file format: typed records (records, guarantees), the plan, JSON I/O, versions."""

from .format import Plan
from .guarantees import (
    Check,
    ConstraintRecord,
    ObjectiveReport,
    RobustnessReport,
    SafetyReport,
    Verification,
)
from .records import (
    BaseReport,
    Feasibility,
    PathQuality,
    Request,
    RobotRef,
    Samples,
    SolutionRecord,
    SolverReport,
)
from .versions import FORMAT

__all__ = [
    "FORMAT",
    "BaseReport",
    "Check",
    "ConstraintRecord",
    "Feasibility",
    "ObjectiveReport",
    "PathQuality",
    "Plan",
    "Request",
    "RobotRef",
    "RobustnessReport",
    "SafetyReport",
    "Samples",
    "SolutionRecord",
    "SolverReport",
    "Verification",
]
