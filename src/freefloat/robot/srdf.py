"""SRDF pairs of a servicer with several arms: each arm's own pairs, under its prefix.

An SRDF lists pairs of links never checked for collision (``<disable_collisions link1 link2>``,
the MoveIt convention). A servicer composed of several arms renames each arm's links with the
arm's prefix, so each arm's SRDF pairs are renamed the same way and merged into one SRDF; the
pairs between two arms, and between an arm and the spacecraft, stay checked.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from ..errors import ModelError
from .model import MAX_URDF_BYTES, Robot, example_robot_data_dir

__all__ = [
    "ARM_SRDFS",
    "arm_srdf",
    "checked_srdf",
    "disabled_pairs",
    "known_srdf",
    "merged_srdf",
]


#: SRDF files of example-robot-data arms (below ``example-robot-data/robots``).
ARM_SRDFS = {
    "panda": "panda_description/srdf/panda.srdf",
    "ur5": "ur_description/srdf/ur5.srdf",
    "kinova": "kinova_description/srdf/kinova.srdf",
    "xarm7": "xarm_description/srdf/xarm7.srdf",
    "z1": "z1_description/srdf/z1.srdf",
}


def known_srdf(robot: Robot) -> Path | None:
    """The SRDF of a servicer composed from an example-robot-data arm (named ``ARM_servicer``).

    None for any other robot, or when example-robot-data is not installed.
    """
    arm = robot.name.removesuffix("_servicer")
    share = example_robot_data_dir()
    if arm == robot.name or arm not in ARM_SRDFS or share is None:
        return None
    path = share / "example-robot-data" / "robots" / ARM_SRDFS[arm]
    return path if path.is_file() else None


def arm_srdf(arm: str) -> Path | None:
    """The SRDF of an arm: example-robot-data's for a named arm, else ``<urdf>.srdf`` if any."""
    if arm in ARM_SRDFS:
        share = example_robot_data_dir()
        path = None if share is None else share / "example-robot-data" / "robots" / ARM_SRDFS[arm]
    else:
        path = Path(arm).expanduser().with_suffix(".srdf")
    return path if path is not None and path.is_file() else None


def disabled_pairs(path: Path) -> list[tuple[str, str]]:
    """The ``(link1, link2)`` pairs an SRDF file disables.

    Raises:
        ModelError: the file is too large or not XML.
    """
    if path.stat().st_size > MAX_URDF_BYTES:
        raise ModelError(f"SRDF {path} is larger than {MAX_URDF_BYTES} bytes")
    try:
        root = ET.fromstring(path.read_text(encoding="utf-8"))
    except (ET.ParseError, UnicodeDecodeError) as exc:
        raise ModelError(f"SRDF {path} is not XML ({exc})") from None
    return [
        (str(e.get("link1")), str(e.get("link2")))
        for e in root.iter("disable_collisions")
        if e.get("link1") and e.get("link2")
    ]


def checked_srdf(path: Path, links: set[str]) -> list[str]:
    """Check an SRDF file as Pinocchio will read it; return the links it names not in ``links``.

    Those links' pairs disable nothing; they are returned in the order found, each once.

    Raises:
        ModelError: the file does not end in ``.srdf`` (Pinocchio refuses it), is too large,
            is not XML, has another root than ``<robot>``, or has a ``<disable_collisions>``
            without both its links.
    """
    if path.suffix.lower() != ".srdf":
        raise ModelError(f"SRDF {path} does not end in .srdf; give an SRDF file (*.srdf)")
    if path.stat().st_size > MAX_URDF_BYTES:
        raise ModelError(f"SRDF {path} is larger than {MAX_URDF_BYTES} bytes")
    try:
        root = ET.fromstring(path.read_text(encoding="utf-8"))
    except (ET.ParseError, UnicodeDecodeError) as exc:
        raise ModelError(f"SRDF {path} is not XML ({exc})") from None
    if root.tag != "robot":
        raise ModelError(f"SRDF {path}: root element is <{root.tag[:40]}>, expected <robot>")
    unknown: dict[str, None] = {}
    for number, element in enumerate(root.iter("disable_collisions"), start=1):
        names = (element.get("link1"), element.get("link2"))
        if not all(names):
            raise ModelError(
                f"SRDF {path}: <disable_collisions> number {number} lacks link1 or link2; each "
                'names two links: <disable_collisions link1="a" link2="b"/>'
            )
        unknown.update((str(n), None) for n in names if n not in links)
    return list(unknown)


def merged_srdf(arms: Sequence[str], prefixes: Sequence[str]) -> str:
    """One SRDF with each arm's disabled pairs, its links renamed with the arm's prefix."""
    root = ET.Element("robot", name="servicer")
    for arm, prefix in zip(arms, prefixes, strict=True):
        path = arm_srdf(arm)
        if path is None:
            continue
        for first, second in disabled_pairs(path):
            ET.SubElement(
                root,
                "disable_collisions",
                link1=prefix + first,
                link2=prefix + second,
                reason=f"from {path.name}",
            )
    ET.indent(root)
    return "<?xml version='1.0' encoding='UTF-8'?>\n" + ET.tostring(root, encoding="unicode") + "\n"
