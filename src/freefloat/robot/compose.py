"""Compose a servicer: mount a robot arm on a box spacecraft and write one validated URDF.

The arm is an ``example-robot-data`` arm by name (:data:`ARMS`) or any URDF file. The new root
link ``spacecraft`` is a uniform box (mass in kg, size in m; inertia in kg m^2 from the box
unless given); a fixed joint ``mount`` places the arm's root link at ``mount`` (m) with
roll-pitch-yaw ``mount_rpy`` (rad) in the spacecraft frame. Gripper and finger joints are locked
by default (made fixed at 0, or at the middle of their range when 0 is outside it; the
composition says so). Several arms may share the spacecraft (:class:`ArmSpec`): each arm's links
and joints then carry its prefix, and its SRDF pairs are merged under that prefix
(:mod:`freefloat.robot.srdf`). Mesh references stay ``package://`` (resolved
at load time against ``example-robot-data``'s share folder) or become absolute paths for a URDF
given by path. yourdfpy builds, validates and writes the result. An optional captured payload
(:class:`~freefloat.robot.payload.Payload`) is then fixed to the composed robot's default end
effector (link ``captured_payload``); :func:`payload_parent` names that link, so the payload
link never becomes the end effector (``load_robot(path, payload_parent(text))``).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ModelError
from ..files import atomic_write_text
from ..staged import write_together
from .arm_tips import arm_tips, every_tip
from .arms import ARMS, BASE_LINK, ArmSpec, arm_part, arm_urdf
from .designed_bodies import LOCKED_ATTRIBUTE
from .model import example_robot_data_dir
from .payload import Payload
from .srdf import ARM_SRDFS, arm_srdf, merged_srdf
from .urdf_checks import check_urdf_xml

LOGGER = logging.getLogger(__name__)

#: A robot name :class:`ServicerSpec` takes.
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")

__all__ = [
    "ARMS",
    "REFUSED",
    "ArmSpec",
    "Composed",
    "ServicerSpec",
    "arm_urdf",
    "compose",
    "compose_servicer",
    "compose_servicer_text",
    "resolve_mesh",
    "write_composed",
]


@dataclass(frozen=True)
class Composed:
    """A composed servicer.

    Attributes:
        text: its URDF.
        locked: every joint made fixed and its value (rad or m), by its name in the servicer.
        notes: what the composition chose on its own (a finger locked mid-range...), one line
            each.
        end_effectors: the default end effector of each arm (the tip of its longest chain
            that is not a finger), in arm order; an arm whose longest chains tie gives every
            tip (composed with ``offer_ties``), or none at all (without).
        srdf: the SRDF text of the pairs never checked (each arm's own SRDF pairs, with the
            arm's prefix), for a servicer of several arms, or of one arm given as a URDF with
            an SRDF beside it (a named arm's is found by the servicer's name); None otherwise.
        prismatic: the locked joints that were prismatic (their values in m, not rad).
    """

    text: str
    locked: dict[str, float]
    notes: tuple[str, ...]
    end_effectors: tuple[str, ...]
    srdf: str | None = None
    prismatic: frozenset[str] = frozenset()


@dataclass(frozen=True)
class ServicerSpec:
    """What to compose (SI units; angles in rad).

    Attributes:
        arm: example-robot-data arm name or URDF path.
        base_mass: spacecraft mass (kg), > 0.
        base_size: spacecraft box edges x, y, z (m), > 0.
        mount: arm root position in the spacecraft frame (m).
        mount_rpy: arm root roll, pitch, yaw in the spacecraft frame (rad).
        base_inertia: principal moments Ixx, Iyy, Izz (kg m^2); default: the uniform box's.
        lock: extra joints to lock: a name (locked at 0, or at the middle of its range when 0
            is outside it) or ``(name, value)`` (rad or m).
        keep_gripper: keep gripper and finger joints movable (else each finger is locked at 0,
            or at the middle of its range when 0 is outside it).
        payload: a captured payload fixed to the (first arm's) end effector.
        more_arms: further arms on the same spacecraft; with any, every arm's links and joints
            get its prefix (``prefix`` for this first one, default ``arm1_``).
        prefix: the first arm's prefix (used only with ``more_arms``; default ``arm1_``).
        name: the URDF's robot name (default: the arms' names joined, then ``_servicer``).
    """

    arm: str
    base_mass: float
    base_size: tuple[float, ...]
    mount: tuple[float, ...] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, ...] = (0.0, 0.0, 0.0)
    base_inertia: tuple[float, ...] | None = None
    lock: tuple[str | tuple[str, float], ...] = field(default_factory=tuple)
    keep_gripper: bool = False
    payload: Payload | None = None
    more_arms: tuple[ArmSpec, ...] = ()
    prefix: str = ""
    name: str = ""

    def __post_init__(self) -> None:
        if self.name and not NAME.fullmatch(self.name):
            raise InputError(
                f"robot name {self.name!r}: give letters, digits, '_', '-' or '.', not first "
                "(at most 100)"
            )
        numbers = [self.base_mass, *self.base_size, *self.mount, *self.mount_rpy]
        for arm in self.more_arms:
            numbers += [*arm.mount, *arm.mount_rpy]
            if len(arm.mount) != 3 or len(arm.mount_rpy) != 3:
                raise InputError("each arm's mount and mount rpy take three numbers each")
        numbers += list(self.base_inertia or ())
        if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in numbers):
            raise InputError("servicer numbers must be finite (mass, size, mount, inertia)")
        if len(self.base_size) != 3 or len(self.mount) != 3 or len(self.mount_rpy) != 3:
            raise InputError("base size, mount and mount rpy take three numbers each")
        if self.base_mass <= 0:
            raise InputError(f"base mass must be > 0 kg, got {self.base_mass:g}")
        if min(self.base_size) <= 0:
            raise InputError(f"base size must be > 0 m on each axis, got {list(self.base_size)}")
        if self.base_inertia is not None:
            ixx, iyy, izz = self.base_inertia
            if min(ixx, iyy, izz) <= 0 or ixx + iyy < izz or iyy + izz < ixx or ixx + izz < iyy:
                raise InputError(
                    f"base inertia {list(self.base_inertia)} kg m^2 is not physical: each moment "
                    "must be > 0 and no larger than the sum of the other two"
                )

    def arms(self) -> list[ArmSpec]:
        """Every arm, the first from this spec's own fields, each with its prefix settled."""
        first = ArmSpec(
            self.arm, self.mount, self.mount_rpy, self.prefix, self.lock, self.keep_gripper
        )
        arms = [first, *self.more_arms]
        if len(arms) == 1:
            return arms
        arms = [replace(a, prefix=a.prefix or f"arm{i + 1}_") for i, a in enumerate(arms)]
        prefixes = [a.prefix for a in arms]
        if len(set(prefixes)) != len(prefixes):
            raise InputError(f"each arm needs its own prefix, got {prefixes}")
        return arms

    @property
    def inertia(self) -> tuple[float, float, float]:
        """Principal moments of the spacecraft (kg m^2)."""
        if self.base_inertia is not None:
            return (
                float(self.base_inertia[0]),
                float(self.base_inertia[1]),
                float(self.base_inertia[2]),
            )
        x, y, z = self.base_size
        m = self.base_mass / 12.0
        return (m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y))

    def key(self) -> str:
        """A short hash of the spec and the arm file (for cache file names)."""
        texts = [arm_urdf(arm.arm).read_text() for arm in self.arms()]  # and COMPOSED_VERSION:
        payload = json.dumps([COMPOSED_VERSION, self.__dict__, *texts], default=str)
        return hashlib.sha256(payload.encode()).hexdigest()[:16]


def compose_servicer(spec: ServicerSpec, output: str | Path) -> Path:
    """Compose the servicer, validate it with yourdfpy and write it atomically to ``output``.

    A servicer of several arms, or of an arm URDF with an SRDF beside it, also gets its SRDF
    (each arm's pairs never checked, prefixed) next to it, as ``output`` suffixed ``.srdf``.

    Raises:
        ModelError: the arm URDF cannot be read, or the result does not validate.
        UnknownNameError: a joint to lock is not in the arm (lists the arm's joints).
        LockedJointError: a joint locked outside its limits.
        InputError: bad numbers in ``spec``.
    """
    return write_composed(compose(spec), output)


def write_composed(composed: Composed, output: str | Path) -> Path:
    """Write a composed servicer's URDF to ``output`` (and its SRDF beside it, both or none)."""
    if composed.srdf is None:
        return atomic_write_text(output, composed.text)
    path = Path(output).expanduser().resolve()
    return write_together({path.with_suffix(".srdf"): composed.srdf, path: composed.text})


#: How a composed servicer that is no URDF freefloat loads is refused.
REFUSED = "the composed servicer is refused, nothing written"


def compose_servicer_text(spec: ServicerSpec) -> str:
    """Compose the servicer and validate it with yourdfpy; return the URDF text (no file).

    Raises: as :func:`compose`.
    """
    return compose(spec, offer_ties=False).text


def compose(spec: ServicerSpec, offer_ties: bool = True) -> Composed:
    """Compose the servicer and validate it with yourdfpy (no file is written).

    An arm whose longest chains tie (a dual-arm torso) has no default end effector: a
    captured payload, which that tip would hold, is refused (:class:`AmbiguousEndEffectorError`,
    naming the candidates). Otherwise :attr:`Composed.end_effectors` lists every tip of such
    an arm with ``offer_ties`` (the compose command: the scenario names the ones it plans
    for), and is empty without (a scenario's servicer: its ``end_effectors`` name them).

    Raises:
        ModelError: an arm URDF cannot be read, or the result does not validate.
        UnknownNameError: a joint to lock is not in its arm (lists the arm's joints).
        LockedJointError: a joint locked outside its limits.
        InputError: bad numbers in ``spec``, or two arms with one prefix.
    """
    import yourdfpy

    arms = spec.arms()
    links, joints = [], []
    materials: dict[str, Any] = {}
    locked: dict[str, float] = {}
    marked: dict[str, float] = {}  # locked by an earlier freefloat, in an arm's own URDF
    notes: list[str] = []
    prismatic: set[str] = set()
    bare: dict[str, None] = {}  # arms without collision geometry, each warned of once
    for arm in arms:
        part = arm_part(arm)
        if not any(link.collisions for link in part.links):  # nothing for clearance to measure
            bare[arm.arm] = None
        notes += _mount_notes(spec, arm)
        links += part.links
        joints += part.joints
        for material in part.materials:
            materials.setdefault(material.name, material)
        locked.update(part.locked)
        marked.update(part.marked)
        notes += part.notes
        prismatic |= part.prismatic
    for name in bare:
        LOGGER.warning(
            "no link of the arm %r has collision geometry: clearance between it and the "
            "spacecraft cannot be checked, and plans may pass it through the box; add "
            "<collision> elements to its URDF",
            name,
        )
    spacecraft, hull = _spacecraft(spec)
    names = [a.arm if a.arm in ARMS else Path(a.arm).stem for a in arms]
    composed = yourdfpy.Robot(
        name=spec.name or "_".join(names) + "_servicer",
        links=[spacecraft, *links],
        joints=joints,
        materials=[hull, *materials.values()],
    )
    urdf = yourdfpy.URDF(
        robot=composed,
        build_scene_graph=False,
        load_meshes=False,
        filename_handler=yourdfpy.filename_handler_null,
    )
    missing = sorted({name for name in _mesh_names(composed) if resolve_mesh(name) is None})
    if missing:  # the dynamics do not need them; playback draws such links as simple shapes
        LOGGER.warning(
            "%d mesh file(s) of the arm cannot be found (e.g. %s); the servicer is composed "
            "and plans, and playback draws those links as simple shapes",
            len(missing),
            missing[0],
        )
    if not urdf.validate():
        errors = "; ".join(str(e) for e in getattr(urdf, "errors", []))
        raise ModelError(f"the composed URDF does not validate: {errors or 'unknown error'}")

    text = _marked_text(urdf, {**marked, **locked})
    try:  # a closed loop, say, before Pinocchio builds the model below (it would crash)
        check_urdf_xml(text)
    except ModelError as exc:
        raise ModelError(f"{REFUSED}: {exc}") from None
    # A payload needs its arm's tip; without one, an arm whose longest chains tie (a dual-arm
    # torso) offers every tip: the scenario names the ones it plans for.
    prefixes = [a.prefix for a in arms]
    tips = arm_tips(text, prefixes, strict=spec.payload is not None)
    if not tips and offer_ties:
        tips = every_tip(text, prefixes)
    # a named arm's SRDF is found by the servicer's name, unless its links are prefixed
    first = arms[0]
    own = len(arms) > 1 or first.prefix or first.arm not in ARM_SRDFS
    own = bool(own) and any(arm_srdf(a.arm) is not None for a in arms)
    srdf = merged_srdf([a.arm for a in arms], prefixes) if own else None
    for note in notes:
        LOGGER.warning("%s", note)  # a choice the user did not state
    if spec.payload is not None:
        from .payload import attach_payload

        text = attach_payload(text, tips[0], spec.payload)
    return Composed(text, locked, tuple(notes), tips, srdf, frozenset(prismatic))


def _marked_text(urdf: Any, locked: dict[str, float]) -> str:
    """The yourdfpy URDF's text, its ``locked`` joints (rad or m) marked as such.

    The mark (:data:`~.designed_bodies.LOCKED_ATTRIBUTE`) keeps the arm as designed: a locked
    joint still separates its bodies for clearance.
    """
    from lxml import etree  # yourdfpy's own XML library

    tree = urdf.write_xml()
    for element in tree.iter("joint"):
        if element.get("name") in locked:
            element.set(LOCKED_ATTRIBUTE, repr(float(locked[element.get("name")])))
    body = etree.tostring(tree, pretty_print=True, encoding="unicode")
    return "<?xml version='1.0' encoding='UTF-8'?>\n" + body


#: Changes whenever a composed servicer's text would differ for the same spec (2: locked
#: joints marked, :mod:`.designed_bodies`), so that an older cache file is not reused.
COMPOSED_VERSION = 2

#: How far (m) a mount point may lie from the spacecraft box's surface without a note.
MOUNT_TOLERANCE = 1e-3


def _mount_notes(spec: ServicerSpec, arm: ArmSpec) -> list[str]:
    """A note when ``arm``'s mount point is not on the spacecraft box's surface.

    Inside the box or off it, the arm is fixed there rigidly, as if on a massless pedestal:
    legal, and said, since a mistyped mount (a size for a half size) composes silently.
    """
    half = 0.5 * np.asarray(spec.base_size, dtype=float)
    where = np.abs(np.asarray(arm.mount, dtype=float))
    outside = float(np.linalg.norm(np.maximum(where - half, 0.0)))
    depth = float(np.min(half - where))
    off = outside if outside > 0.0 else -depth  # the signed distance to the surface (m)
    if abs(off) <= MOUNT_TOLERANCE:
        return []
    how = f"{off:.3g} m off the box's surface" if off > 0 else f"{-off:.3g} m inside the box"
    size = " x ".join(f"{x:g}" for x in spec.base_size)
    return [
        f"the arm {arm.arm!r} is mounted at {list(arm.mount)} m, {how} ({size} m, faces at "
        f"+-{', +-'.join(f'{h:g}' for h in half)} m): it is fixed there rigidly, as on a "
        "massless pedestal; mount it on a face if that is not meant"
    ]


def _spacecraft(spec: ServicerSpec) -> tuple[Any, Any]:
    """The spacecraft link (a uniform box) and its material."""
    import yourdfpy

    ixx, iyy, izz = spec.inertia
    box = yourdfpy.Geometry(box=yourdfpy.Box(size=np.array(spec.base_size, dtype=float)))
    hull = yourdfpy.Material(
        name="freefloat_hull", color=yourdfpy.Color(rgba=np.array([0.78, 0.78, 0.82, 1.0]))
    )
    spacecraft = yourdfpy.Link(
        name=BASE_LINK,
        inertial=yourdfpy.Inertial(
            origin=np.eye(4), mass=float(spec.base_mass), inertia=np.diag([ixx, iyy, izz])
        ),
        visuals=[yourdfpy.Visual(name="hull", origin=np.eye(4), geometry=box, material=hull)],
        collisions=[yourdfpy.Collision(name="hull", origin=np.eye(4), geometry=box)],
    )
    return spacecraft, hull


def _mesh_names(robot: Any) -> list[str]:
    return [
        element.geometry.mesh.filename
        for link in robot.links
        for element in (*link.visuals, *link.collisions)
        if element.geometry is not None and element.geometry.mesh is not None
    ]


def resolve_mesh(name: str) -> Path | None:
    """Absolute path of a mesh reference (``package://`` via example-robot-data), or None."""
    if name.startswith("package://"):
        share = example_robot_data_dir()
        path = share / name[len("package://") :] if share else None
    elif name.startswith("file://"):
        path = Path(name[len("file://") :])
    else:
        path = Path(name)
    return path if path is not None and path.is_file() else None
