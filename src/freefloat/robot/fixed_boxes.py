"""Lower bounds of pairs' signed distances from the faces of boxes fixed to the spacecraft.

The collision model measures a pair exactly (coal) only when its lower bound says it may be the
closest (:mod:`freefloat.robot.collision`). One bounding sphere per shape bounds a box
poorly: the spacecraft's body, a cube 0.6 m wide on the shipped servicers, has a sphere of
radius 0.52 m, which stands 0.22 m off its faces. A box fixed to the spacecraft (its body, a
keep-out box) keeps its place in the collision model's frame (the spacecraft at the identity),
so its faces bound its pairs at the cost of one product: the signed distance from the box to
the other shape's bounding-sphere centre, less that sphere's radius, is at most the shapes'
signed distance (the other shape lies in its sphere, and a box against a ball is exactly
that; negative: the depth of an overlap). Each bound is lowered by :data:`ROUNDING` (m) for
the rounding of the arithmetic.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from .model import Robot

__all__ = ["ROUNDING", "FixedBoxes"]

#: Subtracted from every bound (m): the rounding of the arithmetic, with room to spare.
ROUNDING = 1e-9


class FixedBoxes:
    """The boxes fixed to the spacecraft, and the bounds their faces give their pairs.

    Args:
        robot: the robot (a shape moves with it when one of its joints carries the shape).
        geometry: the collision geometry model.
        pairs: (P, 2) the checked pairs (shape indices).
        radii: (G,) each shape's bounding-sphere radius (m), about the centres the bounds are
            given.
    """

    def __init__(
        self, robot: Robot, geometry: pin.GeometryModel, pairs: np.ndarray, radii: np.ndarray
    ) -> None:
        model = robot.model
        moving = {joint.index for joint in robot.joints}
        fixed = {j for j in range(model.njoints) if not moving & set(model.supports[j])}
        # where the fixed shapes are: the spacecraft at the identity, other joints neutral
        data, placed = model.createData(), pin.GeometryData(geometry)
        pin.updateGeometryPlacements(model, data, geometry, placed, pin.neutral(model))
        objects = list(geometry.geometryObjects)
        pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
        boxes = {
            g
            for g, obj in enumerate(objects)
            if isinstance(obj.geometry, coal.Box) and int(obj.parentJoint) in fixed
        }
        #: the pairs with such a box (two such boxes: the first), the box and the other shape
        chosen = [k for k, (a, b) in enumerate(pairs.tolist()) if a in boxes or b in boxes]
        self.pairs = np.array(chosen, dtype=int)
        box = [a if a in boxes else b for a, b in pairs[chosen].tolist()]
        self._other = np.array(
            [b if a == g else a for g, (a, b) in zip(box, pairs[chosen].tolist(), strict=True)],
            dtype=int,
        )
        poses = [placed.oMg[g] for g in box]
        #: per chosen pair: its box's axes (columns), centre (m) and half sides (m)
        self._axes = np.array([p.rotation for p in poses]).reshape(-1, 3, 3)
        self._centre = np.array([p.translation for p in poses]).reshape(-1, 3)
        self._half = np.array([objects[g].geometry.halfSide for g in box], float).reshape(-1, 3)
        self._radius = np.asarray(radii, dtype=float)[self._other]

    def lower(self, centres: np.ndarray) -> np.ndarray:
        """(B, len(pairs)) lower bounds (m) of the chosen pairs' signed distances.

        ``centres``: (B, G, 3) every shape's bounding-sphere centre in the model's frame (m).
        """
        offset = centres[:, self._other] - self._centre  # (B, C, 3)
        x, y, z = offset[..., 0], offset[..., 1], offset[..., 2]
        outside = np.zeros(offset.shape[:2])
        deepest = np.full(offset.shape[:2], -np.inf)
        for k in range(3):  # the centres' coordinates along each box axis, beyond its face
            axis, half = self._axes[:, :, k], self._half[:, k]
            beyond = np.abs(x * axis[:, 0] + y * axis[:, 1] + z * axis[:, 2]) - half
            outside += np.square(np.maximum(beyond, 0.0))
            np.maximum(deepest, beyond, out=deepest)
        # outside: the distance to the box; inside: minus the depth to the nearest face
        return np.sqrt(outside) + np.minimum(deepest, 0.0) - self._radius - ROUNDING
