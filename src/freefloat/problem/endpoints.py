"""Start and goal checked before any search: inside the joint limits, clear of collisions.

``plan`` and ``reach`` refuse the same scenarios for the same reason: a motion whose start or
goal breaks a limit or the clearance margin cannot be planned, whatever the attitude asked.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import CollisionError
from ..robot.collision import clearance_at
from .build import check_joint_limits
from .constraints import Clearance, Constraint
from .scenario import Scenario

__all__ = ["check_endpoints"]


def check_endpoints(
    scenario: Scenario, constraints: Sequence[Constraint], chosen_goal: bool = False
) -> None:
    """Refuse a start or goal outside the joint limits, then one too close to a collision.

    Limits first: an overlap of a pose the arm cannot take says nothing useful. Each refusal
    names the joint or the pair; ``chosen_goal``: the goal joints came from inverse
    kinematics of an end-effector goal (the refusal asks to move that goal).

    Raises:
        JointLimitError: the start or goal joints outside their limits (rad or m).
        CollisionError: a checked pair of the start or goal closer than the clearance margin
            of a :class:`Clearance` among ``constraints`` (m).
    """
    for where, values in (("start", scenario.start), ("goal", scenario.goal)):
        check_joint_limits(scenario.robot, np.asarray(values, dtype=float), where)
    for constraint in constraints:
        if isinstance(constraint, Clearance) and constraint.applies_to(scenario.robot):
            for where, joints in (("start", scenario.start), ("goal", scenario.goal)):
                clearance, pair = clearance_at(constraint.model, joints)
                if clearance < constraint.margin:
                    chosen = chosen_goal and where == "goal"
                    raise CollisionError(where, pair, clearance, constraint.margin, chosen)
