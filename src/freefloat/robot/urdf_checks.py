"""Checks of a URDF's XML that Pinocchio's parser does not make, each with a clear message.

A free floater needs one root link (the spacecraft), a tree of revolute, continuous,
prismatic or fixed joints, and numbers that parse (masses in kg, lengths in m, limits in rad
or m). Refused by name: closed loops (URDF cannot express one: a link with two parent joints,
or links that are each other's ancestors), ``<mimic>`` joints (freefloat plans every movable
joint on its own path), a revolute or prismatic joint without ``<limit>``, a zero axis.

One parse: a document type declaration (``<!DOCTYPE``, entities) is refused, because
Pinocchio's XML parser (TinyXML2) does not read one the way Python's does and would build
another robot than the one checked; and what Pinocchio is given is the checked tree written
out again (:attr:`CheckedUrdf.text`), never the file's own text. Every number read here is
finite and within a stated magnitude (:data:`MAX_MASS_KG`, :data:`MAX_INERTIA`,
:data:`MAX_LENGTH_M`), every inertia positive semi-definite (definite when the link has mass),
every ``package://`` mesh path stays inside its package.
"""

from __future__ import annotations

import math
import posixpath
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from xml.parsers import expat

import numpy as np

from ..errors import ModelError, UnknownNameError, excerpt
from .urdf_shapes import check_payload_link, check_shapes

__all__ = [
    "MAX_INERTIA",
    "MAX_LENGTH_M",
    "MAX_LIMIT",
    "MAX_MASS_KG",
    "CheckedUrdf",
    "check_urdf_xml",
    "urdf_document",
    "urdf_number",
]

_URDF_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")

#: Largest mass of a link (kg): ten times a space station's.
MAX_MASS_KG = 1e7
#: Largest entry of a link's inertia matrix (kg m^2).
MAX_INERTIA = 1e12
#: Largest coordinate of an origin (m) or angle of one (rad).
MAX_LENGTH_M = 1e6
#: Largest magnitude of a joint limit (position, effort or velocity).
MAX_LIMIT = 1e20


@dataclass(frozen=True)
class CheckedUrdf:
    """What the checks read from a URDF.

    Attributes:
        text: the checked XML tree written out again: the only text Pinocchio is given.
        name: the ``<robot name>``.
        root_link: the root link (the spacecraft).
        links: every link name, in file order.
        movable_joints: names of the revolute, continuous and prismatic joints, in file order.
        total_mass: sum of the links' masses (kg).
    """

    text: str
    name: str
    root_link: str
    links: tuple[str, ...]
    movable_joints: tuple[str, ...]
    total_mass: float


#: A number as urdfdom reads one (C locale, ASCII digits, nothing after it); Python's
#: ``float`` also takes ``1_000``, ``\uff14\uff10`` and trailing blanks, which urdfdom refuses or
#: reads as 0.
_NUMBER = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|\s*[+-]?(inf|nan)", re.I | re.A)


def urdf_number(raw: str) -> float:
    """``raw`` as a float, read as urdfdom reads it; ``ValueError`` otherwise."""
    if not _NUMBER.fullmatch(raw):
        raise ValueError(raw)
    return float(raw)


def _float_attr(
    element: ET.Element,
    attr: str,
    what: str,
    default: float | None = None,
    high: float = MAX_LENGTH_M,
) -> float:
    raw = element.get(attr)
    if raw is None:
        if default is None:
            raise ModelError(f"{what} has no {attr!r} attribute")
        return default
    try:
        value = urdf_number(raw)
    except ValueError:
        raise ModelError(f"{what} {attr}={excerpt(raw)} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{what} {attr}={excerpt(raw)} is not a finite number")
    if abs(value) > high:
        raise ModelError(
            f"{what} {attr}={excerpt(raw)} is beyond the largest magnitude accepted, {high:g}"
        )
    return value


def _triple(element: ET.Element | None, attr: str, what: str) -> list[float]:
    """Three finite numbers of at most :data:`MAX_LENGTH_M` (``xyz`` or ``rpy``; default 0)."""
    raw = "0 0 0" if element is None else element.get(attr, "0 0 0")
    try:
        values = [urdf_number(v) for v in raw.split()]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) and abs(v) <= MAX_LENGTH_M for v in values):
        raise ModelError(
            f"{what} {attr}={excerpt(raw)} is not three finite numbers of magnitude at most "
            f"{MAX_LENGTH_M:g}"
        )
    return values


_LIMIT_UNITS = {"revolute": "rad, N m, rad/s", "prismatic": "m, N, m/s"}


def _check_movable_joint(joint: ET.Element, name: str, kind: str) -> None:
    """Refuse by name what urdfdom would refuse with parser noise, or Pinocchio misread.

    A ``<mimic>`` joint (Pinocchio would plan it as independent), a revolute or prismatic
    joint without ``<limit>``, a ``<limit>`` without effort or velocity, a zero or malformed
    axis.
    """
    mimic = joint.find("mimic")
    if mimic is not None:
        raise ModelError(
            f"joint {name!r} mimics {mimic.get('joint', '?')!r}: mimic joints are not supported "
            "(freefloat moves every joint on its own path); remove the <mimic> element, or "
            "make the joint fixed"
        )
    limit = joint.find("limit")
    if limit is None and kind in _LIMIT_UNITS:
        hint = ", or make it continuous" if kind == "revolute" else ""
        raise ModelError(
            f"joint {name!r} ({kind}) has no <limit>; it needs <limit lower=... upper=... "
            f"effort=... velocity=.../> ({_LIMIT_UNITS[kind]}){hint}"
        )
    if limit is not None:
        for attr in ("effort", "velocity"):  # negative: Pinocchio's parser says only "cannot"
            if _float_attr(limit, attr, f"joint {name!r} <limit>", high=MAX_LIMIT) < 0.0:
                what = f"joint {name!r} <limit> {attr}={excerpt(limit.get(attr))}"
                raise ModelError(f"{what} is negative; a limit is a magnitude (>= 0; 0: none)")
        for attr in ("lower", "upper"):  # +-1e16 stands for "none" in some files
            _float_attr(limit, attr, f"joint {name!r} <limit>", 0.0, MAX_LIMIT)
    axis = joint.find("axis")
    raw = "1 0 0" if axis is None else axis.get("xyz", "1 0 0")
    try:
        xyz = [urdf_number(v) for v in raw.split()]
    except ValueError:
        xyz = []
    if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
        raise ModelError(f"joint {name!r} <axis xyz={raw[:40]!r}> is not three finite numbers")
    if max(abs(v) for v in xyz) < 1e-12:
        raise ModelError(
            f"joint {name!r} has a zero axis (xyz={raw[:40]!r}); give the direction it turns "
            "or slides along"
        )


def _refuse_document_type(text: str) -> None:
    """Refuse a ``<!DOCTYPE>`` (and with it every entity), and processing instructions.

    Python's parser expands entities; TinyXML2, which Pinocchio uses, ends the declaration at
    the first ``>`` and reads what follows as elements: the two would see different robots.
    A processing instruction (other than the leading ``<?xml ...?>``) Python skips and
    TinyXML2 refuses.
    """

    def refuse(*_: object) -> None:
        raise ModelError(
            "the URDF has a document type declaration (<!DOCTYPE ...>, entities): not "
            "accepted, because Pinocchio's XML parser reads it differently; remove it and "
            "write entity values out"
        )

    def instruction(target: str, data: str) -> None:
        raise ModelError(
            f"the URDF has a processing instruction <?{excerpt(target, 20)} ...?>: not "
            "accepted, because Pinocchio's XML parser refuses one inside the document; "
            "remove it"
        )

    parser = expat.ParserCreate()
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    parser.ProcessingInstructionHandler = instruction
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        raise ModelError(f"malformed URDF XML ({exc})") from None


def _check_inertial(link: ET.Element, name: str) -> float:
    """Check a link's ``<inertial>``; return its mass (kg, 0 without one)."""
    inertial = link.find("inertial")
    if inertial is None:
        return 0.0
    _triple(inertial.find("origin"), "xyz", f"link {name!r} inertial origin")
    _triple(inertial.find("origin"), "rpy", f"link {name!r} inertial origin")
    mass_el = inertial.find("mass")
    if mass_el is None:
        raise ModelError(f"link {name!r} has an <inertial> without <mass>")
    mass = _float_attr(mass_el, "value", f"link {name!r} mass", high=MAX_MASS_KG)
    if mass < 0.0:
        raise ModelError(f"link {name!r} has negative mass {mass} kg; masses must be >= 0")
    inertia_el = inertial.find("inertia")
    if inertia_el is None:
        if mass > 0.0:
            raise ModelError(f"link {name!r} has mass but no <inertia>")
        return mass
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    ixx, ixy, ixz, iyy, iyz, izz = (
        _float_attr(inertia_el, k, f"link {name!r} inertia", None, MAX_INERTIA) for k in keys
    )
    eigenvalues = np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    shown = np.round(eigenvalues, 9).tolist()
    if mass > 0.0 and eigenvalues.min() <= 0.0:
        raise ModelError(
            f"link {name!r} inertia is not positive definite (eigenvalues {shown} kg m^2); "
            "it must be"
        )
    if eigenvalues.min() < -1e-12 * max(1.0, float(np.abs(eigenvalues).max())):
        raise ModelError(
            f"link {name!r} has no mass but a negative inertia (eigenvalues {shown} kg m^2); "
            "a massless link's inertia must be zero or positive semi-definite"
        )
    return mass


def _check_mesh_paths(root: ET.Element) -> None:
    """Refuse a ``package://`` mesh path that leaves its package (``package://p/../../x``)."""
    for element in root.iter():
        filename = element.get("filename")
        if filename is None or not filename.startswith("package://"):
            continue
        package, _, inside = filename.removeprefix("package://").partition("/")
        normal = posixpath.normpath(inside) if inside else ""
        if package in ("", ".", "..") or normal.startswith("..") or inside.startswith("/"):
            raise ModelError(
                f"mesh path {excerpt(filename)} leaves its package; a package:// path names "
                "a package and a file inside it (package://NAME/path/inside)"
            )


def _check_tree(root: ET.Element, links: list[str]) -> tuple[str, list[str]]:
    """Check the joints and that the links form one tree; return the root and movable joints."""
    parent_of: dict[str, str] = {}
    movable: list[str] = []
    names: set[str] = set()
    for joint in root.findall("joint"):
        jname = joint.get("name") or ""
        if not jname.strip():
            raise ModelError("a <joint> has no name (or an empty one); every joint needs one")
        if jname in names:
            raise ModelError(f"duplicate joint name {jname!r}")
        names.add(jname)
        jtype = joint.get("type")
        if jtype not in _URDF_JOINT_TYPES:
            floats = (
                "; the URDF's root link is the spacecraft and already floats: remove this joint "
                "and the link above it"
                if jtype == "floating"
                else ""
            )
            raise ModelError(
                f"joint {jname!r} has type {jtype!r}; supported: "
                f"{', '.join(_URDF_JOINT_TYPES)}{floats}"
            )
        if jtype != "fixed":
            _check_movable_joint(joint, jname, jtype)
            movable.append(jname)
        _triple(joint.find("origin"), "xyz", f"joint {jname!r} origin")
        _triple(joint.find("origin"), "rpy", f"joint {jname!r} origin")
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
    return roots[0], movable


def urdf_document(text: str) -> ET.Element:
    """The ``<robot>`` element of a URDF's text, parsed once, without a document type.

    Raises:
        ModelError: a document type declaration, malformed XML, or another root element.
    """
    text = text.removeprefix("\ufeff")  # a UTF-8 byte-order mark
    _refuse_document_type(text)
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ModelError(f"malformed URDF XML ({exc})") from None
    if root.tag != "robot":
        raise ModelError(f"root element is <{excerpt(root.tag)}>, expected <robot>")
    return root


def check_urdf_xml(text: str) -> CheckedUrdf:
    """Check the URDF's structure, numbers and inertials; return what Pinocchio is to load.

    Raises:
        ModelError: a document type declaration, malformed XML, or a check above that fails
            (one line naming the link, joint or value).
        UnknownNameError: a joint names a link that does not exist.
    """
    root = urdf_document(text)
    links = [link.get("name") or "" for link in root.findall("link")]
    if not links:
        raise ModelError("the URDF has no <link>")
    if any(not n.strip() for n in links):
        raise ModelError("a <link> has no name (or an empty one); every link needs one")
    duplicates = sorted({n for n in links if links.count(n) > 1})
    if duplicates:
        raise ModelError(f"duplicate link name(s) {', '.join(duplicates)}")
    total_mass = math.fsum(
        _check_inertial(link, link.get("name", "")) for link in root.findall("link")
    )
    _check_mesh_paths(root)
    check_shapes(root, urdf_number)
    root_link, movable = _check_tree(root, links)
    check_payload_link(root)
    return CheckedUrdf(
        text=ET.tostring(root, encoding="unicode"),
        name=root.get("name", ""),
        root_link=root_link,
        links=tuple(links),
        movable_joints=tuple(movable),
        total_mass=total_mass,
    )
