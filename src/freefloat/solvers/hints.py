"""Hints a refused search adds where the cause points at a change to the scenario.

Each takes the scenario (or its robot) and what stopped the search, and gives one clause, or
"" when it does not apply; :func:`freefloat.solvers.search.search` joins those that do to its
refusal, and ``freefloat reach`` prints the finger one under its table.
"""

from __future__ import annotations

from ..errors import FreeFloatError, SolverError
from ..problem.scenario import Scenario
from ..robot.arms import GRIPPER_JOINT
from ..robot.model import Robot

__all__ = ["REACH_CLAUSE", "extra_hint", "finger_hint", "reach_hint"]

#: What a refused goal attitude ends with, unless its hint names that command already.
REACH_CLAUSE = "freefloat reach SCENARIO prints goal attitudes that plan, per direction"


def extra_hint(scenario: Scenario, error: FreeFloatError | None) -> str:
    """When a fixed ``[path] extra`` may be the cause, say so and how to remove it."""
    if scenario.extra is None or not isinstance(error, SolverError):
        return ""
    fixed = sum(int(k) for k in scenario.extra.values())
    return (
        f"the scenario fixes [path] extra ({fixed} free coefficient(s) in all), which may be too "
        "little freedom for this goal: remove [path] extra and the planner raises the freedom "
        "as it needs (freefloat reach SCENARIO shows what is reachable)"
    )


def finger_hint(robot: Robot, stopped_by: str) -> str:
    """When a finger or gripper joint's limit stopped the search, suggest holding the fingers.

    A robot from its own URDF keeps its finger joints free (a composed servicer locks them),
    and the search may drive those light joints to their limits to turn the spacecraft.
    """
    if "joint_position_limits" not in stopped_by:
        return ""
    fingers = [j.name for j in robot.joints if GRIPPER_JOINT.search(j.name)]
    stopping = [name for name in fingers if f"'{name}'" in stopped_by]
    if not stopping:
        return ""
    listed = ", ".join(f'"{name}"' for name in fingers)
    return (
        f"joint {stopping[0]!r}, whose limit stopped it, looks like a finger or gripper joint: "
        f"to turn the spacecraft with the arm alone, lock the fingers ([robot] lock = [{listed}], "
        'in a [robot] table with urdf = "..." for a robot from its own URDF; a composed '
        "servicer locks them unless keep_gripper = true)"
    )


def reach_hint(hint: str) -> str:
    """:data:`REACH_CLAUSE` for a refused goal attitude, unless ``hint`` names the command."""
    return "" if "freefloat reach" in hint else REACH_CLAUSE
