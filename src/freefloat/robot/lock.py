"""Lock joints of a URDF: make them fixed at a chosen value, within their limits.

A locked joint becomes a ``fixed`` joint whose origin is its old origin followed by the joint's
motion at the locked value (a rotation about its axis by the angle in rad, or a translation
along it in m), so the bodies it carried stay where they were at that value. A joint that
mimics a locked joint is locked with it (at ``multiplier * value + offset``). Fingers of a
gripper are locked by default when an arm is composed: at 0 when 0 is within their limits,
otherwise at the middle of their range (:func:`finger_lock_value`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import LockedJointError, ModelError, UnknownNameError
from .designed_bodies import LOCKED_ATTRIBUTE

__all__ = ["default_lock", "finger_lock_value", "lock_joints", "locked_origin", "movable_joints"]

_MOVABLE = ("revolute", "continuous", "prismatic")
#: Drop-outs of a joint element once it is fixed.
_MOTION_TAGS = ("axis", "limit", "mimic", "dynamics", "safety_controller", "calibration")


def finger_lock_value(lower: float, upper: float) -> float:
    """Where a finger is locked (rad or m): 0 if within ``[lower, upper]``, else the middle."""
    if lower <= 0.0 <= upper:
        return 0.0
    return 0.5 * (lower + upper)


def default_lock(label: str, kind: str, lower: float, upper: float) -> tuple[float, str]:
    """Where a joint locked without a value is fixed (rad or m), and a note when not at 0.

    :func:`finger_lock_value` of its limits ``[lower, upper]`` (rad or m); the note ("" at 0)
    names it by ``label`` and gives the value and range in deg (m for a ``prismatic`` one).
    """
    value = finger_lock_value(lower, upper)
    if value == 0.0:
        return value, ""
    scale, unit = (1.0, "m") if kind == "prismatic" else (180 / math.pi, "deg")
    return value, (
        f"{label} locked at {value * scale:.6g} {unit}, the middle of its range "
        f"[{lower * scale:.4g}, {upper * scale:.4g}] {unit} (0 is outside it)"
    )


def locked_origin(origin: np.ndarray, kind: str, axis: Sequence[float], value: float) -> np.ndarray:
    """The 4 x 4 origin of a joint locked at ``value`` (rad, or m for a prismatic joint).

    Args:
        origin: the joint's 4 x 4 origin (parent link frame to joint frame; m).
        kind: ``revolute``, ``continuous`` or ``prismatic``.
        axis: the joint axis in the joint frame (normalised here).
        value: the locked value (rad or m).
    """
    direction = np.asarray(axis, dtype=float)
    norm = float(np.linalg.norm(direction))
    if not norm > 0.0:
        raise ModelError("a joint to lock has a zero axis")
    direction = direction / norm
    motion = np.eye(4)
    if kind == "prismatic":
        motion[:3, 3] = direction * value
    else:
        motion[:3, :3] = pin.AngleAxis(value, direction).matrix()
    return np.asarray(origin, dtype=float) @ motion


def movable_joints(text: str) -> dict[str, tuple[str, float, float]]:
    """``{name: (kind, lower, upper)}`` of a URDF's movable joints (rad or m; inf if none)."""
    root = _parse(text)
    joints = {}
    for joint in root.findall("joint"):
        kind = joint.get("type", "")
        if kind not in _MOVABLE:
            continue
        limit = joint.find("limit")
        lower, upper = -math.inf, math.inf
        if kind != "continuous" and limit is not None:
            lower = float(limit.get("lower", "0"))
            upper = float(limit.get("upper", "0"))
        joints[str(joint.get("name"))] = (kind, lower, upper)
    return joints


def lock_joints(text: str, values: Mapping[str, float], source_dir: Path | None = None) -> str:
    """The URDF ``text`` with the named joints fixed at ``values`` (rad or m).

    Relative mesh file names are made absolute against ``source_dir`` (the folder of the
    original URDF), so the new text can be written anywhere.

    Raises:
        UnknownNameError: a name is not a movable joint (lists the movable joints).
        LockedJointError: a value outside the joint's limits (deg or m in the message).
    """
    root = _parse(text)
    if source_dir is not None:
        for mesh in root.iter("mesh"):
            name = mesh.get("filename", "")
            if name and "://" not in name and not Path(name).is_absolute():
                mesh.set("filename", str((source_dir / name).resolve()))
    joints = {str(j.get("name")): j for j in root.findall("joint") if j.get("type") in _MOVABLE}
    values = dict(values)
    for joint in joints.values():  # followers of a locked joint are locked with it
        mimic = joint.find("mimic")
        if mimic is not None and mimic.get("joint") in values and joint.get("name") not in values:
            multiplier = float(mimic.get("multiplier", "1"))
            offset = float(mimic.get("offset", "0"))
            values[str(joint.get("name"))] = multiplier * values[str(mimic.get("joint"))] + offset
    for name, value in values.items():
        if name not in joints:
            raise UnknownNameError("joint to lock", name, list(joints))
        _fix(joints[name], name, float(value))
    return "<?xml version='1.0' encoding='UTF-8'?>\n" + ET.tostring(root, encoding="unicode")


def _parse(text: str) -> ET.Element:
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelError(f"cannot lock joints of a URDF that is not XML ({exc})") from None


def _fix(joint: ET.Element, name: str, value: float) -> None:
    """Turn one joint element into a fixed joint at ``value`` (rad or m)."""
    kind = str(joint.get("type"))
    limit = joint.find("limit")
    if kind != "continuous" and limit is not None:
        lower, upper = float(limit.get("lower", "0")), float(limit.get("upper", "0"))
        if not lower <= value <= upper:
            scale, unit = (1.0, "m") if kind == "prismatic" else (180.0 / math.pi, "deg")
            raise LockedJointError(name, value * scale, lower * scale, upper * scale, unit)
    axis_element = joint.find("axis")
    axis = [1.0, 0.0, 0.0]
    if axis_element is not None:
        axis = [float(x) for x in axis_element.get("xyz", "1 0 0").split()]
    origin_element = joint.find("origin")
    xyz = [0.0, 0.0, 0.0]
    rpy = [0.0, 0.0, 0.0]
    if origin_element is not None:
        xyz = [float(x) for x in origin_element.get("xyz", "0 0 0").split()]
        rpy = [float(x) for x in origin_element.get("rpy", "0 0 0").split()]
    origin = np.eye(4)
    origin[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    origin[:3, 3] = xyz
    new = locked_origin(origin, kind, axis, value)
    for tag in _MOTION_TAGS:
        for element in joint.findall(tag):
            joint.remove(element)
    if origin_element is None:
        origin_element = ET.SubElement(joint, "origin")
    origin_element.set("xyz", " ".join(repr(float(x)) for x in new[:3, 3]))
    origin_element.set("rpy", " ".join(repr(float(x)) for x in pin.rpy.matrixToRpy(new[:3, :3])))
    joint.set("type", "fixed")
    joint.set(LOCKED_ATTRIBUTE, repr(float(value)))  # the arm as designed (.designed_bodies)
