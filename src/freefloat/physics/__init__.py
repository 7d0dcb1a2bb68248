"""Physics of the free floater: momentum map, attitude propagation, torques and replay."""

from .attitude import geodesic_angle, quat_from_zyx, zyx_from_quat
from .dynamics import InverseDynamics, inverse_dynamics
from .momentum import MomentumMap, is_planar, planar_axis
from .replay import ReplayResult, replay

__all__ = [
    "InverseDynamics",
    "MomentumMap",
    "ReplayResult",
    "geodesic_angle",
    "inverse_dynamics",
    "is_planar",
    "planar_axis",
    "quat_from_zyx",
    "replay",
    "zyx_from_quat",
]
