"""Results kept per robot content: shared by robots read from one URDF, never by robots whose
physics differs (masses changed in place, other limits, a robot built without URDF text)."""

from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import pinocchio as pin
import pytest

from freefloat.physics.momentum import MomentumMap, cached_planar_axis, planar_axis
from freefloat.physics.planar_map import cached_identify, identify
from freefloat.problem.bounds import cached_planar_bounds, planar_bounds
from freefloat.robot import load_robot, robots_dir
from freefloat.robot.content_cache import RobotCache, content_key

URDF = robots_dir() / "planar_2dof.urdf"


def _bounds(robot):
    return cached_planar_bounds(MomentumMap(robot))


def test_robots_read_from_one_file_share_their_results():
    first, second = load_robot(URDF), load_robot(URDF)
    assert first is not second and first.model is not second.model
    assert content_key(first) == content_key(second)
    assert _bounds(first) is _bounds(second)
    shared = _bounds(first)
    axis = cached_planar_axis(first)
    for array in (shared.g_min, shared.g_max, axis, cached_identify(first).num):
        with pytest.raises(ValueError, match="read-only"):
            array *= -1.0


def test_masses_changed_in_place_get_their_own_bounds():
    robot = load_robot(URDF)
    before = _bounds(robot)
    index = robot.joints[-1].index
    body = robot.model.inertias[index]
    robot.model.inertias[index] = pin.Inertia(3.0 * body.mass, body.lever, 3.0 * body.inertia)
    after = _bounds(robot)
    # Truth: the uncached computation on the changed model.
    axis = planar_axis(robot)
    np.testing.assert_allclose(after.g_max, planar_bounds(MomentumMap(robot), axis=axis).g_max)
    np.testing.assert_allclose(after.g_min, planar_bounds(MomentumMap(robot), axis=axis).g_min)
    assert not np.allclose(after.g_max, before.g_max)
    assert cached_identify(robot) is not cached_identify(load_robot(URDF))
    fresh = identify(robot, axis)
    assert fresh is not None
    np.testing.assert_allclose(cached_identify(robot).gains(np.zeros(2)), fresh.gains(np.zeros(2)))


def test_other_limits_are_other_content():
    robot = load_robot(URDF)
    first = dataclasses.replace(robot.joints[0], lower=-1.0, upper=1.0)
    narrower = dataclasses.replace(robot, joints=(first, *robot.joints[1:]))
    assert content_key(narrower) != content_key(robot)
    wide = _bounds(robot)
    found = _bounds(narrower)
    assert found is not wide
    truth = planar_bounds(MomentumMap(narrower), axis=planar_axis(narrower))
    np.testing.assert_allclose(found.g_min, truth.g_min)
    np.testing.assert_allclose(found.g_max, truth.g_max)


def test_a_robot_without_text_is_kept_per_object_and_old_entries_are_dropped():
    cache: RobotCache[int] = RobotCache(size=2)
    calls = []

    def compute(value):
        calls.append(value)
        return value

    robots = [load_robot(URDF) for _ in range(2)]
    bare = dataclasses.replace(robots[0], urdf_text="")
    assert content_key(bare) is None
    assert cache.get(bare, lambda: compute(1)) == 1
    assert cache.get(bare, lambda: compute(2)) == 1  # the same object: kept
    other = dataclasses.replace(robots[1], urdf_text="")
    assert cache.get(other, lambda: compute(3)) == 3  # no text: not shared
    keys = []
    for k in range(3):
        robot = load_robot(URDF)
        robot.model.inertias[1] = pin.Inertia(
            1.0 + k, robot.model.inertias[1].lever, robot.model.inertias[1].inertia
        )
        keys.append(robot)
        cache.get(robot, lambda k=k: compute(10 + k))
    assert cache.get(keys[0], lambda: compute(99)) == 99  # the oldest entry was dropped
    assert cache.get(keys[2], lambda: compute(98)) == 12  # the newest is kept
    assert calls == [1, 3, 10, 11, 12, 99]


def test_threads_asking_at_once_compute_each_content_once():
    cache: RobotCache[int] = RobotCache()
    robot = load_robot(URDF)
    calls = []
    gate = threading.Barrier(8)

    def compute():
        calls.append(1)
        time.sleep(0.05)  # lets the other threads run meanwhile: without the lock they compute
        return 7

    results = []

    def ask():
        gate.wait()  # all eight threads ask together
        results.append(cache.get(robot, compute))

    threads = [threading.Thread(target=ask) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert results == [7] * 8
    assert calls == [1]


def test_a_robot_that_is_not_planar_has_no_planar_map_nor_bounds():
    robot = load_robot(robots_dir() / "ur5_servicer.urdf")
    assert cached_planar_axis(robot) is None
    assert cached_identify(robot) is None
    with pytest.raises(ValueError, match="does not turn about one axis"):
        cached_planar_bounds(MomentumMap(robot))


def test_a_joint_axis_changed_in_place_is_other_content():
    robot = load_robot(URDF)
    keys = []
    for axis in ((0.0, 0.6, 0.8), (0.0, 0.8, 0.6)):
        robot.model.joints[2] = pin.JointModel(pin.JointModelRevoluteUnaligned(*axis))
        keys.append(content_key(robot))
    assert keys[0] != keys[1]  # the same joint type, another axis


def test_a_computation_asking_for_its_own_content_raises_and_others_are_computed_apart():
    cache: RobotCache[int] = RobotCache()
    other: RobotCache[int] = RobotCache()
    robot = load_robot(URDF)

    def cycle() -> int:
        return cache.get(robot, cycle)  # its own content again: a cycle, not a hang

    with pytest.raises(RuntimeError, match="its own robot content"):
        cache.get(robot, cycle)
    # another cache's computation of the same content, from inside this one's: no cycle
    assert cache.get(robot, lambda: other.get(robot, lambda: 5) + 1) == 6
    assert other.get(robot, lambda: 99) == 5


def test_threads_asking_for_other_contents_are_not_held_up():
    """One content's computation waits until another thread has asked for another content
    and got it: with one lock held while computing, that other thread would wait for it."""
    cache: RobotCache[int] = RobotCache()
    slow, fast = load_robot(URDF), load_robot(URDF)
    fast.model.inertias[1] = pin.Inertia(
        2.0, fast.model.inertias[1].lever, fast.model.inertias[1].inertia
    )
    answered, started = threading.Event(), threading.Event()

    def waits() -> int:
        started.set()
        assert answered.wait(timeout=30), "the other content was held up"
        return 1

    worker = threading.Thread(target=lambda: cache.get(slow, waits))
    worker.start()
    assert started.wait(timeout=30)  # the slow computation has begun and holds its lock
    assert cache.get(fast, lambda: 2) == 2
    answered.set()
    worker.join()
    assert cache.get(slow, lambda: 3) == 1
