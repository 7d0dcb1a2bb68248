"""Links mounted on the spacecraft that can swing into it: not touching by design.

Clearance spares parent and child bodies (:func:`.geometry.checked_pairs`): they touch where
the joint joins them, by design. That holds for a shoulder on its mount; it does not for a
long first link hinged at the face of the spacecraft's hull, which the joint can swing deep
into the hull (a 1 m link 0.29 m inside it planned and verified). For every such pair of a
body fixed to the spacecraft and a body one joint away, the joint is swept over its range
(its limits; a full turn when it has none) with the other shapes fixed, and the pair's
overlap depth is measured on true convex hulls (primitives as they are; coal's signed
distance). When the depth varies by more than :func:`swing_allowance` over the range, or
stays deeper than a quarter of the link's reach (a link lodged in the spacecraft; a locked
joint: at its locked value), the pair is not touching by design: it is checked like any
other pair (its start then has to keep the margin too). Within the allowance the depth is
the shapes' own asymmetry about the axis (Astrobee's arm in its bay: 12 mm); the shipped
servicers' and example-robot-data arms' pairs do not vary at all. The relative pose of the
two bodies depends on that one joint alone, so the sweep is exact up to its spacing
(:data:`SWEEP_SAMPLES`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import coal
import numpy as np
import pinocchio as pin

from .designed_bodies import DesignedBodies
from .meshes import true_hull

__all__ = ["SWEEP_SAMPLES", "swing_allowance", "swinging_pairs"]

#: Joint values sampled over the joint's range (every 4 deg of a full turn: between two, the
#: overlap changes by at most 7 % of the reach, under the allowance).
SWEEP_SAMPLES = 91
#: The least variation of the overlap depth (m) that is a swing, not the shapes' asymmetry.
_LEAST = 0.02
#: The share of the moving shape's size (its largest distance from the joint) that is too.
_SHARE = 0.05
#: The share of its size a shape inside the spacecraft at every joint value must exceed to be
#: no mount contact but a link lodged in the spacecraft.
_DEEP = 0.25


def swing_allowance(reach: float) -> float:
    """How much the overlap depth may vary (m) for a moving shape reaching ``reach`` (m)."""
    return max(_LEAST, _SHARE * reach)


def swinging_pairs(
    model: pin.Model,
    geometry: pin.GeometryModel,
    designed: DesignedBodies,
    candidates: Sequence[tuple[int, int]],
) -> set[tuple[int, int]]:
    """The ``candidates`` (index pairs of ``geometry``, parent and child) that swing.

    Only pairs of a shape fixed to the spacecraft (the root body) and one moved by a single
    movable joint from it are swept; the others are returned as not swinging.
    """
    objects = list(geometry.geometryObjects)
    links = [model.frames[o.parentFrame].name for o in objects]
    found = set()
    for a, b in candidates:
        for fixed, moved in ((a, b), (b, a)):
            joint = designed.body(links[moved])
            if designed.body(links[fixed]) != "" or not joint or designed.parent(joint) != "":
                continue
            if model.existJointName(joint):
                swings = _swings(model, geometry, fixed, moved, model.getJointId(joint))
            else:  # locked: fixed where the lock put it (a frame of that name marks it)
                swings = _lodged(model, geometry, fixed, moved, joint)
            if swings:
                found.add((a, b))
    return found


def _swings(
    model: pin.Model, geometry: pin.GeometryModel, fixed: int, moved: int, joint: int
) -> bool:
    """Whether the overlap of shapes ``fixed`` and ``moved`` varies beyond the allowance."""
    data, gdata = model.createData(), pin.GeometryData(geometry)
    first, second = (_convex(geometry.geometryObjects[k]) for k in (fixed, moved))
    second.computeLocalAABB()
    q = pin.neutral(model)
    index, nq = model.joints[joint].idx_q, model.joints[joint].nq
    depths, reach = [], 0.0
    for value in _range(model, joint):
        q[index : index + nq] = (math.cos(value), math.sin(value)) if nq == 2 else (value,)
        pin.updateGeometryPlacements(model, data, geometry, gdata, q)
        depth, far = _depth_and_reach(first, second, gdata.oMg[fixed], gdata.oMg[moved])
        depths.append(depth)
        reach = max(reach, far(data.oMi[joint].translation))
    allowance = swing_allowance(reach)
    return max(depths) - min(depths) > allowance or min(depths) > _DEEP * reach


def _lodged(
    model: pin.Model, geometry: pin.GeometryModel, fixed: int, moved: int, joint: str
) -> bool:
    """Whether a locked joint holds shape ``moved`` inside ``fixed`` beyond the allowance.

    The lock fixes one value of the joint: the depth there, against the shape's reach.
    """
    if not model.existFrame(joint):
        return False
    data, gdata = model.createData(), pin.GeometryData(geometry)
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    pin.updateGeometryPlacements(model, data, geometry, gdata)
    first, second = (_convex(geometry.geometryObjects[k]) for k in (fixed, moved))
    second.computeLocalAABB()
    depth, far = _depth_and_reach(first, second, gdata.oMg[fixed], gdata.oMg[moved])
    return depth > swing_allowance(far(data.oMf[model.getFrameId(joint)].translation))


def _depth_and_reach(
    first: coal.CollisionGeometry, second: coal.CollisionGeometry, a: pin.SE3, b: pin.SE3
) -> tuple[float, Callable[[np.ndarray], float]]:
    """How deep (m, 0 when apart) the shapes placed at ``a`` and ``b`` overlap, and reach.

    ``reach(point)``: the farthest ``second`` reaches from a point (m, from its local box's
    bounding sphere).
    """
    distance = coal.distance(
        first,
        coal.Transform3s(a.rotation, a.translation),
        second,
        coal.Transform3s(b.rotation, b.translation),
        coal.DistanceRequest(),
        coal.DistanceResult(),
    )
    centre = b.act(np.asarray(second.aabb_center))
    radius = float(second.aabb_radius)

    def reach(origin: np.ndarray) -> float:
        return float(np.linalg.norm(centre - origin)) + radius

    return max(0.0, -float(distance)), reach


def _convex(obj: pin.GeometryObject) -> coal.CollisionGeometry:
    """A shape for signed distances: a mesh's true hull, anything else as it is."""
    if isinstance(obj.geometry, coal.BVHModelBase):
        return true_hull(obj)
    return obj.geometry


def _range(model: pin.Model, joint: int) -> np.ndarray:
    """:data:`SWEEP_SAMPLES` values over the joint's limits (rad or m).

    A full turn for a revolute joint without limits (or wider ones), 1 m either way for a
    prismatic one without.
    """
    index = model.joints[joint].idx_q
    if model.joints[joint].nq == 2:
        return np.linspace(-math.pi, math.pi, SWEEP_SAMPLES)
    lower, upper = float(model.lowerPositionLimit[index]), float(model.upperPositionLimit[index])
    prismatic = "P" in model.joints[joint].shortname().removeprefix("JointModel")
    wide = math.pi if not prismatic else 1.0
    if not (math.isfinite(lower) and math.isfinite(upper)):
        lower, upper = max(lower, -wide), min(upper, wide)
    if upper - lower > 2 * wide:  # one full turn of it (1 m either way), from its lower limit
        upper = lower + 2 * wide
    return np.linspace(lower, upper, SWEEP_SAMPLES)
