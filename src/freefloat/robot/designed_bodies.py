"""The arm's bodies as designed: links grouped by the joint that moves them, locked or not.

A locked joint (``[robot] lock``, ``compose --lock``, a composed arm's fingers) becomes a fixed
joint in the URDF freefloat loads, and Pinocchio merges what it carries into its parent's
body. Which bodies touch by design (parent and child, spared by the clearance rules:
:func:`freefloat.robot.geometry.checked_pairs`) is a fact of the arm as built, not of the
lock: with the UR5's first joint locked, its upper arm hangs from the merged shoulder and
spacecraft, yet it still may not enter the spacecraft. So every joint freefloat locks is
marked in the URDF it writes (:data:`LOCKED_ATTRIBUTE`, its locked value in rad or m; urdfdom
and Pinocchio ignore it), and the bodies here count a marked joint as a moving one. Joints
fixed in the arm's own URDF are rigid as designed.
"""

from __future__ import annotations

import re
from functools import lru_cache

import pinocchio as pin

from .urdf_checks import urdf_document

__all__ = ["GRASPING_NAME", "LOCKED_ATTRIBUTE", "DesignedBodies", "designed_bodies", "finger_of"]

#: The attribute freefloat puts on a joint it locked (the locked value, rad or m).
LOCKED_ATTRIBUTE = "freefloat_locked"

_MOVING = ("revolute", "continuous", "prismatic", "planar", "floating")


class DesignedBodies:
    """Each link's designed body (the joint that moves it; ``""`` for the root's), its parent.

    Args:
        links: ``{link: (joint, parent link, moves)}`` for every link with a parent joint,
            ``moves`` true for a movable or locked joint.
    """

    def __init__(self, links: dict[str, tuple[str, str, bool]]) -> None:
        self._links = links
        self._body: dict[str, str] = {}
        #: The link each moving (or locked) joint hangs from.
        self._mount = {joint: parent for joint, parent, moves in links.values() if moves}

    def body(self, link: str) -> str:
        """The joint moving ``link`` as designed (``""``: the root's body, or an unknown link)."""
        if link not in self._body:
            seen, here = [], link
            while here in self._links and not self._links[here][2]:
                seen.append(here)
                here = self._links[here][1]
                if len(seen) > len(self._links):  # a loop: check_urdf_xml refuses these
                    break
            found = self._links[here][0] if here in self._links else ""
            for name in [link, *seen]:
                self._body[name] = found
        return self._body[link]

    def parent(self, body: str) -> str | None:
        """The body ``body`` is mounted on (None for the root's)."""
        mount = self._mount.get(body)
        return None if mount is None else self.body(mount)

    def placed(self, link: str) -> tuple[str, str | None]:
        """``link``'s designed body and that body's parent (what its pairs depend on)."""
        body = self.body(link)
        return body, self.parent(body)

    def adjacent(self, first: str, second: str) -> bool:
        """Whether the links ``first`` and ``second`` lie on parent and child bodies."""
        a, b = self.body(first), self.body(second)
        return a != b and (self.parent(a) == b or self.parent(b) == a)

    def held_apart(self, first: str, second: str) -> bool:
        """Whether locks hold ``first`` and ``second`` together on bodies that do not touch.

        As designed the two links lie neither on one body, nor on parent and child, nor on
        two fingers of one hand (joints named like a hand's, one parent).
        """
        a, b = self.body(first), self.body(second)
        if a == b or self.adjacent(first, second):
            return False
        fingers = all(GRASPING_NAME.search(body) for body in (a, b))
        return not (fingers and self.parent(a) == self.parent(b))


@lru_cache(maxsize=16)
def designed_bodies(text: str) -> DesignedBodies:
    """The designed bodies of the URDF ``text`` (parsed once per text in a process)."""
    links = {}
    for joint in urdf_document(text).findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue
        moves = joint.get("type") in _MOVING or joint.get(LOCKED_ATTRIBUTE) is not None
        links[str(child.get("link"))] = (str(joint.get("name")), str(parent.get("link")), moves)
    return DesignedBodies(links)


#: Joint names of a hand that grasps a payload (Robotiq's knuckles, Tiago's ``hand_*_flex``,
#: jaws): the payload touches what hangs below its holder through such joints.
GRASPING_NAME = re.compile(r"finger|gripper|knuckle|thumb|jaw|claw|hand|grasp|pinch|flex", re.I)


def finger_of(model: pin.Model, holder: int, joint: int) -> bool:
    """Whether ``joint``'s body is a finger of ``holder``'s (Pinocchio joint indices).

    It hangs below the holder only through joints named like a hand's
    (:data:`GRASPING_NAME`): a payload held by a mid-arm link, or by the spacecraft, is
    checked against the arm beyond it. (A hand whose joints are named otherwise has its
    fingers checked against the payload: lock them, or disable those pairs in an SRDF.)
    """
    if joint == holder:
        return False
    parent = model.parents
    while joint != holder:
        if joint <= 1 or not GRASPING_NAME.search(model.names[joint]):
            return False
        joint = int(parent[joint])
    return True
