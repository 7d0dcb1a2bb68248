"""The smallest clearance along a plan, recomputed with its collision model (for figures).

The plan's keep-out objects and the smallest signed distance (m) over
the checked pairs at evenly spaced instants of the plan's joint polynomials
(:func:`clearance_curve`), with the pair that is closest, and the lowest point refined in time
between the samples (as the plan's own check refines it, so that the figure's label and the
plan's summary agree). Used by the ``clearance`` figure (:mod:`freefloat.viz.plots`) and the
playback page's keep-out objects.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..plans.format import Plan

if TYPE_CHECKING:
    from ..robot.collision import CollisionModel
    from ..robot.model import Robot

__all__ = ["CLEARANCE_SAMPLES", "ClearanceCurve", "LowestPoint", "clearance_curve"]

#: Instants (evenly spaced over [0, T]) at which the clearance figure recomputes distances.
CLEARANCE_SAMPLES = 400


@dataclass(frozen=True)
class LowestPoint:
    """The smallest clearance along a plan: ``distance`` (m) at ``time`` (s), of ``pair``."""

    distance: float
    time: float
    pair: int


@dataclass(frozen=True)
class ClearanceCurve:
    """The smallest clearance along a plan.

    Attributes:
        t: instants (s).
        smallest: per instant, the smallest signed distance over the checked pairs (m).
        pair: per instant, the index (into ``names``) of the pair at that distance.
        names: the checked pairs, ``"a / b"``.
        margin: the plan's clearance margin (m).
        lowest: the smallest clearance (m), its time (s) and pair (index into ``names``),
            refined between the samples.
    """

    t: np.ndarray
    smallest: np.ndarray
    pair: np.ndarray
    names: list[str]
    margin: float
    lowest: LowestPoint

    @property
    def closest(self) -> tuple[float, float, str]:
        """``(distance m, time s, pair name)`` of the smallest clearance along the plan."""
        low = self.lowest
        return low.distance, low.time, self.names[low.pair]


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
    smallest = np.array([v for v, _ in values])
    pair = np.array([k for _, k in values], dtype=int)
    return ClearanceCurve(
        t=t,
        smallest=smallest,
        pair=pair,
        names=list(model.names),
        margin=float(plan.safety.margin_m),
        lowest=_lowest(model, plan, t, smallest, pair),
    )


#: Sampled local minima within this of the smallest are refined in time (m).
_NEAR = 0.01
#: At most this many of them, the lowest (a count).
_REFINED = 8


def _lowest(
    model: CollisionModel, plan: Plan, t: np.ndarray, smallest: np.ndarray, pair: np.ndarray
) -> LowestPoint:
    """The smallest clearance (m), its time (s) and pair, each near-lowest sample refined.

    A bounded scalar search between the neighbouring samples of the sampled local minima
    within :data:`_NEAR` of the smallest, the lowest :data:`_REFINED` of them (to 1e-9 of
    the duration).
    """
    from ..problem.scalar_minimum import scalar_minimum

    def at(s: float) -> tuple[float, int]:
        return model.closest_value(plan.joint_positions(np.array([s]))[0])

    k = int(np.argmin(smallest))
    best = LowestPoint(float(smallest[k]), float(t[k]), int(pair[k]))
    inner = (smallest[1:-1] <= smallest[:-2]) & (smallest[1:-1] <= smallest[2:])
    ends = [0] if smallest[0] <= smallest[1] else []
    ends += [len(t) - 1] if smallest[-1] <= smallest[-2] else []
    minima = [
        k
        for k in {*ends, *(np.flatnonzero(inner) + 1).tolist()}
        if smallest[k] <= best.distance + _NEAR
    ]
    # the first of a run of equal samples only (a pair whose distance stays put is a run of
    # minima), and the lowest few: the figure's label needs the lowest point alone
    minima = [k for k in minima if k == 0 or smallest[k] != smallest[k - 1]]
    for k in sorted(minima, key=lambda k: (smallest[k], k))[:_REFINED]:
        low, high = t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]
        found = scalar_minimum(lambda s: at(s)[0], low, high, 1e-9 * plan.duration)
        if found.value < best.distance:
            best = LowestPoint(found.value, found.x, at(found.x)[1])
    return best
