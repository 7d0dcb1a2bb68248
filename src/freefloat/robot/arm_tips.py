"""The end effectors of a composed servicer's arms, and the link holding its payload.

Each arm's default end effector is the tip of its longest chain of movable joints that is not
a finger (:func:`~freefloat.robot.end_effectors.end_effector_candidates`, among the frames
with the arm's prefix); an arm whose longest chains tie (a dual-arm torso) has none.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..errors import AmbiguousEndEffectorError
from .payload import PAYLOAD_LINK

__all__ = ["arm_tips", "every_tip", "payload_parent"]


def arm_tips(text: str, prefixes: Sequence[str], strict: bool = True) -> tuple[str, ...]:
    """The default end effector of each arm (by its prefix) in a composed URDF.

    An arm whose longest chains tie has none: with ``strict`` that is an error
    (:class:`AmbiguousEndEffectorError`), otherwise the tuple is empty: one tip per arm, or
    none.
    """
    import pinocchio as pin

    from .end_effectors import end_effector_candidates

    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    tips = []
    for prefix in prefixes:
        found = end_effector_candidates(model, prefix)
        if len(found) > 1 and strict:
            raise AmbiguousEndEffectorError(found)
        if len(found) > 1:
            return ()
        tips.append(found[0])
    return tuple(tips)


def every_tip(text: str, prefixes: Sequence[str]) -> tuple[str, ...]:
    """Every default end-effector candidate of each arm (by its prefix), in arm order.

    An arm whose longest chains tie gives them all (:func:`arm_tips` gives none then).
    """
    import pinocchio as pin

    from .end_effectors import end_effector_candidates

    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    return tuple(tip for prefix in prefixes for tip in end_effector_candidates(model, prefix))


def payload_parent(text: str) -> str | None:
    """The link a URDF's captured payload is fixed to (its end effector), or None if none."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError:
        return None
    for joint in root.findall("joint"):
        child, parent = joint.find("child"), joint.find("parent")
        if child is not None and parent is not None and child.get("link") == PAYLOAD_LINK:
            return parent.get("link")
    return None
