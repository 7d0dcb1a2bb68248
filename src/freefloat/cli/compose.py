"""``freefloat compose``: mount one or more arms on a box spacecraft and write one URDF."""

from __future__ import annotations

import argparse
import dataclasses
import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import AmbiguousEndEffectorError, InputError, ModelError
from ..problem.limits import MAX_ANGLE_DEG, MAX_LENGTH_M, MAX_MAGNITUDE, check_number
from ..progress import stage
from .common import Commands, check_not_read, check_outputs

if TYPE_CHECKING:
    from ..robot.compose import ServicerSpec
    from ..robot.payload import Payload

__all__ = ["add_parser", "check", "run"]


@dataclasses.dataclass(frozen=True)
class _Numbers:
    """A numeric option: its numbers' names, its limit and unit, and how it is given.

    Attributes:
        option: the option (``--base-size``).
        names: one metavar per number (``("X", "Y", "Z")``); one name: a single number.
        high: the largest magnitude accepted (in ``unit``).
        unit: the unit of the numbers (``m``, ``kg``, ``kg m^2``, ``deg``).
        help: the option's help, or None.
        required: the option must be given.
        append: given once per ``--arm`` (a list of lists).
    """

    option: str
    names: tuple[str, ...]
    high: float
    unit: str
    help: str | None = None
    required: bool = False
    append: bool = False

    def add(self, parser: argparse.ArgumentParser) -> None:
        """Add the option to ``parser``."""
        shape: dict[str, Any] = {"metavar": self.names[0]}
        if len(self.names) > 1:
            shape = {"nargs": len(self.names), "metavar": self.names}
        if self.required:
            shape["required"] = True
        if self.append:
            shape["action"] = "append"
        parser.add_argument(self.option, type=float, help=self.help, **shape)

    def check(self, args: argparse.Namespace) -> None:
        """Refuse a number beyond the limit (:class:`InputLimitError` naming the option)."""
        given = getattr(args, self.option.lstrip("-").replace("-", "_"))
        if given is None:
            return
        values = [given] if len(self.names) == 1 else given
        if self.append:
            values = [x for each in values for x in each]
        for value in values:
            check_number(value, self.option, self.high, self.unit)


_XYZ = ("X", "Y", "Z")
#: The spacecraft's and the mounts' numbers, in the order of ``--help``.
_BASE = (
    _Numbers("--base-mass", ("KG",), MAX_MAGNITUDE, "kg", required=True),
    _Numbers("--base-size", _XYZ, MAX_LENGTH_M, "m", "box edges [m]", required=True),
    _Numbers(
        "--base-inertia",
        ("IXX", "IYY", "IZZ"),
        MAX_MAGNITUDE,
        "kg m^2",
        "principal moments [kg m^2] (default: uniform box)",
    ),
    _Numbers(
        "--mount",
        _XYZ,
        MAX_LENGTH_M,
        "m",
        "arm root in the spacecraft frame [m] (once per --arm)",
        required=True,
        append=True,
    ),
    _Numbers(
        "--mount-rpy",
        ("R", "P", "Y"),
        MAX_ANGLE_DEG,
        "deg",
        "arm root roll, pitch, yaw [deg] (once per --arm; default 0 0 0)",
        append=True,
    ),
)
#: The ``--payload-*`` options: a captured payload fixed to the end effector.
_PAYLOAD = (
    _Numbers(
        "--payload-mass",
        ("KG",),
        MAX_MAGNITUDE,
        "kg",
        "captured payload fixed to the end effector",
    ),
    _Numbers(
        "--payload-com",
        _XYZ,
        MAX_LENGTH_M,
        "m",
        "payload centre of mass in the end-effector frame [m] (default: 0 0 0)",
    ),
    _Numbers(
        "--payload-inertia",
        ("IXX", "IYY", "IZZ", "IXY", "IXZ", "IYZ"),
        MAX_MAGNITUDE,
        "kg m^2",
        "payload inertia about its centre of mass [kg m^2] (default: the uniform --payload-box's)",
    ),
    _Numbers(
        "--payload-box",
        _XYZ,
        MAX_LENGTH_M,
        "m",
        "payload box (visual and collision), centred on its centre of mass [m]",
    ),
)


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_compose = commands.add_parser(
        "compose",
        help="mount one or more arms on a box spacecraft and write one validated URDF",
        description="Compose a servicer: example-robot-data arms (panda, ur5, kinova, "
        "xarm7, z1) or URDF files, mounted on a uniform box spacecraft (--arm A --mount ... "
        "--arm B --mount ...). Gripper and finger joints are locked (at 0, or mid-range when "
        "0 is outside their limits) unless --keep-gripper. Angles in degrees.",
    )
    p_compose.add_argument(
        "--arm",
        required=True,
        action="append",
        help="arm name or URDF path; repeat for more arms, each with its --mount",
    )
    for numbers in _BASE:
        numbers.add(p_compose)
    p_compose.add_argument(
        "--prefix",
        action="append",
        help="put before each link and joint name of the arm (once per --arm; with several "
        "arms default arm1_, arm2_...)",
    )
    p_compose.add_argument(
        "--lock",
        nargs="*",
        action="append",
        metavar="JOINT[=DEG]",
        help="more joints to lock, at 0 or at DEG (with several arms, prefixed names); "
        "several after one --lock, or --lock repeated",
    )
    p_compose.add_argument(
        "--keep-gripper", action="store_true", help="keep gripper and finger joints movable"
    )
    for numbers in _PAYLOAD:
        numbers.add(p_compose)
    p_compose.add_argument(
        "--name", help="the robot's name in the URDF (default: the output file's name, no .urdf)"
    )
    p_compose.add_argument("-o", "--output", required=True, help="URDF file to write")
    p_compose.set_defaults(func=run, check=check)
    return p_compose


def check(args: argparse.Namespace) -> None:
    """Refuse numbers beyond the limits and an unwritable output before any work."""
    for numbers in (*_BASE, *_PAYLOAD):
        numbers.check(args)
    if args.name is not None and not args.name:  # "" would fall back to the default silently
        raise InputError("--name is empty; give the robot's name, or leave --name out")
    check_outputs(args, ("-o", "output"))


def run(args: argparse.Namespace) -> int:
    """Compose the servicer, write its URDF (and SRDF) and print what it is."""
    from ..robot.compose import REFUSED, compose, write_composed
    from ..robot.model import load_robot
    from ..robot.srdf import arm_srdf

    spec = _servicer_spec(args, _payload(args))
    with stage("compose servicer"):
        try:
            composed = compose(spec)
        except AmbiguousEndEffectorError as exc:  # a payload: compose cannot name its holder
            raise ModelError(
                f"{REFUSED}: the payload's holder is ambiguous: {len(exc.candidates)} chains are "
                f"longest ({', '.join(exc.candidates)}); compose cannot choose it: write the "
                "servicer inline in a scenario ([robot] arm = ..., [payload], and "
                'end_effector = "..." naming the holder)'
            ) from None
        # loaded from its text first: a servicer freefloat refuses is never written (and an
        # earlier file of that name stays as it was)
        try:
            robot = load_robot(Path(args.output), composed.end_effectors, text=composed.text)
        except ModelError as exc:  # named as the servicer composed, not as a file read
            reason = str(exc).removeprefix(f"{exc.urdf}: ") if exc.urdf else str(exc)
            raise ModelError(f"{REFUSED}: {reason}") from None
        if composed.srdf is not None:  # written beside the output: never over an arm's own
            check_not_read(args, [arm_srdf(a.arm) for a in spec.arms()], ".srdf", "an arm's")
        path = write_composed(composed, args.output)
    print(f"freefloat compose: wrote {path}")
    if composed.srdf is not None:
        whose = (
            "each arm's SRDF pairs, prefixed" if len(spec.arms()) > 1 else "the arm's SRDF pairs"
        )
        print(f"  with {path.with_suffix('.srdf').name}: {whose}")
    for name, value in composed.locked.items():
        shown = value if name in composed.prismatic else math.degrees(value)
        print(f"  locked {name} at {shown:.6g} {'m' if name in composed.prismatic else 'deg'}")
    tips = ", ".join(repr(e) for e in robot.end_effectors)
    print(
        f"  {robot.n} joints ({', '.join(robot.joint_names)}), total mass "
        f"{robot.total_mass:.3f} kg, end effector{'s' if len(robot.end_effectors) > 1 else ''} "
        f"{tips}"
    )
    if len(robot.end_effectors) > len(spec.arms()):  # an arm's longest chains tie
        print(
            "  an arm's longest chains tie: a scenario names the end effectors it plans for "
            '(end_effectors = ["..."])'
        )
    if spec.payload is not None:
        print(
            f"  captured payload {spec.payload.mass:g} kg fixed to {robot.end_effector!r} "
            "(link 'captured_payload')"
        )
    return 0


def _payload(args: argparse.Namespace) -> Payload | None:
    """The ``--payload-*`` options as a validated ``Payload``, or None without a mass."""
    from ..robot.payload import Payload

    extra = [args.payload_com, args.payload_inertia, args.payload_box]
    if args.payload_mass is None:
        if any(v is not None for v in extra):
            raise InputError(
                "--payload-com, --payload-inertia and --payload-box need --payload-mass"
            )
        return None
    if not (math.isfinite(args.payload_mass) and args.payload_mass > 0.0):  # the mass first
        raise InputError(
            f"--payload-mass must be a finite number > 0 kg, got {args.payload_mass!r}"
        )
    com = tuple(args.payload_com or (0.0, 0.0, 0.0))
    box = tuple(args.payload_box) if args.payload_box is not None else None
    if args.payload_inertia is not None:
        ixx, iyy, izz, ixy, ixz, iyz = (float(v) for v in args.payload_inertia)
        return Payload(args.payload_mass, com, (ixx, iyy, izz, ixy, ixz, iyz), box)
    if box is None:
        raise InputError(
            "--payload-mass needs --payload-inertia IXX IYY IZZ IXY IXZ IYZ [kg m^2] "
            "(or --payload-box X Y Z [m] for a uniform box)"
        )
    return Payload.uniform_box(args.payload_mass, box, com)


def _servicer_spec(args: argparse.Namespace, payload: Payload | None) -> ServicerSpec:
    """The ``compose`` options as a spec: one ``--arm`` with its ``--mount`` per arm."""
    from ..robot.compose import ArmSpec, ServicerSpec

    count = len(args.arm)
    rpys = args.mount_rpy or [[0.0, 0.0, 0.0]] * count
    prefixes = args.prefix or [""] * count
    given_per_arm = (("--mount", args.mount), ("--mount-rpy", rpys), ("--prefix", prefixes))
    for option, given in given_per_arm:
        if len(given) != count:
            raise InputError(f"give {option} once per --arm ({count}), got {len(given)}")
    arms = [
        ArmSpec(arm, tuple(mount), tuple(math.radians(a) for a in rpy), prefix)
        for arm, mount, rpy, prefix in zip(args.arm, args.mount, rpys, prefixes, strict=True)
    ]
    if count > 1:
        arms = [
            dataclasses.replace(a, prefix=a.prefix or f"arm{i + 1}_") for i, a in enumerate(arms)
        ]
    locks: list[list[str | tuple[str, float]]] = [[] for _ in arms]
    if args.lock is not None and not all(args.lock):  # one list per --lock
        raise InputError("--lock needs at least one JOINT or JOINT=DEG after it")
    seen: dict[str, str] = {}
    for item in [item for given in args.lock or () for item in given]:
        name, equals, degrees = item.partition("=")
        if equals and not degrees.strip():
            raise InputError(f"--lock {item}: give JOINT or JOINT=DEG (a number after =)")
        if name in seen:
            raise InputError(
                f"--lock {name} given twice ({seen[name]} and {item}); lock each joint once"
            )
        seen[name] = item
        value = 0.0
        if degrees:
            try:
                amount = float(degrees)
            except ValueError:
                raise InputError(f"--lock {item}: give JOINT or JOINT=DEG") from None
            value = math.radians(check_number(amount, f"--lock {name}", MAX_ANGLE_DEG, "deg"))
        owner = next((i for i, a in enumerate(arms) if name.startswith(a.prefix)), None)
        if owner is None:
            raise InputError(
                f"--lock {name}: name a joint with its arm's prefix "
                f"({', '.join(a.prefix for a in arms)})"
            )
        local = name[len(arms[owner].prefix) :]
        locks[owner].append((local, value) if degrees else local)
    arms = [
        dataclasses.replace(a, lock=tuple(lock), keep_gripper=args.keep_gripper)
        for a, lock in zip(arms, locks, strict=True)
    ]
    first = arms[0]
    return ServicerSpec(
        arm=first.arm,
        base_mass=args.base_mass,
        base_size=tuple(args.base_size),
        base_inertia=tuple(args.base_inertia) if args.base_inertia else None,
        mount=first.mount,
        mount_rpy=first.mount_rpy,
        lock=first.lock,
        keep_gripper=args.keep_gripper,
        payload=payload,
        more_arms=tuple(arms[1:]),
        prefix=first.prefix,
        name=_default_name(args.output) if args.name is None else args.name,
    )


def _default_name(output: str) -> str:
    """The output file's name as a robot name: other characters as '_' ("" if none is left)."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", Path(output).stem).lstrip(".-")[:100]
    return name if re.search(r"[A-Za-z0-9]", name) else ""
