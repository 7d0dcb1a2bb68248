"""Checks of a URDF's XML that Pinocchio's parser does not make, each with a clear message.

A free floater needs one root link (the spacecraft), a tree of revolute, continuous,
prismatic or fixed joints, and numbers that parse (masses in kg, lengths in m, limits in rad
or m).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from ..errors import ModelError, UnknownNameError

__all__ = ["check_urdf_xml"]

_URDF_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")


def _float_attr(element: ET.Element, attr: str, what: str, default: float | None = None) -> float:
    raw = element.get(attr)
    if raw is None:
        if default is None:
            raise ModelError(f"{what} has no {attr!r} attribute")
        return default
    try:
        value = float(raw)
    except ValueError:
        raise ModelError(f"{what} {attr}={raw!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{what} {attr}={raw!r} is not a finite number")
    return value


def check_urdf_xml(text: str) -> tuple[str, list[str]]:
    """Check the URDF's structure and inertials; return the root link and the link names."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelError(f"malformed URDF XML ({exc})") from None
    if root.tag != "robot":
        raise ModelError(f"root element is <{root.tag}>, expected <robot>")
    links = [link.get("name") or "" for link in root.findall("link")]
    if not links:
        raise ModelError("the URDF has no <link>")
    if "" in links:
        raise ModelError("a <link> has no name")
    duplicates = sorted({n for n in links if links.count(n) > 1})
    if duplicates:
        raise ModelError(f"duplicate link name(s) {', '.join(duplicates)}")

    for link in root.findall("link"):
        name = link.get("name")
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass_el = inertial.find("mass")
        if mass_el is None:
            raise ModelError(f"link {name!r} has an <inertial> without <mass>")
        mass = _float_attr(mass_el, "value", f"link {name!r} mass")
        if mass < 0.0:
            raise ModelError(f"link {name!r} has negative mass {mass} kg; masses must be >= 0")
        inertia_el = inertial.find("inertia")
        if inertia_el is None:
            if mass > 0.0:
                raise ModelError(f"link {name!r} has mass but no <inertia>")
            continue
        keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        ixx, ixy, ixz, iyy, iyz, izz = (
            _float_attr(inertia_el, k, f"link {name!r} inertia", 0.0) for k in keys
        )
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        if mass > 0.0 and np.linalg.eigvalsh(inertia).min() <= 0.0:
            raise ModelError(
                f"link {name!r} inertia is not positive definite (eigenvalues "
                f"{np.round(np.linalg.eigvalsh(inertia), 9).tolist()} kg m^2); it must be"
            )

    parent_of: dict[str, str] = {}
    for joint in root.findall("joint"):
        jname = joint.get("name") or "?"
        jtype = joint.get("type")
        if jtype not in _URDF_JOINT_TYPES:
            raise ModelError(
                f"joint {jname!r} has type {jtype!r}; supported: {', '.join(_URDF_JOINT_TYPES)}"
            )
        parent_el, child_el = joint.find("parent"), joint.find("child")
        if parent_el is None or child_el is None:
            raise ModelError(f"joint {jname!r} needs a <parent> and a <child>")
        parent, child = parent_el.get("link", ""), child_el.get("link", "")
        for end in (parent, child):
            if end not in links:
                raise UnknownNameError(f"link (in joint {jname!r})", end, links)
        if child in parent_of:
            raise ModelError(
                f"closed loop: link {child!r} is the child of two joints; a free floater must "
                "be a tree (open chains)"
            )
        parent_of[child] = parent
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        raise ModelError(
            "closed loop: every link has a parent joint; a tree needs exactly one root link"
            if not roots
            else f"several root links ({', '.join(roots)}); the URDF must be one tree"
        )
    # A cycle that leaves the root reachable is impossible once each link has one parent and
    # there is one root, except for a detached cycle: check every link reaches the root.
    for name in links:
        seen = set()
        while name in parent_of:
            if name in seen:
                raise ModelError(f"closed loop through link {name!r}; the URDF must be a tree")
            seen.add(name)
            name = parent_of[name]
    return roots[0], links
