"""How far a pair's signed distance can move when the joints move: a bound that spares queries.

The solvers ask for the smallest distance over every checked pair at many configurations
along a path. A pair measured at one configuration bounds its distance at any other: the
shapes are rigid, so their signed distance changes no more than their points move relative
to each other, and :func:`motion_weights` bounds that per joint (m per rad). A pair whose
lower bound exceeds another pair's upper bound cannot be the closest, and need not be measured
(:class:`~freefloat.robot.collision.CollisionModel`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .model import Robot

__all__ = ["BOUND_SLACK", "motion_weights"]

#: Allowance (m) for the error of a measured distance, in the bound of a pair not measured
#: (a thousand times coal's GJK and EPA tolerance).
BOUND_SLACK = 1e-6


def motion_weights(
    robot: Robot,
    geometry: pin.GeometryModel,
    pairs: Sequence[tuple[int, int]],
    centres: np.ndarray,
    radii: np.ndarray,
) -> np.ndarray | None:
    """How fast each pair's signed distance can change with each joint (P x N, m per rad).

    A joint that moves both bodies of a pair (an ancestor of both) moves them as one rigid
    body and leaves their distance unchanged; a revolute joint that moves one of them moves
    each of its points at most ``rho`` per rad, ``rho`` the distance from the joint's origin
    (on its axis) to the farthest point of the body's bounding sphere: at most the lengths of
    the joint offsets down the chain, plus the sphere's centre offset and radius (rotations
    keep lengths). A signed distance changes no more than its two shapes' points move, so
    ``|d(q) - d(q')| <= weights[p] @ |q - q'|`` along the straight line between any two
    joint vectors. With a prismatic joint the lengths change with it: None (no bound).
    """
    if any(not joint.angular for joint in robot.joints):
        return None
    weights = np.zeros((len(pairs), robot.n))
    model = robot.model
    column = {joint.index: k for k, joint in enumerate(robot.joints)}
    objects = list(geometry.geometryObjects)

    def reach(index: int) -> dict[int, float]:
        obj = objects[index]
        length = float(np.linalg.norm(obj.placement.act(centres[index]))) + float(radii[index])
        out, joint = {}, int(obj.parentJoint)
        while joint in column:  # arm joints; the spacecraft (free flyer) and the world end it
            out[column[joint]] = length
            length += float(np.linalg.norm(model.jointPlacements[joint].translation))
            joint = int(model.parents[joint])
        return out

    reaches = [reach(i) for i in range(len(objects))]
    for p, (a, b) in enumerate(pairs):
        for one, other in ((reaches[a], reaches[b]), (reaches[b], reaches[a])):
            for k, rho in one.items():
                if k not in other:
                    weights[p, k] = rho
    return weights
