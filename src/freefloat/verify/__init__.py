"""Independent verification of a plan, from the plan file and its URDF alone."""

from .checks import TOLERANCES, verify_plan

__all__ = ["TOLERANCES", "verify_plan"]
