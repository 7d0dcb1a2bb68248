"""Keep-out objects fixed to the spacecraft: a box, a sphere or a capsule, posed in its frame."""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from ..errors import InputError

__all__ = ["SHAPES", "Obstacle"]

#: Keep-out shapes and the sizes each takes (m): box [x, y, z], sphere [r], capsule [r, length].
SHAPES = {"box": 3, "sphere": 1, "capsule": 2}


@dataclass(frozen=True)
class Obstacle:
    """A keep-out object fixed to the spacecraft.

    Attributes:
        name: its name (in messages and plots).
        shape: ``"box"``, ``"sphere"`` or ``"capsule"`` (a capsule's axis is its local z).
        size: box edge lengths [x, y, z], sphere [radius], capsule [radius, length] (m).
        xyz: position of its centre in the spacecraft frame (m).
        rpy: its orientation in the spacecraft frame, roll, pitch, yaw (rad).
    """

    name: str
    shape: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise InputError(
                f"obstacle {self.name!r}: unknown shape {self.shape!r}; valid: " + ", ".join(SHAPES)
            )
        if len(self.size) != SHAPES[self.shape]:
            raise InputError(
                f"obstacle {self.name!r}: a {self.shape} takes {SHAPES[self.shape]} size(s) "
                f"[m], got {len(self.size)}"
            )
        if not all(math.isfinite(s) and s > 0.0 for s in self.size):
            raise InputError(
                f"obstacle {self.name!r}: sizes must be finite and > 0 m, got {list(self.size)}"
            )
        if not all(math.isfinite(v) for v in (*self.xyz, *self.rpy)):
            raise InputError(f"obstacle {self.name!r}: pose must be finite numbers")

    def geometry(self) -> coal.CollisionGeometry:
        """The coal shape."""
        if self.shape == "box":
            return coal.Box(*self.size)
        if self.shape == "sphere":
            return coal.Sphere(self.size[0])
        return coal.Capsule(self.size[0], self.size[1])

    def placement(self) -> pin.SE3:
        """Its pose in the spacecraft frame."""
        return pin.SE3(pin.rpy.rpyToMatrix(*self.rpy), np.array(self.xyz, dtype=float))
