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
    Safe across threads (a Dask worker's): each content is computed once, under a lock of its
    own (threads asking for other contents go on meanwhile); a computation may ask this cache
    for another content, and asking for its own content again raises rather than hangs.
    """

    def __init__(self, size: int = 32) -> None:
        self._size = size
        self._by_content: OrderedDict[str, T] = OrderedDict()
        self._by_object: weakref.WeakKeyDictionary[Robot, tuple[T]] = weakref.WeakKeyDictionary()
        self._lock = threading.Lock()  # guards the dictionaries, never held while computing
        self._gates: dict[object, threading.RLock] = {}  # one per content being computed

    def get(self, robot: Robot, compute: Callable[[], T]) -> T:
        """The value for ``robot``: kept, or ``compute()`` kept for the next robot like it.

        Raises:
            RuntimeError: ``compute`` asked for the same robot content again (a cycle).
        """
        key = content_key(robot)
        gate_key: object = key if key is not None else id(robot)
        found = self._kept(robot, key)
        if found is not None:
            return found[0]
        with self._lock:
            gate = self._gates.setdefault(gate_key, threading.RLock())
        mine = (id(self), gate_key)  # other caches may compute the same content meanwhile
        with gate:
            if mine in _computing():
                raise RuntimeError("a cached computation asked for its own robot content")
            found = self._kept(robot, key)  # another thread may have computed it meanwhile
            if found is not None:
                return found[0]
            _computing().add(mine)
            try:
                value = compute()
            finally:
                _computing().discard(mine)
            with self._lock:
                self._store(robot, key, value)
                self._gates.pop(gate_key, None)
            return value

    def _kept(self, robot: Robot, key: str | None) -> tuple[T] | None:
        """The kept value for ``robot`` (in a 1-tuple: a value may be None), or None."""
        with self._lock:
            if key is None:
                return self._by_object.get(robot)
            if key in self._by_content:
                self._by_content.move_to_end(key)
                return (self._by_content[key],)
            return None

    def _store(self, robot: Robot, key: str | None, value: T) -> None:
        """Keep ``value`` for ``robot`` (under the lock); its arrays become read-only if shared."""
        if key is None:
            self._by_object[robot] = (value,)
            return
        self._by_content[key] = _read_only(value)
        if len(self._by_content) > self._size:
            self._by_content.popitem(last=False)


_LOCAL = threading.local()


def _computing() -> set[object]:
    """The contents this thread is computing now (to tell a cycle from a wait)."""
    if not hasattr(_LOCAL, "keys"):
        _LOCAL.keys = set()
    keys: set[object] = _LOCAL.keys
    return keys


def _read_only(value: T) -> T:
    """``value`` with its arrays (itself, or a dataclass's fields) made read-only: shared."""
    arrays = [value] if isinstance(value, np.ndarray) else []
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        arrays = [getattr(value, f.name) for f in dataclasses.fields(value)]
    for array in arrays:
        if isinstance(array, np.ndarray):
            array.setflags(write=False)
    return value
