"""Checks of a URDF's shapes: every ``<collision>`` geometry is one urdfdom keeps.

urdfdom drops a geometry element it cannot read (a box ``size="0,6 0,6 0,6"`` with decimal
commas, ``nan``, two numbers, an empty ``<geometry/>``) with a message on stderr and goes on:
the link then has no collision shape, and clearance is not checked against it at all. A mesh
scaled by 0 crashes the convex-hull code. Each is refused here, in one line naming the link,
before Pinocchio reads the file. Numbers are read as urdfdom reads them
(:func:`~freefloat.robot.urdf_checks.urdf_number`). Lengths in m.

The link name ``captured_payload`` is freefloat's own: a captured payload, a leaf link fixed
to the body that holds it. A URDF whose link of that name is anything else (the spacecraft,
say) is refused: the payload rules of clearance and sensitivity would apply to it.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable

from ..errors import ModelError
from ..excerpts import excerpt

#: How urdfdom reads one number: a float, or ``ValueError``.
Reader = Callable[[str], float]

__all__ = ["PAYLOAD_LINK", "check_payload_link", "check_shapes"]

#: Name of the link a captured payload becomes (:mod:`freefloat.robot.payload`).
PAYLOAD_LINK = "captured_payload"

#: Largest size of a shape accepted (m; a radius, a length, a box side or a mesh scale).
MAX_SIZE_M = 1e6

#: The attributes of each primitive shape urdfdom reads and how many numbers each takes (the
#: urdfdom inside Pinocchio 4.1 reads no ``<capsule>``: it drops it with a note on stderr).
_SHAPES = {
    "box": (("size", 3),),
    "sphere": (("radius", 1),),
    "cylinder": (("radius", 1), ("length", 1)),
}


def check_shapes(root: ET.Element, number: Reader) -> None:
    """Refuse a ``<collision>`` geometry urdfdom would drop or that would crash the hull code.

    ``number``: how urdfdom reads one number (``urdf_number``: a float, or ``ValueError``).

    Raises:
        ModelError: naming the link, the element and the value: an empty ``<geometry>``, a
            primitive whose sizes are not its count of finite numbers > 0 (at most
            :data:`MAX_SIZE_M`), or a mesh whose ``scale`` is not three finite non-zero numbers.
    """
    for link in root.findall("link"):
        name = link.get("name", "")
        for element in link.findall("collision"):
            geometry = element.find("geometry")
            if geometry is not None:  # urdfdom refuses a <collision> without one itself
                _check_geometry(geometry, f"link {name!r} collision", number)


def _check_geometry(geometry: ET.Element, where: str, number: Reader) -> None:
    valid = "<box>, <sphere>, <cylinder>, <mesh>"
    if len(geometry) == 0:
        raise ModelError(f"{where} has an empty <geometry>; give one of {valid}")
    shape = geometry[0]  # urdfdom reads the first element only
    if shape.tag not in (*_SHAPES, "mesh"):
        raise ModelError(
            f"{where} <{shape.tag[:40]}> is not a shape urdfdom reads (it would drop it); "
            f"give one of {valid} first"
        )
    if shape.tag == "mesh":
        raw = shape.get("scale")
        if raw is not None:
            values = _numbers(raw, number)
            if len(values) != 3 or not all(
                math.isfinite(v) and 0.0 < abs(v) <= MAX_SIZE_M for v in values
            ):
                raise ModelError(
                    f"{where} mesh scale={excerpt(raw)} is not three finite non-zero numbers "
                    f"of magnitude at most {MAX_SIZE_M:g}"
                )
        return
    for attr, count in _SHAPES[shape.tag]:
        raw = shape.get(attr)
        values = [] if raw is None else _numbers(raw, number)
        if len(values) != count or not all(
            math.isfinite(v) and 0.0 < v <= MAX_SIZE_M for v in values
        ):
            said = "missing" if raw is None else f"{attr}={excerpt(raw)}"
            plural = f"{count} numbers" if count > 1 else "a number"
            raise ModelError(
                f"{where} {shape.tag} {said}: give {plural} > 0 m (at most {MAX_SIZE_M:g}), "
                "written with a decimal point"
            )


def _numbers(raw: str, number: Reader) -> list[float]:
    """The numbers of a blank-separated attribute, as urdfdom reads them ([] if one is not)."""
    try:
        return [number(v) for v in raw.split()]
    except ValueError:
        return []


def check_payload_link(root: ET.Element) -> None:
    """Refuse a link named ``captured_payload`` that is not a leaf fixed to another link.

    Raises:
        ModelError: the link is the root, carries other links, or hangs on a movable joint.
    """
    if PAYLOAD_LINK not in {link.get("name") for link in root.findall("link")}:
        return
    held_by = carries = None
    for joint in root.findall("joint"):
        child, parent = joint.find("child"), joint.find("parent")
        if child is not None and child.get("link") == PAYLOAD_LINK:
            held_by = joint
        if parent is not None and parent.get("link") == PAYLOAD_LINK:
            carries = joint
    if held_by is None or carries is not None or held_by.get("type") != "fixed":
        raise ModelError(
            f"link {PAYLOAD_LINK!r} is freefloat's name for a captured payload (a leaf link "
            "fixed to the body holding it); rename this link"
        )
