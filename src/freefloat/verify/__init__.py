"""Independent verification of a plan, from the plan file and its URDF alone."""

from .checks import PLAN_CHECKS, verify_plan
from .plan_checks import TOLERANCES

__all__ = ["PLAN_CHECKS", "TOLERANCES", "verify_plan"]
