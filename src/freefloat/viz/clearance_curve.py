"""The smallest clearance along a plan, recomputed with its collision model (for figures).

The plan's keep-out objects and the smallest signed distance (m) over
the checked pairs at evenly spaced instants of the plan's joint polynomials
(:func:`clearance_curve`), with the pair that is closest. Used by the ``clearance`` figure
(:mod:`freefloat.viz.plots`) and the playback page's keep-out objects.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..plans.format import Plan

if TYPE_CHECKING:
    from ..robot.model import Robot

__all__ = ["CLEARANCE_SAMPLES", "ClearanceCurve", "clearance_curve"]

#: Instants (evenly spaced over [0, T]) at which the clearance figure recomputes distances.
CLEARANCE_SAMPLES = 400


@dataclass(frozen=True)
class ClearanceCurve:
    """The smallest clearance along a plan.

    Attributes:
        t: instants (s).
        smallest: per instant, the smallest signed distance over the checked pairs (m).
        pair: per instant, the index (into ``names``) of the pair at that distance.
        names: the checked pairs, ``"a / b"``.
        margin: the plan's clearance margin (m).
    """

    t: np.ndarray
    smallest: np.ndarray
    pair: np.ndarray
    names: list[str]
    margin: float

    @property
    def closest(self) -> tuple[float, float, str]:
        """``(distance m, time s, pair name)`` of the smallest clearance along the plan."""
        k = int(np.argmin(self.smallest))
        return float(self.smallest[k]), float(self.t[k]), self.names[int(self.pair[k])]


def clearance_curve(
    plan: Plan, samples: int = CLEARANCE_SAMPLES, robot: Robot | None = None
) -> ClearanceCurve | None:
    """The smallest clearance on ``samples`` instants of the plan's joint polynomials.

    None when the plan was not kept clear (``plan.safety.checked`` false) or has no pairs.

    Raises:
        FreeFloatError: the robot or its collision model cannot be loaded.
    """
    if not plan.safety.checked:
        return None
    from ..plans.robot_copy import plan_robot
    from ..robot.collision import CollisionModel

    robot = robot or plan_robot(plan)
    model = CollisionModel(robot, plan.safety.srdf, plan.safety.obstacles)
    if model.n_pairs == 0:
        return None
    t = np.linspace(0.0, plan.duration, max(2, int(samples)))
    joints = plan.joint_positions(t)
    values = [model.closest_value(q) for q in joints]
    return ClearanceCurve(
        t=t,
        smallest=np.array([v for v, _ in values]),
        pair=np.array([k for _, k in values], dtype=int),
        names=list(model.names),
        margin=float(plan.safety.margin_m),
    )
