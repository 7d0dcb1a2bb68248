"""A warning for a URDF whose root link, taken as the spacecraft, is lighter than its arm."""

from __future__ import annotations

from ..progress import LOGGER
from .model import Robot
from .payload import held_payload

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
    """The captured payload's mass (kg; :func:`.payload.held_payload`); 0 without one."""
    held = held_payload(robot)
    return 0.0 if held is None else float(held.mass)
