"""The planner's lever-arm speed bounds (:mod:`freefloat.robot.pair_levers`) against truth.

Truth here is computed without the code under test: the joint axes and the shapes' placements
from Pinocchio (``forwardKinematics``, the world Jacobian's angular columns,
``updateGeometryPlacements``) one instant at a time, and every pair's signed distance from a
fresh collision model that measures every pair, at many instants inside each interval.
Robots: the shipped Panda, UR5 and dual UR5 servicers, and a small arm built here with slanted
axes, a continuous joint and offset shapes.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.problem.constraints.clearance_samples import bounds_between, lever_arms
from freefloat.problem.paths import JointPolynomials
from freefloat.problem.rate_bounds import rate_bounds
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.robot.motion_bound import BOUND_SLACK

import urdfs
from conftest import ROOT

SCENARIOS = ROOT / "robots" / "scenarios"
NAMES = ["panda_servicer", "ur5_servicer", "dual_ur5_servicer", "slanted"]


def _slanted_arm() -> str:
    """A box spacecraft and three links on slanted axes (the first continuous), each carrying
    a shape off its joint's axis: a box, a cylinder and a sphere."""
    body = urdfs.BASE.format(mass=100.0, i=16.7).replace(
        "<visual>", '<collision><geometry><box size="1 1 1"/></geometry></collision><visual>'
    )
    shapes = [
        '<origin xyz="0.3 0.1 0.05"/><geometry><box size="0.5 0.12 0.1"/></geometry>',
        '<origin xyz="0.25 -0.05 0.1" rpy="0 1.2 0.3"/>'
        '<geometry><cylinder radius="0.05" length="0.4"/></geometry>',
        '<origin xyz="0.35 0.1 -0.08"/><geometry><sphere radius="0.08"/></geometry>',
    ]
    axes = [(0, 0.6, 0.8), (0.6, 0, 0.8), (0.48, 0.6, 0.64)]
    kinds = ["continuous", "revolute", "revolute"]
    parent = "base"
    for i, (kind, axis, shape) in enumerate(zip(kinds, axes, shapes, strict=True), start=1):
        body += urdfs.joint(f"j{i}", parent, f"l{i}", kind, axis, (0.5, 0.1 * i, 0.05))
        link = urdfs.link(f"l{i}", mass=3.0, inertia=(0.05, 0.1, 0.1))
        body += link.replace("</link>", f"<collision>{shape}</collision>\n  </link>")
        parent = f"l{i}"
    return urdfs.robot(body, "slanted")


@pytest.fixture(scope="module", params=NAMES)
def case(request, tmp_path_factory):
    """(robot, collision model, a fresh model for truth, start joints, duration)."""
    if request.param == "slanted":
        path = tmp_path_factory.mktemp("arm") / "slanted.urdf"
        path.write_text(_slanted_arm())
        robot = ff.load_robot(path)
        build = lambda: CollisionModel(robot)  # noqa: E731
        start, duration = np.array([0.3, -0.4, 0.8]), 4.0
    else:
        s = ff.Scenario.from_toml(SCENARIOS / f"{request.param}.toml")
        robot, srdf = s.robot, s.safety.srdf or known_srdf(s.robot)
        build = lambda: CollisionModel(robot, srdf, s.safety.obstacles)  # noqa: E731
        start, duration = np.asarray(s.start, dtype=float), s.duration
    model = build()
    assert model.levers is not None and model.n_pairs > 0
    return robot, model, build(), start, duration


def _path(n: int, start: np.ndarray, duration: float, seed: int) -> JointPolynomials:
    """A smooth random path from ``start``: quintic wiggles of a few rad per joint."""
    rng = np.random.default_rng(seed)
    monomials = [[a, *rng.normal(0.0, 1.0, 5) / duration ** np.arange(1, 6)] for a in start]
    assert len(monomials) == n
    return JointPolynomials.from_monomials(monomials, duration)


def _truth_arms(robot: ff.Robot, model: CollisionModel, joints: np.ndarray) -> np.ndarray:
    """(G, N) each shape's bounding sphere's centre distance from each joint's axis plus its
    radius (m), from Pinocchio's frames and geometry placements; NaN where the joint does
    not move the shape."""
    data, geometry = robot.model.createData(), model.geometry
    gdata = pin.GeometryData(geometry)
    q = robot.configuration(joints)
    pin.computeJointJacobians(robot.model, data, q)
    pin.updateGeometryPlacements(robot.model, data, geometry, gdata)
    arms = np.full((len(geometry.geometryObjects), robot.n), np.nan)
    for k, joint in enumerate(robot.joints):
        axis = data.J[3:6, joint.idx_v]
        origin = data.oMi[joint.index].translation
        subtree = set(robot.model.subtrees[joint.index])
        for g, obj in enumerate(geometry.geometryObjects):
            if obj.parentJoint not in subtree:
                continue
            obj.geometry.computeLocalAABB()
            centre = gdata.oMg[g].act(np.asarray(obj.geometry.aabb_center))
            arms[g, k] = np.linalg.norm(np.cross(centre - origin, axis) / np.linalg.norm(axis))
            arms[g, k] += float(obj.geometry.aabb_radius)
    return arms


def test_arms_are_pinocchios_distances_from_the_joint_axes(case):
    robot, model, _, start, _ = case
    rng = np.random.default_rng(11)
    joints = start + rng.normal(0.0, 0.8, (6, robot.n))
    arms = model.levers.arms(joints)
    for i, q in enumerate(joints):
        truth = _truth_arms(robot, model, q)
        moved = ~np.isnan(truth)
        assert moved.sum() > robot.n  # some shapes are moved by several joints
        assert np.allclose(arms[i][moved], truth[moved], atol=1e-12, rtol=0.0)


def _intervals(duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Narrow, middling and wide intervals (s) spread along the path."""
    starts = np.array([0.05, 0.2, 0.37, 0.5, 0.61, 0.8]) * duration
    widths = np.array([1 / 200, 1 / 25, 0.1, 1 / 200, 0.25, 1 / 25]) * duration
    return starts, starts + widths


def test_levers_hold_at_every_instant_inside_the_interval(case):
    """Each shape's lever about each joint that moves it is at least its sphere's true
    distance from the axis (Pinocchio) at 60 instants inside the interval; and tighter than
    its reach somewhere (not vacuous)."""
    robot, model, _, start, duration = case
    levers = model.levers
    tighter = 0
    for seed in (1, 2):
        path = _path(robot.n, start, duration, seed)
        t0, t1 = _intervals(duration)
        arms0, arms1 = levers.arms(path.evaluate(t0).q), levers.arms(path.evaluate(t1).q)
        bound = levers.levers(rate_bounds(path, t0, t1), t1 - t0, (arms0, arms1))
        for i in range(len(t0)):
            inside = path.evaluate(np.linspace(t0[i], t1[i], 60)).q
            truth = np.max([_truth_arms(robot, model, q) for q in inside], axis=0)
            moved = ~np.isnan(truth)
            assert np.all(truth[moved] <= bound[i][moved] + 1e-12)
            tighter += int(np.sum(bound[i][moved] < 0.9 * levers.reach[moved]))
    assert tighter > 0


def test_speeds_are_never_above_the_motion_weights_and_often_below(case):
    robot, model, _, start, duration = case
    path = _path(robot.n, start, duration, 3)
    t = np.linspace(0.0, duration, 26)
    arms = lever_arms(model, path.evaluate(t).q)
    rates = rate_bounds(path, t[:-1], t[1:])
    speed = model.levers.speeds(rates, np.diff(t), (arms[:-1], arms[1:]))
    former = rates @ model.weights.T
    assert np.all(speed <= former)
    assert np.mean(speed < 0.9 * former) > 0.3  # a tighter bound for many (interval, pair)


def test_each_pairs_distance_changes_no_faster_than_its_speed(case):
    """Every pair's signed distance, measured by a fresh model at 80 instants inside each
    interval: its largest change between any two of them is within the speed bound times
    their time apart, and its smallest is at least the bound between the two ends; the
    clearance's bound (:func:`bounds_between`, from the collision model's own queries) is
    at most the smallest distance inside."""
    robot, model, fresh, start, duration = case
    near = 0
    for seed in (4, 5):
        path = _path(robot.n, start, duration, seed)
        t0, t1 = _intervals(duration)
        q0, q1 = path.evaluate(t0).q, path.evaluate(t1).q
        ends = (lever_arms(model, q0), lever_arms(model, q1))
        speed = model.levers.speeds(rate_bounds(path, t0, t1), t1 - t0, ends)
        with model.own_bounds():
            lower = (model.closest_many(q0).lower, model.closest_many(q1).lower)
        clearance = bounds_between(model, path, (t0, t1), lower, ends)
        for i in range(len(t0)):
            times = np.linspace(t0[i], t1[i], 80)
            dense = np.array([fresh.distances(q).values for q in path.evaluate(times).q])
            change = np.abs(dense[:, None, :] - dense[None, :, :])  # (80, 80, P)
            apart = np.abs(times[:, None] - times[None, :])[..., None]
            assert np.all(change <= speed[i] * apart + BOUND_SLACK)
            per_pair = 0.5 * (dense[0] + dense[-1] - speed[i] * (t1[i] - t0[i])) - BOUND_SLACK
            assert np.all(per_pair <= dense.min(axis=0))
            assert clearance[i] <= dense.min()
            near += int(clearance[i] > dense.min() - 0.05)
    assert near > 0  # the clearance's bound comes within 5 cm of the truth somewhere


def test_a_prismatic_joint_has_no_levers(tmp_path):
    """Lengths change with a prismatic joint: no motion weights, no lever arms."""
    path = tmp_path / "slider.urdf"
    ball = '<collision><geometry><sphere radius="0.1"/></geometry></collision>'
    cube = '<collision><geometry><box size="1 1 1"/></geometry></collision>'
    text = urdfs.slider_arm().replace('<link name="l2">', f'<link name="l2">{ball}')
    path.write_text(text.replace("<visual>", f"{cube}<visual>"))
    model = CollisionModel(ff.load_robot(path))
    assert model.n_pairs > 0
    assert model.weights is None and model.levers is None
