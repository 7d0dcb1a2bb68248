"""Which frame of a robot is its end effector when the scenario does not say.

The tip of the longest chain of movable joints that is not a gripper finger: a planner's
default must not be a finger a composed gripper carries.
"""

from __future__ import annotations

import re

import pinocchio as pin

__all__ = ["FINGER_NAME", "end_effector_candidates"]

_TOOL_NAME = re.compile(r"tcp|end_?effector|eef|tool|(^|_)ee($|_)", re.IGNORECASE)
#: Joint and link names of gripper fingers: never the default end effector.
FINGER_NAME = re.compile(r"finger|gripper", re.IGNORECASE)


def end_effector_candidates(model: pin.Model, prefix: str = "") -> list[str]:
    """The frame at the tip of each longest chain of movable joints that is not a finger.

    Body frames carried by a gripper or finger joint, or named like one (``finger``,
    ``gripper``), are left out, as is a captured payload's link. Depth counts the movable
    joints from the base. Among the bodies carried by one deepest joint, a frame named like a
    tool (``tcp``, ``end_effector``, ``eef``, ``tool``, ``ee``) wins; otherwise the latest in
    tree order. One name per deepest joint, in tree order. With ``prefix``, only frames whose
    name starts with it (one arm of a composed servicer).
    """
    finger_joints = {j for j in range(2, model.njoints) if FINGER_NAME.search(model.names[j])}
    bodies = []
    for index, frame in enumerate(model.frames):
        if frame.type != pin.FrameType.BODY or frame.name == "captured_payload":
            continue
        if not frame.name.startswith(prefix):
            continue
        support = list(model.supports[frame.parentJoint])
        if _on_a_finger(model, index) or finger_joints.intersection(support):
            continue
        depth = sum(1 for j in support if j >= 2)
        bodies.append((depth, frame.parentJoint, bool(_TOOL_NAME.search(frame.name)), index))
    if not bodies:  # every body is a finger's: fall back to the deepest of all
        return [_deepest(model, prefix)]
    deepest = max(b[0] for b in bodies)
    best: dict[int, tuple[bool, int]] = {}
    for depth, joint, tool, index in bodies:
        if depth == deepest:
            best[joint] = max(best.get(joint, (False, -1)), (tool, index))
    return [model.frames[best[joint][1]].name for joint in sorted(best)]


def _on_a_finger(model: pin.Model, index: int) -> bool:
    """Whether a frame is named like a finger or hangs below a (locked) finger joint.

    Walks up the frame tree through fixed joints and bodies to the movable joint carrying it.
    """
    seen = set()
    while index not in seen:
        seen.add(index)
        frame = model.frames[index]
        if FINGER_NAME.search(frame.name):
            return True
        if frame.type == pin.FrameType.JOINT:
            return False
        index = int(frame.parentFrame)
    return False


def _deepest(model: pin.Model, prefix: str) -> str:
    bodies = [
        (len(model.supports[frame.parentJoint]), index, frame.name)
        for index, frame in enumerate(model.frames)
        if frame.type == pin.FrameType.BODY
        and frame.name != "captured_payload"
        and frame.name.startswith(prefix)
    ]
    return max(bodies)[2]
