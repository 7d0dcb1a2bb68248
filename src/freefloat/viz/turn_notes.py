"""A note for a continuous joint asked to travel more than half a turn (for the summary).

A continuous joint's goal of 350 deg from a start of 0 is travelled as +350 deg; the same pose
lies at -10 deg, ten degrees away. The planner takes the goal as written (the attitude it
brings depends on the way round; ``allow_full_turns`` tries it first too), so the summary names
the shorter way: a goal to give for it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from ..robot.model import Robot

__all__ = ["long_way_line"]


def long_way_line(
    robot: Robot, start: list[float], goal: list[float], chosen: Mapping[str, int]
) -> str:
    """``""``, or a line naming the continuous joints that travel more than half a turn.

    ``start`` and ``goal``: the plan's joint values (rad or m), in joint order; ``chosen``:
    the whole turns the planner itself added per joint (``allow_full_turns``): not noted.
    """
    notes = []
    for joint, a, b in zip(robot.joints, start, goal, strict=True):
        travel = b - a
        if joint.kind == "continuous" and abs(travel) > math.pi and not chosen.get(joint.name):
            turns = round(abs(travel) / (2.0 * math.pi))
            other = travel - math.copysign(2.0 * math.pi * turns, travel)
            notes.append(
                f"{joint.name} travels {math.degrees(travel):.4g} deg; the same pose lies "
                f"{math.degrees(other):.4g} deg away"
            )
    if not notes:
        return ""
    return f"  long way round  {'; '.join(notes)} (continuous: give that goal for the short way)"
