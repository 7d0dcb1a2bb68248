"""Results that depend on a robot's physics alone, kept per content rather than per object.

A user's process reads the same URDF many times (a sweep, a study, each ``ff.plan`` of a
scenario file builds a new :class:`.Robot`). What depends only on the robot's physics (the
planar axis, the planar map's coefficients, the planar bounds) is then the same each time;
:class:`RobotCache` keeps it under a key of everything it can depend on (:func:`content_key`):
the URDF text, the movable joints with their limits as the robot holds them, and every joint's
type, axis and placement and every body's inertia as the Pinocchio model holds them *now*, so a
model whose masses were changed in place (``freefloat.robust``) gets its own entry.
"""

from __future__ import annotations

import dataclasses
import hashlib
import threading
import weakref
from collections import OrderedDict
from collections.abc import Callable
from typing import Generic, TypeVar

import numpy as np

from .model import Robot

__all__ = ["RobotCache", "content_key"]

T = TypeVar("T")


def content_key(robot: Robot) -> str | None:
    """SHA-256 (hex) of what a robot's physics is made of; None if it has no URDF text."""
    if not robot.urdf_text:
        return None
    model = robot.model
    digest = hashlib.sha256(robot.urdf_text.encode("utf-8"))
    digest.update(repr((robot.base_link, robot.joints)).encode("utf-8"))
    for index in range(model.njoints):
        joint = model.joints[index]
        digest.update(joint.shortname().encode("utf-8"))  # RX, RZ, ...: the axis when aligned
        axis = getattr(joint.extract(), "axis", None)  # an unaligned joint's own axis
        if axis is not None:
            digest.update(np.asarray(axis, dtype=float).tobytes())
        digest.update(model.jointPlacements[index].homogeneous.tobytes())
        digest.update(model.inertias[index].toDynamicParameters().tobytes())
    return digest.hexdigest()


class RobotCache(Generic[T]):
    """Values computed once per robot content (at most ``size`` kept, the oldest dropped).

    A robot without URDF text (built in memory) is kept per object, for as long as it lives.
    Safe across threads (a Dask worker's): one lock per cache, held while a value is computed,
    so each content is computed once; a computation may use *other* caches (each its own lock).
    """

    def __init__(self, size: int = 32) -> None:
        self._size = size
        self._by_content: OrderedDict[str, T] = OrderedDict()
        self._by_object: weakref.WeakKeyDictionary[Robot, tuple[T]] = weakref.WeakKeyDictionary()
        self._lock = threading.Lock()

    def get(self, robot: Robot, compute: Callable[[], T]) -> T:
        """The value for ``robot``: kept, or ``compute()`` kept for the next robot like it."""
        key = content_key(robot)
        with self._lock:
            return self._get(robot, key, compute)

    def _get(self, robot: Robot, key: str | None, compute: Callable[[], T]) -> T:
        """:meth:`get` under the lock (``key``: the robot's :func:`content_key`)."""
        if key is None:
            if robot not in self._by_object:
                self._by_object[robot] = (compute(),)
            return self._by_object[robot][0]
        if key in self._by_content:
            self._by_content.move_to_end(key)
            return self._by_content[key]
        value = _read_only(compute())
        self._by_content[key] = value
        if len(self._by_content) > self._size:
            self._by_content.popitem(last=False)
        return value


def _read_only(value: T) -> T:
    """``value`` with its arrays (itself, or a dataclass's fields) made read-only: shared."""
    arrays = [value] if isinstance(value, np.ndarray) else []
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        arrays = [getattr(value, f.name) for f in dataclasses.fields(value)]
    for array in arrays:
        if isinstance(array, np.ndarray):
            array.setflags(write=False)
    return value
