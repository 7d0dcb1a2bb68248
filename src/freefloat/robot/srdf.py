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

import pinocchio as pin

from ..errors import ModelError
from ..progress import LOGGER
from .model import MAX_URDF_BYTES, Robot, example_robot_data_dir

__all__ = [
    "ARM_SRDFS",
    "arm_srdf",
    "checked_srdf",
    "disabled_pairs",
    "known_srdf",
    "merged_srdf",
    "remove_srdf_pairs",
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

    Only when the robot's collision shapes of every link the SRDF names are that arm's own
    (:func:`_differing_link`): a URDF that keeps the name but changes a shape (a wrist grown
    to a 0.4 m sphere) would otherwise have pairs disabled that now collide; it is then not
    applied, with a warning. None for any other robot, or when example-robot-data is not
    installed.
    """
    arm = robot.name.removesuffix("_servicer")
    share = example_robot_data_dir()
    if arm == robot.name or arm not in ARM_SRDFS or share is None:
        return None
    path = share / "example-robot-data" / "robots" / ARM_SRDFS[arm]
    if not path.is_file():
        return None
    key = (robot.urdf_text, str(path))
    if key not in _MATCHED:
        from .arms import ARMS  # the arms' table, only for a servicer named like one

        arm_text = (share / "example-robot-data" / "robots" / ARMS[arm]).read_text()
        links = {name for pair in disabled_pairs(path) for name in pair}
        differing = _differing_link(robot.urdf_text, arm_text, links)
        if differing:
            LOGGER.warning(
                "%s is named like a servicer of example-robot-data's %s, but the collision "
                "shapes or joints of its link %r are not that arm's: the arm's SRDF (%s) is not "
                "applied; give [safety] srdf to disable pairs",
                robot.name,
                arm,
                differing,
                path.name,
            )
        if len(_MATCHED) >= 64:  # one per URDF text: a sweep of masses makes many
            _MATCHED.pop(next(iter(_MATCHED)))
        _MATCHED[key] = not differing
    return path if _MATCHED[key] else None


#: Whether a robot's shapes match its arm's, per (URDF text, SRDF path).
_MATCHED: dict[tuple[str, str], bool] = {}


def _differing_link(text: str, arm_text: str, links: set[str]) -> str:
    """The first of ``links`` whose ``<collision>`` elements differ between two URDFs ("" if none).

    Compared by shape, its numbers (sizes, mesh scale), the mesh file's name and the
    collision's origin, and by the joint from the link's parent, to 1e-9 (the arm's root,
    mounted in the servicer, by its shapes alone); a link the arm lacks differs, one the robot
    lacks is skipped (its pairs disable nothing).
    """
    mine, theirs = _collisions(text), _collisions(arm_text)
    for link in sorted(links):  # a link the robot lacks (renamed, prefixed) disables nothing
        if link not in mine:
            continue
        if link not in theirs or mine[link][0] != theirs[link][0]:
            return link
        ours, arms = mine[link][1], theirs[link][1]  # None: the arm's root, mounted
        if ours is not None and arms is not None and ours[1] == arms[1] and ours != arms:
            return link  # a locked joint (fixed in the servicer) moves by its lock value
    return ""


def _collisions(text: str) -> dict[str, tuple[list[tuple], tuple | None]]:
    """Per link: its collisions and the joint from its parent link.

    Each collision as (origin, shape, its numbers, mesh file name) (m); the joint as (type,
    parent, origin, axis; None for a root): a shorter forearm keeps its shapes but moves what
    it carries.
    """
    root = ET.fromstring(text)
    parents = {}
    for joint in root.findall("joint"):
        child, parent = joint.find("child"), joint.find("parent")
        if child is not None and parent is not None:
            parents[str(child.get("link"))] = joint
    found: dict[str, tuple[list[tuple], tuple | None]] = {}
    for link in root.findall("link"):
        shapes = []
        for element in link.findall("collision"):
            origin = element.find("origin")
            where = tuple(
                round(float(v), 9)
                for attr in ("xyz", "rpy")
                for v in (origin.get(attr, "0 0 0") if origin is not None else "0 0 0").split()
            )
            geometry = element.find("geometry")
            for shape in [] if geometry is None else list(geometry):
                numbers = tuple(
                    round(float(v), 9)
                    for attr in ("size", "radius", "length", "scale")
                    for v in shape.get(attr, "1 1 1" if attr == "scale" else "").split()
                )
                mesh = Path(shape.get("filename", "")).name
                shapes.append((where, shape.tag, numbers, mesh))
        above = parents.get(str(link.get("name")))
        found[str(link.get("name"))] = (shapes, None if above is None else _joint_key(above))
    return found


def _joint_key(joint: ET.Element) -> tuple:
    """A joint's type, parent link, origin and axis (numbers to 1e-9), for comparisons."""
    origin, axis, parent = joint.find("origin"), joint.find("axis"), joint.find("parent")
    numbers = [
        *(origin.get("xyz", "0 0 0").split() if origin is not None else ["0"] * 3),
        *(origin.get("rpy", "0 0 0").split() if origin is not None else ["0"] * 3),
        *(axis.get("xyz", "1 0 0").split() if axis is not None else ["1", "0", "0"]),
    ]
    owner = "" if parent is None else str(parent.get("link"))
    return ("joint", joint.get("type"), owner, tuple(round(float(v), 9) for v in numbers))


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
        text = path.read_text(encoding="utf-8")
        if "<!doctype" in text.lower():  # as for URDFs: no entities, no second reading
            raise ModelError(f"SRDF {path} has a document type declaration; remove it")
        root = ET.fromstring(text)
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


def remove_srdf_pairs(model: pin.Model, geometry: pin.GeometryModel, srdf: Path) -> None:
    """Remove the pairs the SRDF disables, the file checked first (:func:`.srdf.checked_srdf`).

    Raises:
        ModelError: the file is not an SRDF Pinocchio can read.
    """
    links = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    unknown = checked_srdf(srdf, links)
    if unknown:
        LOGGER.warning(
            "the SRDF %s names links the robot does not have (%s): their pairs disable nothing",
            srdf,
            ", ".join(unknown[:5]) + (f" and {len(unknown) - 5} more" if len(unknown) > 5 else ""),
        )
    try:
        pin.removeCollisionPairs(model, geometry, str(srdf))
    except (RuntimeError, ValueError) as exc:  # what the check above does not foresee
        raise ModelError(f"SRDF {srdf} cannot be read ({exc})") from None


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
