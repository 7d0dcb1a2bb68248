"""The faces of boxes fixed to the spacecraft as lower bounds of their pairs' distances.

Truth the bound does not compute: a ball against a box in closed form (the nearest point of
the box by clamping, written here), coal's exact signed distances of the shapes (overlaps
included), and the count of coal queries a batch makes with and without the faces.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.collision import CollisionModel, Obstacle, known_srdf
from freefloat.robot.fixed_boxes import ROUNDING

from conftest import ROOT
from test_collision import sphere_arm  # noqa: F401 (fixture)

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"
UR5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
#: Keep-out boxes fixed to the spacecraft, turned and offset; the last one crosses the arm's
#: reach, so some configurations overlap it.
BOXES = [
    Obstacle("plate", "box", (0.8, 0.05, 0.6), (0.1, 0.7, 0.3), (0.3, -0.2, 0.9)),
    Obstacle("crate", "box", (0.3, 0.4, 0.2), (0.6, -0.2, 0.6), (0.0, 0.5, -0.4)),
    Obstacle("beam", "box", (1.2, 0.08, 0.08), (0.5, 0.0, 0.5), (0.7, 0.1, 0.2)),
]

#: The sphere arm's spacecraft: a 1 m cube at its frame's origin.
SPACECRAFT = Obstacle("base", "box", (1.0, 1.0, 1.0))


def _ball_box(centre: np.ndarray, radius: float, box: Obstacle) -> float:
    """Signed distance (m) of a ball from a box obstacle, in closed form."""
    rotation = pin.rpy.rpyToMatrix(*box.rpy)
    local = rotation.T @ (centre - np.asarray(box.xyz))
    half = 0.5 * np.asarray(box.size)
    beyond = np.abs(local) - half
    if np.all(beyond <= 0.0):
        return float(beyond.max()) - radius  # inside: minus the depth to the nearest face
    return float(np.linalg.norm(np.maximum(beyond, 0.0))) - radius


def test_a_ball_against_a_fixed_box_is_bounded_by_its_closed_form(sphere_arm):  # noqa: F811
    """The sphere arm's ball link against its spacecraft's cube and turned keep-out boxes: the
    bound is the ball-box distance itself (a ball's bounding sphere is the ball), to the
    rounding allowed, inside a box as well as outside."""
    model = CollisionModel(sphere_arm, obstacles=BOXES)
    ball = next(g for g, o in enumerate(model.geometry.geometryObjects) if o.name == "l2_0")
    rng = np.random.default_rng(3)
    joints = rng.uniform(-3.0, 3.0, (200, 2))
    centres = model._kinematics.centres(joints)
    bounds = model._boxes.lower(centres)
    checked = 0
    for column, k in enumerate(model._boxes.pairs.tolist()):
        a, b = model.pairs[k]
        if ball not in (a, b):
            continue
        name = model.names[k].split("obstacle:")[-1]
        box = next((o for o in BOXES if o.name == name), SPACECRAFT)  # else the base cube
        truth = [_ball_box(c, 0.1, box) for c in centres[:, ball]]
        assert np.allclose(bounds[:, column], truth, rtol=0.0, atol=2 * ROUNDING)
        checked += 1
    assert checked == len(BOXES) + 1  # and the spacecraft's own box
    assert np.any(bounds < 0.0)  # some configurations put the ball inside a box


@pytest.mark.parametrize("path", [UR5, PANDA])
def test_the_faces_never_exceed_coals_distances(path):
    """Servicers with keep-out boxes, random configurations (some overlapping): every pair a
    fixed box holds is bounded below its exact signed distance (coal on the shapes), and the
    faces are tighter than the bounding spheres for most of the spacecraft's own pairs."""
    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot), BOXES)
    rng = np.random.default_rng(5)
    lower = np.array([max(j.lower, -3.0) for j in robot.joints])
    upper = np.array([min(j.upper, 3.0) for j in robot.joints])
    joints = rng.uniform(lower, upper, (40, robot.n))
    centres = model._kinematics.centres(joints)
    bounds = model._boxes.lower(centres)
    pairs = model._boxes.pairs
    first, second = model._pair_array[pairs].T
    spheres = (
        np.linalg.norm(centres[:, first] - centres[:, second], axis=2)
        - model._radii[first]
        - model._radii[second]
    )
    overlaps = 0
    for i, q in enumerate(joints):
        exact = model.distances(q).values[pairs]
        assert np.all(bounds[i] <= exact), [model.names[k] for k in pairs[bounds[i] > exact]]
        overlaps += int(np.sum(exact < 0.0))
    assert overlaps > 0  # overlapping shapes were bounded too
    own = np.array(["obstacle:" not in model.names[k] for k in pairs])
    assert np.mean(bounds[:, own] > spheres[:, own]) > 0.5


class _NoFaces:
    """Bounds no pair by faces: the bounding spheres alone, as before the faces."""

    pairs = np.zeros(0, dtype=int)

    @staticmethod
    def lower(centres: np.ndarray) -> np.ndarray:
        return np.zeros((len(centres), 0))


def test_a_batch_asks_coal_less_with_the_faces(monkeypatch):
    """The Panda servicer along its path: the same smallest distances and pairs with the
    faces as without them, from fewer coal queries."""
    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    u = np.linspace(0.0, 1.0, 40)
    joints = start + u[:, None] * (goal - start)
    queries = [0]
    compute = pin.computeDistance

    def counted(*args):
        queries[0] += 1
        return compute(*args)

    monkeypatch.setattr(pin, "computeDistance", counted)
    found = {}
    for faces in (True, False):
        model = CollisionModel(robot, known_srdf(robot))
        if not faces:  # the spheres alone
            model._boxes = _NoFaces()
        queries[0] = 0
        got = model.closest_many(joints, u)
        found[faces] = (got.values.tolist(), got.pairs.tolist(), queries[0])
    assert found[True][:2] == found[False][:2]
    assert found[True][2] < found[False][2]
    assert not math.isnan(found[True][0][0])
