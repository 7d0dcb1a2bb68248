"""Clearance queries in batches: sphere centres placed at once, and the same closest pairs.

Truth here: the sphere arm's closed-form sphere centre, Pinocchio's own placements of every
shape (one configuration at a time) for joints of every kind, and a fresh model that measures
every pair at every configuration.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.robot.sphere_kinematics import SphereKinematics

from conftest import ROOT
from test_collision import SPHERE_ARM, _sphere_centre, sphere_arm  # noqa: F401 (fixture)

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"
DUAL = ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml"


def test_the_sphere_arms_centre_is_its_closed_form(sphere_arm):  # noqa: F811
    model = CollisionModel(sphere_arm)
    objects = [obj.name for obj in model.geometry.geometryObjects]
    kinematics = SphereKinematics(sphere_arm, model.geometry, model._centres)
    rng = np.random.default_rng(5)
    joints = rng.uniform(-3.0, 3.0, (40, 2))
    centres = kinematics.centres(joints)[:, objects.index("l2_0")]
    want = np.array([_sphere_centre(*q) for q in joints])
    assert np.allclose(centres, want, atol=1e-13, rtol=0.0)


#: The sphere arm with a continuous first joint about a slanted axis and a prismatic second.
MIXED_ARM = (
    SPHERE_ARM.replace('name="q1" type="revolute"', 'name="q1" type="continuous"')
    .replace(
        '<axis xyz="0 0 1"/>\n    <limit lower="-3.1"',
        '<axis xyz="0 0.6 0.8"/>\n    <limit lower="-3.1"',
        1,
    )
    .replace('name="q2" type="revolute"', 'name="q2" type="prismatic"')
    .replace(
        '<axis xyz="0 0 1"/>\n    <limit lower="-3.1" upper="3.1"',
        '<axis xyz="1 0 0"/>\n    <limit lower="-0.5" upper="0.5"',
        1,
    )
)


@pytest.mark.parametrize("which", ["mixed", "panda", "dual"])
def test_sphere_centres_are_pinocchios_placements(which, tmp_path):
    """Every shape's sphere centre, batched, against Pinocchio placing the shapes one
    configuration at a time (continuous, slanted, prismatic and revolute joints)."""
    if which == "mixed":
        path = tmp_path / "mixed.urdf"
        path.write_text(MIXED_ARM)
        robot = ff.load_robot(path)
        kinds = {j.kind for j in robot.joints}
        assert kinds == {"continuous", "prismatic"}
    else:
        robot = ff.Scenario.from_toml(PANDA if which == "panda" else DUAL).robot
    model = CollisionModel(robot)
    kinematics = SphereKinematics(robot, model.geometry, model._centres)
    rng = np.random.default_rng(11)
    lower = np.array([max(j.lower, -3.0) for j in robot.joints])
    upper = np.array([min(j.upper, 3.0) for j in robot.joints])
    joints = rng.uniform(lower, upper, (25, robot.n))
    batched = kinematics.centres(joints)
    data, gdata = robot.model.createData(), pin.GeometryData(model.geometry)
    for b, q in enumerate(joints):
        pin.updateGeometryPlacements(
            robot.model, data, model.geometry, gdata, robot.configuration(q)
        )
        for g, placement in enumerate(gdata.oMg):
            assert np.allclose(batched[b, g], placement.act(model._centres[g]), atol=1e-12)


@pytest.mark.parametrize("path", [PANDA, DUAL])
def test_a_batch_gives_the_closest_pair_of_every_pair_measured(path):
    """Along a path and around it, slotted as the solvers ask, after earlier batches: each
    row's smallest distance, pair and gradient are those of a fresh model measuring every
    pair (brute force), and every pair's reported lower bound holds against its distance."""
    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    walked = CollisionModel(robot, known_srdf(robot))
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    rng = np.random.default_rng(4)
    u = np.linspace(0.0, 1.0, 24)
    fresh = CollisionModel(robot, known_srdf(robot))
    for round_ in range(3):  # the second and third batches start from the bounds kept
        joints = start + u[:, None] * (goal - start) + rng.normal(0.0, 0.05 * round_, (24, robot.n))
        got = walked.closest_many(joints, u, gradients=True)
        for i, q in enumerate(joints):
            every = fresh.distances(q, gradients=True)
            k = int(np.argmin(every.values))
            assert (float(got.values[i]), int(got.pairs[i])) == (float(every.values[k]), k)
            assert np.array_equal(got.gradients[i], every.gradients[k])
            assert np.all(got.lower[i] <= every.values + 1e-9)


def test_gradients_of_a_batch_against_finite_differences():
    """Each row's gradient against central differences of that pair's distance (a fresh
    model, every pair measured), on the Panda servicer: pairs between two arm links (only
    some joints move both) and between an arm link and the spacecraft."""
    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    rng = np.random.default_rng(8)
    joints = start + rng.uniform(0.0, 1.0, (12, 1)) * (goal - start) + rng.normal(0, 0.3, (12, 7))
    got = model.closest_many(joints, np.linspace(0.0, 1.0, 12), gradients=True)
    kinds = set()
    h = 1e-6
    for i, q in enumerate(joints):
        k = int(got.pairs[i])
        a, b = model.pairs[k]
        moving = [int(model.geometry.geometryObjects[g].parentJoint) > 1 for g in (a, b)]
        kinds.add(tuple(moving))
        numeric = np.array(
            [
                (fresh.distances(q + h * e).values[k] - fresh.distances(q - h * e).values[k])
                / (2 * h)
                for e in np.eye(robot.n)
            ]
        )
        assert np.allclose(got.gradients[i], numeric, atol=2e-6, rtol=1e-4), (i, k)
    assert kinds == {(True, True), (False, True)}  # arm / arm and spacecraft / arm


@pytest.mark.parametrize("rows", [10, 3])
def test_a_row_with_a_non_finite_joint_is_never_reported_clear(rows):
    """No bound holds for a joint vector with a NaN: every pair is asked, and the query is
    refused as a single configuration's is (a batch and a small batch alike), instead of the
    row reading as infinitely clear."""
    scenario = ff.Scenario.from_toml(PANDA)
    model = CollisionModel(scenario.robot, known_srdf(scenario.robot))
    joints = np.tile(np.asarray(scenario.start, dtype=float), (rows, 1))
    joints[1, 2] = math.nan
    with pytest.raises(ff.FreeFloatError):
        model.distances(joints[1])
    with pytest.raises(ff.FreeFloatError):
        model.closest_many(joints, np.linspace(0.0, 1.0, rows))


def _against_brute_force(model, fresh, joints, slots, gradients):
    """Every row's smallest distance and pair against a fresh model measuring every pair, and
    every reported lower bound against its pair's distance."""
    got = model.closest_many(joints, slots, gradients=gradients)
    for i, q in enumerate(joints):
        every = fresh.distances(q, gradients=gradients)
        k = int(np.argmin(every.values))
        assert (float(got.values[i]), int(got.pairs[i])) == (float(every.values[k]), k)
        if gradients:
            assert np.allclose(got.gradients[i], every.gradients[k], atol=1e-12)
        assert np.all(got.lower[i] <= every.values + 1e-9)


def test_impossible_coal_values_in_a_batch_are_asked_again(monkeypatch):
    """coal made to return impossible values (-DBL_MAX, NaN, -inf, 1e6) for one query in
    twenty: the batch places those rows again and asks again, and every row still gives the
    smallest distance, pair and gradient of every pair measured, with valid lower bounds."""
    import sys

    import freefloat.robot.pair_queries as pair_queries

    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(11)
    real = pin.computeDistance

    class Wrong:
        def __init__(self, value: float) -> None:
            self.min_distance = value

    def faulty(geometry, data, k):
        result = real(geometry, data, k)
        if rng.uniform() < 0.05:
            return Wrong(float(rng.choice([-sys.float_info.max, math.nan, -math.inf, 1e6])))
        return result

    class Pinocchio:
        def __getattr__(self, name):
            return faulty if name == "computeDistance" else getattr(pin, name)

    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    for round_ in range(4):
        u = rng.uniform(0.0, 1.0, (16, 1))
        joints = start + u * (goal - start) + rng.normal(0.0, 0.3, (16, robot.n))
        before = model.retries
        with monkeypatch.context() as faults:  # only the batch under test meets the faults
            faults.setattr(pair_queries, "pin", Pinocchio())
            got = model.closest_many(joints, None if round_ == 0 else u[:, 0], bool(round_ % 2))
        assert model.retries > before  # the faults were met and asked again
        for i, q in enumerate(joints):
            every = fresh.distances(q, gradients=bool(round_ % 2))
            k = int(np.argmin(every.values))
            assert (float(got.values[i]), int(got.pairs[i])) == (float(every.values[k]), k)
            assert np.all(got.lower[i] <= every.values + 1e-9)
            if round_ % 2:
                assert np.allclose(got.gradients[i], every.gradients[k], atol=1e-9)


def test_slots_repeated_in_a_batch_and_forgotten_between_batches(monkeypatch):
    """Slots repeated within one batch (recorded one after the other) and a store of five
    slots that forgets them all between batches: the answers are those of every pair."""
    from freefloat.robot.motion_bound import PairBounds

    monkeypatch.setattr(PairBounds, "SLOTS", 5)
    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(5)
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    for round_ in range(6):
        u = rng.uniform(0.0, 1.0, (12, 1))
        joints = start + u * (goal - start) + rng.normal(0.0, 0.05 * (1 + round_ % 3), (12, 7))
        slots = rng.choice([0.0, 0.5, 1.0], 12) if round_ % 2 else np.round(u[:, 0], 1)
        _against_brute_force(model, fresh, joints, slots, gradients=bool(round_ % 2))


def test_clearance_at_is_the_smallest_of_every_pair_measured():
    """The endpoint check measures only the pairs that can be the closest: the same figure and
    pair as every pair's distance, whatever the model was asked before."""
    from freefloat.robot.collision import clearance_at

    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(11)
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    for _ in range(12):
        joints = start + rng.uniform(0.0, 1.0) * (goal - start) + rng.normal(0.0, 0.3, 7)
        model.closest_many(np.repeat(joints[None], 9, axis=0) + 0.05)  # some history
        every = model.distances(joints).values
        k = int(np.argmin(every))
        found = clearance_at(model, joints)
        assert (found.distance, found.pair, found.name) == (float(every[k]), k, model.names[k])


def test_pairs_a_joint_set_moves_are_those_whose_distance_changes():
    """On the dual UR5 servicer with the right arm's joints held: the pairs
    :meth:`pairs_moved_by` the left arm's joints are exactly those whose distance (a fresh
    model, every pair measured) changes when only those joints move; the others keep
    theirs to the bit."""
    scenario = ff.Scenario.from_toml(DUAL)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    left = np.array([j.name.startswith("left_") for j in robot.joints])
    moved = model.pairs_moved_by(left)
    assert 0 < moved.sum() < len(moved)
    start = np.asarray(scenario.start)
    rng = np.random.default_rng(12)
    changed = np.zeros(len(moved), dtype=bool)
    before = model.distances(start).values
    for _ in range(4):
        q = start.copy()
        q[left] += rng.normal(0.0, 0.4, left.sum())
        changed |= model.distances(q).values != before
    assert np.array_equal(changed, moved)
    assert not model.pairs_moved_by(np.zeros(robot.n, dtype=bool)).any()
    assert model.pairs_moved_by(np.ones(robot.n, dtype=bool)).all()


@pytest.mark.parametrize("rows", [3, 24])
def test_the_smallest_among_some_pairs_is_that_of_every_pair_measured(rows):
    """``closest_many(..., among=)`` gives each row's smallest distance over those pairs
    alone, its pair and gradient, as a fresh model measuring every pair finds them (a batch
    and one row at a time), after batches over every pair have kept their bounds."""
    scenario = ff.Scenario.from_toml(DUAL)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    left = np.array([j.name.startswith("left_") for j in robot.joints])
    among = model.pairs_moved_by(left)
    start = np.asarray(scenario.start)
    rng = np.random.default_rng(13)
    u = np.linspace(0.0, 1.0, rows)
    hidden = 0  # rows where a held pair is the smallest of all
    for _ in range(2):
        joints = start + rng.normal(0.0, 0.2, (rows, robot.n)) * left
        model.closest_many(joints, u)  # every pair: bounds kept for the next call
        got = model.closest_many(joints, u, gradients=True, among=among)
        for i, q in enumerate(joints):
            every = fresh.distances(q, gradients=True)
            values = np.where(among, every.values, math.inf)
            k = int(np.argmin(values))
            assert (float(got.values[i]), int(got.pairs[i])) == (float(values[k]), k)
            assert np.array_equal(got.gradients[i], every.gradients[k])
            hidden += not among[int(np.argmin(every.values))]
    assert hidden > 0
