"""The ``[robot]`` table of a scenario: a URDF or a composed servicer, with joints locked.

Forms (degrees at this edge, metres for lengths; see :mod:`freefloat.problem.scenario`)::

    robot = "dual_ur5_servicer"            # a shipped name or a URDF path (no table)

    [robot]                                # a URDF with joints locked
    urdf = "r2_dualarm.urdf"
    lock = ["r2/left_arm/joint6", { joint = "r2/right_arm/joint6", value = 10.0 }]

    [robot]                                # one arm on a box spacecraft
    arm = "panda"
    base_mass = 100.0
    base_size = [0.6, 0.6, 0.6]
    mount = [0.3, 0.0, 0.0]                # also mount_rpy_deg, base_inertia, keep_gripper, lock

    [robot]                                # two (or more) arms on one box
    base_mass = 100.0
    base_size = [0.6, 0.6, 0.6]
    arms = [
      { arm = "ur5", mount = [0.3, 0.2, 0.0], mount_rpy_deg = [0, 90, 0], prefix = "left_" },
      { arm = "ur5", mount = [0.3, -0.2, 0.0], mount_rpy_deg = [0, 90, 0], prefix = "right_" },
    ]

A locked joint is made fixed at its value: the ``value`` given (deg, or m for a prismatic
joint), else its ``[start]`` value, else 0; a value outside the joint's limits is refused
(:class:`~freefloat.errors.LockedJointError`). A servicer of several arms names each arm's
joints and links with its prefix (default ``arm1_``, ``arm2_``...) and checks clearance with
each arm's SRDF pairs (prefixed; written beside the servicer) and every pair between arms.
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, InputLimitError, ScenarioError, UnknownNameError, excerpt
from ..files import read_text_file
from ..robot.locations import is_path_like
from ..robot.lock import default_lock, lock_joints, movable_joints
from ..robot.model import MAX_URDF_BYTES, resolve_robot
from .cache_files import cached_text
from .limits import MAX_ANGLE_DEG, MAX_LENGTH_M, MAX_MAGNITUDE, check_number

if TYPE_CHECKING:
    from ..robot.compose import ServicerSpec

__all__ = [
    "RobotSource",
    "check_keys",
    "number",
    "numbers",
    "robot_source",
    "scenario_errors",
    "servicer_cache_dir",
    "triple",
]

LOGGER = logging.getLogger(__name__)

_SERVICER_KEYS = (
    "arm",
    "arms",
    "base_mass",
    "base_size",
    "base_inertia",
    "mount",
    "mount_rpy_deg",
    "lock",
    "keep_gripper",
)
_ARM_KEYS = ("arm", "mount", "mount_rpy_deg", "prefix", "keep_gripper")
_URDF_KEYS = ("urdf", "lock")


def check_keys(table: Mapping[str, Any], valid: tuple[str, ...], where: str) -> None:
    """Refuse a key of ``table`` not in ``valid`` (the error lists the valid ones)."""
    for key in table:
        if key not in valid:
            raise UnknownNameError(f"key in {where}", key, valid)


def scenario_errors(check: Any, *args: Any, **kwargs: Any) -> Any:
    """``check(*args, **kwargs)`` with its plain input errors as :class:`ScenarioError`.

    Limit errors (:class:`InputLimitError`) pass as they are: they carry the limit.
    """
    try:
        return check(*args, **kwargs)
    except InputLimitError:
        raise
    except InputError as exc:
        raise ScenarioError(str(exc)) from None


def number(
    value: Any, where: str, limit: float = MAX_MAGNITUDE, unit: str = "", low: float | None = None
) -> float:
    """A finite number at most ``limit`` in magnitude, at least ``low`` if given (README)."""
    return float(scenario_errors(check_number, value, where, limit, unit, low))


def numbers(
    value: Any,
    count: int,
    where: str,
    limit: float = MAX_MAGNITUDE,
    unit: str = "",
    low: float | None = None,
) -> np.ndarray:
    """A list of ``count`` finite numbers of magnitude at most ``limit`` (at least ``low``)."""
    if not isinstance(value, list) or len(value) != count:
        raise ScenarioError(f"{where} must be a list of {count} numbers, got {excerpt(value)}")
    return np.array([number(v, f"{where}[{i}]", limit, unit, low) for i, v in enumerate(value)])


def triple(
    table: Mapping[str, Any],
    key: str,
    default: list[float] | None = None,
    where: str = "[robot]",
) -> Any:
    """Three numbers of ``table[key]`` (deg for ``*_deg``, kg m^2 for inertias, else m)."""
    limit, unit = (MAX_ANGLE_DEG, "deg") if key.endswith("_deg") else (MAX_LENGTH_M, "m")
    if key.endswith("inertia"):
        limit, unit = MAX_MAGNITUDE, "kg m^2"
    values = numbers(table.get(key, default), 3, f"{where} {key}", limit, unit)
    return tuple(float(x) for x in values)


def servicer_cache_dir() -> Path:
    """Folder of servicers composed from inline ``[robot]`` tables.

    ``$FREEFLOAT_CACHE`` if set, else ``$XDG_CACHE_HOME/freefloat/servicers`` (default
    ``~/.cache``).
    """
    if os.environ.get("FREEFLOAT_CACHE"):
        return Path(os.environ["FREEFLOAT_CACHE"])
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "freefloat" / "servicers"


@dataclass(frozen=True)
class RobotSource:
    """Where the robot of a scenario comes from.

    Attributes:
        urdf: its URDF path (a cache file for a composed or locked robot).
        text: the URDF text, written to that file by the scenario's ``write_robot`` unless
            the cache holds it already (:mod:`.cache_files`); None for a URDF of the user's.
        servicer: the composed servicer's description, if it is one.
        end_effectors: default end effectors (each arm's tip for several arms), or none.
        srdf: the SRDF of its pairs never checked, when the robot brings one (several arms:
            each arm's SRDF, prefixed; a URDF with an SRDF beside it).
        srdf_text: that SRDF's text, written as ``text`` is (None: the user's own file).
        locked: the joints locked by the scenario and their values (rad or m).
    """

    urdf: Path
    text: str | None = None
    servicer: ServicerSpec | None = None
    end_effectors: tuple[str, ...] = ()
    srdf: Path | None = None
    srdf_text: str | None = None
    locked: Mapping[str, float] = field(default_factory=dict)


def robot_source(value: Any, start: Any, relative_to: Path | None) -> RobotSource:
    """The robot a scenario's ``robot`` key names, with its ``lock`` list applied.

    ``start`` is the scenario's ``[start]`` table (degrees): a locked joint without a value
    is locked at its start value there.

    Raises:
        ScenarioError: a bad value in the table.
        UnknownNameError: an unknown key or joint to lock (lists the valid ones).
        LockedJointError: a locked value outside its joint's limits.
    """
    if isinstance(value, str):
        urdf = resolve_robot(value, relative_to)
        return RobotSource(urdf, srdf=_sibling_srdf(urdf))
    if not isinstance(value, Mapping):
        raise ScenarioError(
            "robot must be a shipped robot name, a URDF path or a [robot] table, got "
            f"{excerpt(value)}"
        )
    if "urdf" in value:
        check_keys(value, _URDF_KEYS, "[robot] (with urdf)")
        if not isinstance(value["urdf"], str):
            raise ScenarioError(f"[robot] urdf must be a path, got {excerpt(value['urdf'])}")
        urdf = resolve_robot(value["urdf"], relative_to)
        source = RobotSource(urdf, srdf=_sibling_srdf(urdf))
    else:
        source = _servicer(value, relative_to)
    lock = value.get("lock", [])
    if lock == []:
        return source
    text = source.text
    if text is None:
        text = read_text_file(source.urdf, "URDF", MAX_URDF_BYTES, ScenarioError)
    values = _lock_values(lock, text, start)
    locked = lock_joints(text, values, source.urdf.parent)
    digest = hashlib.sha256(locked.encode()).hexdigest()[:16]
    path = servicer_cache_dir() / f"{source.urdf.stem}-lock-{digest}.urdf"
    return RobotSource(
        path,
        locked,
        source.servicer,
        source.end_effectors,
        source.srdf,
        source.srdf_text,
        values,
    )


def _sibling_srdf(urdf: Path) -> Path | None:
    path = urdf.with_suffix(".srdf")
    return path if path.is_file() else None


def _lock_values(lock: Any, text: str, start: Any) -> dict[str, float]:
    """``{joint: value}`` (rad or m) of a ``lock`` list: given value, start value, or else 0.

    Or else the middle of the joint's range when 0 is outside it
    (:func:`~freefloat.robot.lock.default_lock`).
    """
    if not isinstance(lock, list):
        raise ScenarioError(
            '[robot] lock must be a list of joint names or { joint = "name", value = deg }, '
            f"got {excerpt(lock)}"
        )
    movable = movable_joints(text)
    given = start.get("joints", {}) if isinstance(start, Mapping) else {}
    given = given if isinstance(given, Mapping) else {}
    values: dict[str, float] = {}
    for item in lock:
        if isinstance(item, Mapping):
            check_keys(item, ("joint", "value"), "[robot] lock entry")
            name, raw = item.get("joint"), item.get("value")
        else:
            name, raw = item, None
        if not isinstance(name, str):
            raise ScenarioError(
                '[robot] lock entries are joint names or { joint = "name", value = deg }, got '
                f"{excerpt(item)}"
            )
        if name not in movable:
            raise UnknownNameError("joint to lock", name, list(movable))
        if name in values:  # the last would win, silently
            raise ScenarioError(f"[robot] lock names joint {name!r} twice; lock each joint once")
        kind, lower, upper = movable[name]
        if raw is None and name not in given:  # 0, or the middle of a range without it
            values[name], note = default_lock(f"joint {name!r}", kind, lower, upper)
            if note:  # a choice the user did not state
                LOGGER.warning("%s", note)
            continue
        raw = given[name] if raw is None else raw
        angular = kind != "prismatic"
        limit, unit = (MAX_ANGLE_DEG, "deg") if angular else (MAX_LENGTH_M, "m")
        amount = number(raw, f"[robot] lock value of {name!r}", limit, unit)
        values[name] = math.radians(amount) if angular else amount
    if movable and set(values) >= set(movable):
        raise ScenarioError(
            f"[robot] lock locks every movable joint ({', '.join(movable)}); leave at least "
            "one to move"
        )
    return values


def _servicer(table: Mapping[str, Any], relative_to: Path | None = None) -> RobotSource:
    """The cache path of the servicer an inline ``[robot]`` table describes, and its URDF.

    The URDF text is None when the cache file exists (it is read from there); otherwise the
    servicer is composed in memory and written only by the scenario's ``write_robot``.
    """
    from ..robot.arm_tips import arm_tips
    from ..robot.compose import ServicerSpec, compose_servicer_text
    from ..robot.srdf import ARM_SRDFS, arm_srdf, merged_srdf

    check_keys(table, _SERVICER_KEYS, "[robot]")
    arms = _arms(table, relative_to)
    for key in ("base_mass", "base_size"):
        if key not in table:
            raise ScenarioError(f"[robot] needs {key!r} (required: arm, base_mass, base_size)")
    first = arms[0]
    spec = ServicerSpec(
        arm=first.arm,
        base_mass=number(table["base_mass"], "[robot] base_mass", MAX_MAGNITUDE, "kg"),
        base_size=triple(table, "base_size"),
        base_inertia=triple(table, "base_inertia") if "base_inertia" in table else None,
        mount=first.mount,
        mount_rpy=first.mount_rpy,
        keep_gripper=first.keep_gripper,
        more_arms=tuple(arms[1:]),
        prefix=first.prefix,
    )
    path = servicer_cache_dir() / f"{spec.key()}.urdf"
    text = cached_text(path) or compose_servicer_text(spec)  # composed again unless vouched for
    if len(arms) == 1 and not first.prefix and (first.arm in ARM_SRDFS or not arm_srdf(first.arm)):
        return RobotSource(path, text, spec)  # a named arm's SRDF is found by its name
    settled = spec.arms()
    prefixes = [a.prefix for a in settled]
    # an arm whose longest chains tie leaves the end effectors to the scenario or the loader
    tips = arm_tips(text, prefixes, strict=False)
    srdf = path.with_suffix(".srdf")
    srdf_text = cached_text(srdf) or merged_srdf([a.arm for a in settled], prefixes)
    return RobotSource(path, text, spec, tips, srdf, srdf_text)


def _arms(table: Mapping[str, Any], relative_to: Path | None = None) -> list[Any]:
    """The arms of a servicer table: ``arm`` (with ``mount``...) or an ``arms`` list.

    An arm given as a relative URDF path is taken relative to ``relative_to`` (the scenario's
    folder), as ``robot = "..."`` is; an arm name (:data:`~freefloat.robot.compose.ARMS`) as is.
    """
    from ..robot.compose import ARMS, ArmSpec

    if ("arm" in table) == ("arms" in table):
        raise ScenarioError(
            "[robot] needs 'arm' (one arm) or 'arms' (a list of arm tables), not both or neither"
        )
    if "arm" in table:
        items: list[Any] = [
            {k: table[k] for k in ("arm", "mount", "mount_rpy_deg", "keep_gripper") if k in table}
        ]
    else:
        items = table["arms"]
        if (
            not isinstance(items, list)
            or not items
            or not all(isinstance(a, Mapping) for a in items)
        ):
            raise ScenarioError("[robot] arms must be a list of tables { arm = ..., mount = ... }")
        for key in ("mount", "mount_rpy_deg"):
            if key in table:
                raise ScenarioError(f"[robot] {key} belongs in each entry of arms")
    arms = []
    for index, item in enumerate(items):
        where = f"[robot] arms #{index + 1}" if "arms" in table else "[robot]"
        check_keys(item, _ARM_KEYS, where)
        if not isinstance(item.get("arm"), str):
            raise ScenarioError(
                f"{where} arm must be an arm name or a URDF path, got {excerpt(item.get('arm'))}"
            )
        prefix = item.get("prefix", "")
        if not isinstance(prefix, str):
            raise ScenarioError(f"{where} prefix must be text, got {excerpt(prefix)}")
        keep = item.get("keep_gripper", table.get("keep_gripper", False))
        if not isinstance(keep, bool):
            raise ScenarioError(f"{where} keep_gripper must be true or false, got {excerpt(keep)}")
        rpy = triple(item, "mount_rpy_deg", [0.0] * 3, where)
        arm = item["arm"]
        if arm not in ARMS and relative_to is not None and is_path_like(arm):
            arm = os.path.normpath(relative_to / Path(arm).expanduser())  # absolute: kept
        arms.append(
            ArmSpec(
                arm,
                triple(item, "mount", [0.0, 0.0, 0.0], where),
                tuple(math.radians(a) for a in rpy),
                prefix,
                (),
                keep,
            )
        )
    return arms
