"""A URDF's text checked and built into a free-flyer Pinocchio model, kept per text.

Parsing is a function of the text alone (the XML checks, Pinocchio's parser, the checks of the
model built, the default end effectors): a process that loads the same unchanged URDF again (a
fresh scenario naming the same file) takes the parsed robot kept for that text. A text that
fails is parsed (and refused) again each time. The model kept is never handed out: every load
gets its own copy (:meth:`pinocchio.Model.copy`), so a caller that changes its model (a
perturbed inertia, say) changes no other robot. The parser's messages are kept with it and
logged (at DEBUG level) at every load, as at the first.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import pinocchio as pin

from ..errors import AmbiguousEndEffectorError, ModelError
from ..progress import LOGGER
from .built_model import check_built_model
from .end_effectors import end_effector_candidates
from .parser_messages import parser_messages
from .urdf_checks import CheckedUrdf, check_urdf_xml

__all__ = ["Joint", "ParsedUrdf", "parsed_urdf"]

#: Pinocchio joint model short names, by the kind of joint freefloat exposes.
_KINDS = {
    "JointModelRX": "revolute",
    "JointModelRY": "revolute",
    "JointModelRZ": "revolute",
    "JointModelRevoluteUnaligned": "revolute",
    "JointModelRUBX": "continuous",
    "JointModelRUBY": "continuous",
    "JointModelRUBZ": "continuous",
    "JointModelRevoluteUnboundedUnaligned": "continuous",
    "JointModelPX": "prismatic",
    "JointModelPY": "prismatic",
    "JointModelPZ": "prismatic",
    "JointModelPrismaticUnaligned": "prismatic",
}

#: The most texts kept (the oldest goes first).
_KEPT = 16


@dataclass(frozen=True)
class Joint:
    """One movable joint, as the API sees it.

    Attributes:
        name: URDF joint name.
        kind: ``"revolute"``, ``"continuous"`` or ``"prismatic"``.
        index: Pinocchio joint index.
        idx_q: first index of the joint in Pinocchio's configuration vector.
        idx_v: index of the joint in Pinocchio's velocity vector.
        lower: lower position limit (rad or m; ``-inf`` for a continuous joint).
        upper: upper position limit (rad or m; ``+inf`` for a continuous joint).
        velocity_limit: URDF velocity limit (rad/s or m/s; ``inf`` when not given).
        effort_limit: URDF effort limit (N m or N; ``inf`` when not given).
    """

    name: str
    kind: str
    index: int
    idx_q: int
    idx_v: int
    lower: float
    upper: float
    velocity_limit: float
    effort_limit: float

    @property
    def unit(self) -> str:
        """Unit of the joint's position: ``"rad"`` or ``"m"``."""
        return "m" if self.kind == "prismatic" else "rad"

    @property
    def effort_unit(self) -> str:
        """Unit of the joint's effort: ``"N m"`` (torque) or ``"N"`` (force, prismatic)."""
        return "N" if self.kind == "prismatic" else "N m"

    @property
    def angular(self) -> bool:
        """True for revolute and continuous joints (positions in rad)."""
        return self.kind != "prismatic"


@dataclass(frozen=True)
class ParsedUrdf:
    """A URDF text checked and built (see the module docstring).

    Attributes:
        checked: what the XML checks read (name, root link, links, movable joints, mass).
        model: the Pinocchio model with a free-flyer root joint, no gravity (kept: copy it).
        joints: the movable joints, in Pinocchio's (depth-first) order.
        frames: names of the body frames, in model order.
        messages: what the parser printed (urdfdom's lines).
    """

    checked: CheckedUrdf
    model: pin.Model
    joints: tuple[Joint, ...]
    frames: tuple[str, ...]
    messages: tuple[str, ...] = ()

    @functools.cached_property
    def candidates(self) -> tuple[str, ...]:
        """The default end effectors (:func:`end_effector_candidates`); several: ambiguous."""
        return tuple(end_effector_candidates(self.model))

    def default_end_effector(self, path: Path) -> str:
        """The one default end effector (``path`` names the file in the error).

        Raises:
            AmbiguousEndEffectorError: several chains are longest.
        """
        if len(self.candidates) > 1:
            raise AmbiguousEndEffectorError(list(self.candidates), str(path))
        return self.candidates[0]


def parsed_urdf(text: str, path: Path) -> ParsedUrdf:
    """The URDF ``text`` checked and built, kept per text (``path`` names it in errors).

    Raises:
        ModelError: malformed XML, a check refused, or Pinocchio cannot parse it.
    """
    parsed = _PARSED.get(text)
    if parsed is None:
        parsed = _parse(text, path)  # its messages logged as the parser printed them
        if len(_PARSED) >= _KEPT:
            _PARSED.pop(next(iter(_PARSED)))
        _PARSED[text] = parsed
    else:
        for line in parsed.messages:
            LOGGER.debug("URDF parser: %s", line)
    return parsed


def _parse(text: str, path: Path) -> ParsedUrdf:
    """:func:`parsed_urdf`'s work: the checks, Pinocchio's parser, the checks of its model."""
    try:
        checked = check_urdf_xml(text)
    except ModelError as exc:
        raise ModelError(str(exc), urdf=str(path)) from None
    error: RuntimeError | ValueError | None
    with parser_messages() as messages:
        try:  # the checked tree, written out again: Pinocchio loads what was checked
            model = pin.buildModelFromXML(checked.text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            error = exc
        else:
            error = None
    if error is not None:
        said = next((m for m in messages if m.startswith("Error:")), "")
        said = f"; urdfdom: {said.removeprefix('Error:').strip()}" if said else ""
        raise ModelError(f"Pinocchio cannot parse it ({error}{said})", urdf=str(path)) from None
    model.gravity = pin.Motion.Zero()  # free flight: no gravity acts on the system
    joints = _joints(model, path)
    try:
        check_built_model(model, checked)
    except ModelError as exc:
        raise ModelError(str(exc), urdf=str(path)) from None
    return ParsedUrdf(
        checked=checked,
        model=model,
        joints=tuple(joints),
        frames=tuple(f.name for f in model.frames if f.type == pin.FrameType.BODY),
        messages=tuple(messages),
    )


def _joints(model: pin.Model, path: Path) -> list[Joint]:
    """The movable joints of a free-flyer model, with their limits (rad or m, per s, N m or N).

    Raises:
        ModelError: a joint of unsupported type, inverted limits, or no movable joint.
    """
    joints = []
    for index in range(2, model.njoints):
        jm = model.joints[index]
        kind = _KINDS.get(jm.shortname())
        if kind is None:  # pragma: no cover - filtered by the XML check above
            raise ModelError(f"joint {model.names[index]!r} of unsupported type", urdf=str(path))
        lower, upper = -math.inf, math.inf
        if kind != "continuous":
            lower = float(model.lowerPositionLimit[jm.idx_q])
            upper = float(model.upperPositionLimit[jm.idx_q])
            if not lower < upper:
                fixed = (
                    '; a joint that cannot move is type="fixed" (or lock it: [robot] lock, '
                    "compose --lock)"
                    if lower == upper
                    else ""
                )
                raise ModelError(
                    f"joint {model.names[index]!r} has limits [{lower}, {upper}]; lower must "
                    f"be below upper{fixed}",
                    urdf=str(path),
                )
        vel = float(model.velocityLimit[jm.idx_v])
        eff = float(model.effortLimit[jm.idx_v])
        joints.append(
            Joint(
                name=model.names[index],
                kind=kind,
                index=index,
                idx_q=jm.idx_q,
                idx_v=jm.idx_v,
                lower=lower,
                upper=upper,
                velocity_limit=vel if vel > 0 else math.inf,
                effort_limit=eff if eff > 0 else math.inf,
            )
        )
    if not joints:
        raise ModelError(
            "no movable joint (revolute, continuous or prismatic); a manipulator needs at least "
            "one",
            urdf=str(path),
        )
    return joints


#: The parsed robots kept, by URDF text (at most :data:`_KEPT`).
_PARSED: dict[str, ParsedUrdf] = {}
