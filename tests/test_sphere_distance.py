"""The closed-form sphere distances against coal outside, brute force inside, and differences."""

from __future__ import annotations

import math

import coal
import numpy as np
import pytest

from freefloat.robot.distance_query import checked_distance
from freefloat.robot.sphere_distance import sphere_distance

SHAPES = {
    "sphere": lambda: coal.Sphere(0.2),
    "box": lambda: coal.Box(0.3, 0.5, 0.2),
    "cylinder": lambda: coal.Cylinder(0.15, 0.6),
    "capsule": lambda: coal.Capsule(0.1, 0.5),
}


def _transform(rng: np.random.Generator) -> coal.Transform3s:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    x, y, z, w = q
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return coal.Transform3s(rotation, rng.normal(0.0, 0.2, 3))


def _surface(name: str, count: int = 400) -> np.ndarray:
    """Dense points on the shape's surface (its own frame, m), for brute force."""
    u = np.linspace(0.0, 1.0, count)
    a, b = np.meshgrid(u, u, indexing="ij")
    a, b = a.ravel(), b.ravel()
    if name == "sphere":
        theta, phi = math.pi * a, 2 * math.pi * b
        return 0.2 * np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1
        )
    if name == "box":
        half = np.array([0.15, 0.25, 0.1])
        faces = []
        for k in range(3):
            i, j = [m for m in range(3) if m != k]
            for sign in (-1.0, 1.0):
                face = np.zeros((len(a), 3))
                face[:, k] = sign * half[k]
                face[:, i], face[:, j] = (2 * a - 1) * half[i], (2 * b - 1) * half[j]
                faces.append(face)
        return np.concatenate(faces)
    phi = 2 * math.pi * b
    if name == "cylinder":
        side = np.stack([0.15 * np.cos(phi), 0.15 * np.sin(phi), (2 * a - 1) * 0.3], 1)
        caps = [
            np.stack([0.15 * a * np.cos(phi), 0.15 * a * np.sin(phi), np.full_like(a, s)], 1)
            for s in (-0.3, 0.3)
        ]
        return np.concatenate([side, *caps])
    theta = math.pi * a  # capsule: a cylinder side and two half spheres
    side = np.stack([0.1 * np.cos(phi), 0.1 * np.sin(phi), (2 * a - 1) * 0.25], 1)
    ball = 0.1 * np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1
    )
    ends = ball + np.where(ball[:, 2:] >= 0.0, 0.25, -0.25) * np.array([0.0, 0.0, 1.0])
    return np.concatenate([side, ends])


def _inside(name: str, p: np.ndarray) -> bool:
    x, y, z = p
    if name == "sphere":
        return bool(np.linalg.norm(p) < 0.2)
    if name == "box":
        return bool(abs(x) < 0.15 and abs(y) < 0.25 and abs(z) < 0.1)
    if name == "cylinder":
        return bool(math.hypot(x, y) < 0.15 and abs(z) < 0.3)
    return bool(np.linalg.norm(p - [0.0, 0.0, min(max(z, -0.25), 0.25)]) < 0.1)


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_a_sphere_outside_is_coals_distance_and_inside_the_brute_force_depth(name):
    """Outside, the closed form is coal's GJK distance; with the sphere's centre inside, it is
    minus the centre's distance to the nearest of 160,000 surface points, less the radius (the
    samples' spacing bounds the error); the witness points are the distance apart along the
    normal, each on its own shape's surface."""
    rng = np.random.default_rng(5)
    shape, surface = SHAPES[name](), _surface(name)
    outside = inside = 0
    request = coal.DistanceRequest()
    request.gjk_tolerance = 1e-10
    while outside < 20 or inside < 20:
        place_b = _transform(rng)
        local = rng.uniform(-0.5, 0.5, 3)
        ball = coal.Sphere(0.05)
        rotation, origin = np.asarray(place_b.getRotation()), np.asarray(place_b.getTranslation())
        place_a = coal.Transform3s(np.eye(3), rotation @ local + origin)
        found = sphere_distance(ball, place_a, shape, place_b)
        assert found is not None
        p1, p2 = found.points
        assert np.allclose(p2 - p1, found.min_distance * found.normal, atol=1e-12)
        assert abs(np.linalg.norm(p1 - place_a.getTranslation()) - 0.05) < 1e-12
        if _inside(name, local):
            inside += 1
            depth = float(np.min(np.linalg.norm(surface - local, axis=1)))
            assert found.min_distance == pytest.approx(-depth - 0.05, abs=3e-3)
            assert np.min(np.linalg.norm(surface - rotation.T @ (p2 - origin), axis=1)) < 3e-3
        elif not _inside(name, local) and found.min_distance > 1e-3:
            outside += 1
            result = coal.DistanceResult()
            truth = coal.distance(ball, place_a, shape, place_b, request, result)
            assert found.min_distance == pytest.approx(truth, abs=1e-8)
            # coal's witnesses and normal: the same points, the same direction (ball to shape)
            assert np.allclose(found.normal, result.normal, atol=1e-6)
            assert np.allclose(p1, result.getNearestPoint1(), atol=1e-6)
            assert np.allclose(p2, result.getNearestPoint2(), atol=1e-6)


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_the_normal_is_the_distances_derivative_under_translation(name):
    """Moving the sphere by ``h e`` changes the distance by ``-h n . e`` (central differences),
    inside and outside, with either shape first."""
    rng = np.random.default_rng(8)
    shape, ball, h = SHAPES[name](), coal.Sphere(0.05), 1e-6
    for _ in range(20):
        place_b = _transform(rng)
        centre = np.asarray(place_b.getTranslation()) + rng.uniform(-0.35, 0.35, 3)
        e = rng.normal(size=3)

        def value(c: np.ndarray, first: bool, place_b: coal.Transform3s = place_b) -> float:
            place_a = coal.Transform3s(np.eye(3), c)
            pair = (ball, place_a, shape, place_b) if first else (shape, place_b, ball, place_a)
            found = sphere_distance(*pair)
            assert found is not None
            return found.min_distance

        for first in (True, False):
            found = sphere_distance(
                *(
                    (ball, coal.Transform3s(np.eye(3), centre), shape, place_b)
                    if first
                    else (shape, place_b, ball, coal.Transform3s(np.eye(3), centre))
                )
            )
            assert found is not None
            slope = (value(centre + h * e, first) - value(centre - h * e, first)) / (2 * h)
            moved = -1.0 if first else 1.0  # the sphere is the first shape or the second
            assert slope == pytest.approx(moved * float(found.normal @ e), abs=1e-6)


def test_a_sphere_deep_in_a_cylinder_leaves_through_the_nearer_cap():
    """The ETS-VII case: a 0.06 m sphere centred 0.1568 m up a cylinder of radius 0.06 m and
    half-length 0.175 m, 0.004 m off its axis. Out through the cap is 0.175 - 0.1568 + 0.06
    m, shorter than out through the side (0.06 - 0.004 + 0.06 m): the checked distance is
    minus the first, within what the bounding spheres allow."""
    cylinder, ball = coal.Cylinder(0.06, 0.35), coal.Sphere(0.06)
    offset = np.array([0.0033971, -0.0019779, 0.1567675])
    place_a, place_b = coal.Transform3s(), coal.Transform3s(np.eye(3), offset)
    cap = 0.175 - offset[2] + 0.06
    gap, reach = float(np.linalg.norm(offset)), math.hypot(0.06, 0.175) + 0.06
    answer = checked_distance(cylinder, place_a, ball, place_b, (gap - reach, gap + reach), "c/s")
    assert answer.value == pytest.approx(-cap, abs=1e-9)
    assert answer.value >= gap - reach
    assert sphere_distance(cylinder, place_a, coal.Box(0.1, 0.1, 0.1), place_b) is None


def _cylinder_arm() -> str:
    """The sphere arm of test_collision with an upright cylinder on its spacecraft."""
    from test_collision import SPHERE_ARM

    box = '<collision><geometry><box size="1.0 1.0 1.0"/></geometry></collision>'
    cylinder = (
        '<collision><origin xyz="2.12 0.005 0.15"/>'
        '<geometry><cylinder radius="0.2" length="0.5"/></geometry></collision>'
    )
    assert box in SPHERE_ARM
    return SPHERE_ARM.replace(box, box + cylinder)


def test_a_sphere_in_a_cylinder_is_measured_in_closed_form_by_the_collision_model(tmp_path):
    """The arm's 0.1 m ball (centre at x = 0.5 + cos q1 + 0.6 cos(q1 + q2)) inside a 0.2 m,
    0.5 m long upright cylinder on the spacecraft: its way out through the top cap (hand
    computed below) is shorter than through the side, and the model's distance, in a batch
    or alone, is that one; its gradient is the central differences' of the distance."""
    import freefloat as ff
    from freefloat.robot.collision import CollisionModel

    path = tmp_path / "cylinder_arm.urdf"
    path.write_text(_cylinder_arm())
    model = CollisionModel(ff.load_robot(path))
    k = next(i for i, name in enumerate(model.names) if "base_1" in name and "l2" in name)
    for q1 in (0.0, 0.01, -0.02):
        centre = np.array([0.5 + math.cos(q1) + 0.6 * math.cos(q1), 1.6 * math.sin(q1), 0.0])
        rel = centre - np.array([2.12, 0.005, 0.15])
        side, cap = 0.2 - math.hypot(rel[0], rel[1]), 0.25 - abs(rel[2])
        assert cap < side  # out through the cap
        q = np.array([q1, 0.0])
        assert model.distances(q).values[k] == pytest.approx(-cap - 0.1, abs=1e-12)
        batch = model.closest_many(np.repeat(q[None], 20, axis=0), gradients=True)
        assert batch.pairs[0] == k and batch.values[0] == pytest.approx(-cap - 0.1, abs=1e-12)
        h = 1e-6
        slopes = [
            (model.distances(q + h * e).values[k] - model.distances(q - h * e).values[k]) / (2 * h)
            for e in np.eye(2)
        ]
        assert batch.gradients[0] == pytest.approx(slopes, abs=1e-6)


@pytest.mark.parametrize("other", sorted(SHAPES))
def test_pinocchio_placements_give_what_coal_transforms_give(other):
    """The collision model passes Pinocchio's placements (``oMg``) without making coal's
    transforms of them: the answer is the same, to the bit, and in the other order the same
    distance with the normal reversed (to rounding for two spheres: each is then measured
    from the other's frame)."""
    import pinocchio as pin

    rng = np.random.default_rng(11)
    sphere, shape = SHAPES["sphere"](), SHAPES[other]()
    for _ in range(50):
        place_a, place_b = _transform(rng), _transform(rng)
        pin_a, pin_b = (
            pin.SE3(np.asarray(p.getRotation()), np.asarray(p.getTranslation()))
            for p in (place_a, place_b)
        )
        by_coal = sphere_distance(sphere, place_a, shape, place_b)
        by_pin = sphere_distance(sphere, pin_a, shape, pin_b)
        swapped = sphere_distance(shape, pin_b, sphere, pin_a)
        assert by_coal is not None and by_pin is not None and swapped is not None
        assert by_pin.min_distance == by_coal.min_distance
        assert np.array_equal(by_pin.normal, by_coal.normal)
        for mine, theirs in zip(by_pin.points, by_coal.points, strict=True):
            assert np.array_equal(mine, theirs)
        assert swapped.min_distance == pytest.approx(by_pin.min_distance, abs=1e-15)
        assert np.allclose(swapped.normal, -by_pin.normal, atol=1e-15)
