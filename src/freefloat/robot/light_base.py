"""A warning for a URDF whose root link, taken as the spacecraft, is lighter than its arm."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from ..progress import LOGGER
from .model import Robot
from .payload import PAYLOAD_LINK

__all__ = ["warn_light_base"]


def warn_light_base(robot: Robot) -> None:
    """Warn when the URDF's root, taken as the spacecraft, is lighter than the arm it carries.

    A fixed-base arm's URDF (root ``world`` or a small mounting link) planned as it is makes
    that link the spacecraft: a legal model, rarely the one meant (masses in kg, the model's).
    A captured payload does not count (:func:`_payload_mass`): a client heavier than its
    servicer is a real case, not a modelling slip.
    """
    masses = [float(inertia.mass) for inertia in robot.model.inertias[1:]]
    base, carried = masses[0], sum(masses[1:]) - _payload_mass(robot)
    if base < carried:
        LOGGER.warning(
            "the spacecraft (the URDF's root link %r, %.3g kg) is lighter than the arm it "
            "carries (%.3g kg); if the URDF describes an arm alone, add a spacecraft with "
            "freefloat compose or an inline [robot] table",
            robot.base_link,
            base,
            carried,
        )


def _payload_mass(robot: Robot) -> float:
    """The captured payload's mass (kg) as the robot's URDF file states it; 0 without one.

    Pinocchio merges the payload's link into the end effector's body, so its mass is read
    from the file.
    """
    if not any(frame.name == PAYLOAD_LINK for frame in robot.model.frames):
        return 0.0
    try:
        root = ET.parse(robot.urdf).getroot()
    except (OSError, ET.ParseError):
        return 0.0
    for link in root.iter("link"):
        mass = link.find("inertial/mass")
        if link.get("name") == PAYLOAD_LINK and mass is not None:
            return float(mass.get("value", 0.0))
    return 0.0
