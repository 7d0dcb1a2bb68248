"""Checks of a URDF's XML that Pinocchio's parser does not make, each with a clear message.

A free floater needs one root link (the spacecraft), a tree of revolute, continuous,
prismatic or fixed joints, and numbers that parse (masses in kg, lengths in m, limits in rad
or m). Refused by name: closed loops (URDF cannot express one: a link with two parent joints,
or links that are each other's ancestors), ``<mimic>`` joints (freefloat plans every movable
joint on its own path), a revolute or prismatic joint without ``<limit>``, a zero axis.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ModelError, UnknownNameError
from ..progress import LOGGER

__all__ = ["check_masses", "check_urdf_xml", "parser_messages"]

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
        for attr in ("effort", "velocity"):
            _float_attr(limit, attr, f"joint {name!r} <limit>")
        for attr in ("lower", "upper"):
            _float_attr(limit, attr, f"joint {name!r} <limit>", 0.0)
    axis = joint.find("axis")
    raw = "1 0 0" if axis is None else axis.get("xyz", "1 0 0")
    try:
        xyz = [float(v) for v in raw.split()]
    except ValueError:
        xyz = []
    if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
        raise ModelError(f"joint {name!r} <axis xyz={raw[:40]!r}> is not three finite numbers")
    if max(abs(v) for v in xyz) < 1e-12:
        raise ModelError(
            f"joint {name!r} has a zero axis (xyz={raw[:40]!r}); give the direction it turns "
            "or slides along"
        )


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

    _check_inertials(root)

    parent_of: dict[str, str] = {}
    for joint in root.findall("joint"):
        jname = joint.get("name") or "?"
        jtype = joint.get("type")
        if jtype not in _URDF_JOINT_TYPES:
            raise ModelError(
                f"joint {jname!r} has type {jtype!r}; supported: {', '.join(_URDF_JOINT_TYPES)}"
            )
        if jtype != "fixed":
            _check_movable_joint(joint, jname, jtype)
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


@contextmanager
def parser_messages() -> Iterator[list[str]]:
    """Collect what C++ code (urdfdom) prints on file descriptor 2 instead of showing it.

    The lines are in the yielded list after the block; they are logged at DEBUG level (and an
    error message quotes the first). Without a usable descriptor 2 nothing is captured.
    """
    lines: list[str] = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield lines
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            lines += sink.read(100_000).decode("utf-8", "replace").splitlines()
            for line in lines:
                LOGGER.debug("URDF parser: %s", line)


def _check_inertials(root: ET.Element) -> None:
    """Every link's <inertial>: mass >= 0 (kg), a positive definite inertia if massive."""
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


def check_masses(model: pin.Model, root_link: str, path: Path) -> None:
    """Every moving body has a mass (kg), the base a positive definite inertia (kg m^2).

    Raises:
        ModelError: naming the body.
    """
    for index in range(1, model.njoints):
        inertia = model.inertias[index]
        body = model.names[index] if index > 1 else f"base {root_link!r}"
        if inertia.mass <= 0.0:
            raise ModelError(
                f"the body moved by joint {body!r} has no mass; every moving body needs a "
                "positive <mass>",
                urdf=str(path),
            )
        if np.linalg.eigvalsh(inertia.inertia).min() <= 0.0 and index == 1:
            raise ModelError(
                f"the base {root_link!r} has a singular rotational inertia; give it a positive "
                "definite <inertia>",
                urdf=str(path),
            )
