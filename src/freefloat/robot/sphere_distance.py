"""Exact signed distance of a sphere and a sphere, box, cylinder or capsule, in closed form.

coal's specialised sphere-cylinder routine answers a deep penetration with the radial way
out even when the way out through a cap is shorter (a sphere centred 0.157 m up a 0.175 m
half-length cylinder of radius 0.06 m: -0.116 m where the true depth gives -0.078 m), an
answer :func:`~freefloat.robot.distance_query.checked_distance` sees is impossible. For a
sphere against such a primitive the signed distance is that of the sphere's centre to the
other shape less the sphere's radius, and the centre's signed distance has a closed form:
outside, the distance to the nearest point of the shape; inside, minus the distance to the
nearest point of its surface. :func:`sphere_distance` gives it with its witness points and
normal, as coal's result does: always for a sphere and a cylinder
(:func:`closed_form_first`), and for the other shapes where coal's answer is impossible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np

__all__ = ["SphereWitness", "closed_form_first", "sphere_distance"]


@dataclass(frozen=True)
class SphereWitness:
    """A signed distance with its witness points and normal, read as coal's result is read.

    Attributes:
        min_distance: signed distance (m), negative when the shapes overlap.
        normal: unit normal from the first shape to the second (world frame).
        points: the witness points on the first and on the second shape (world frame, m).
    """

    min_distance: float
    normal: np.ndarray
    points: tuple[np.ndarray, np.ndarray]

    def getNearestPoint1(self) -> np.ndarray:  # noqa: N802 - coal's name, read alike
        """The witness point on the first shape (world frame, m)."""
        return self.points[0]

    def getNearestPoint2(self) -> np.ndarray:  # noqa: N802 - coal's name, read alike
        """The witness point on the second shape (world frame, m)."""
        return self.points[1]


def closed_form_first(shape_a: coal.CollisionGeometry, shape_b: coal.CollisionGeometry) -> bool:
    """Whether the pair is measured in closed form rather than by coal: a sphere and a cylinder.

    coal's routine for them takes the radial way out of an overlap whatever the cap's: its
    depths are wrong (and jump where its way out changes) well inside what the bounding
    spheres allow, so no check could catch them.
    """
    kinds = {type(shape_a), type(shape_b)}
    return kinds == {coal.Sphere, coal.Cylinder}


def sphere_distance(
    shape_a: coal.CollisionGeometry,
    place_a: coal.Transform3s,
    shape_b: coal.CollisionGeometry,
    place_b: coal.Transform3s,
) -> SphereWitness | None:
    """The exact signed distance of a sphere and a sphere, box, cylinder or capsule (m).

    Either shape may be the sphere; None for any other pair of shapes.
    """
    if isinstance(shape_b, coal.Sphere) and not isinstance(shape_a, coal.Sphere):
        found = sphere_distance(shape_b, place_b, shape_a, place_a)
        if found is None:
            return None
        return SphereWitness(found.min_distance, -found.normal, found.points[::-1])
    if not isinstance(shape_a, coal.Sphere):
        return None
    rotation, origin = np.asarray(place_b.getRotation()), np.asarray(place_b.getTranslation())
    centre = rotation.T @ (np.asarray(place_a.getTranslation()) - origin)  # in b's frame
    surface = _nearest_surface(shape_b, centre)
    if surface is None:
        return None
    signed, point, outward = surface  # the centre's signed distance, b's point, its normal
    on_b = rotation @ point + origin
    normal = -(rotation @ outward)  # from the sphere (a) to b
    on_a = np.asarray(place_a.getTranslation()) + float(shape_a.radius) * normal
    return SphereWitness(signed - float(shape_a.radius), normal, (on_a, on_b))


def _nearest_surface(
    shape: coal.CollisionGeometry, p: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Signed distance (m) of the point ``p`` (the shape's frame) to the shape.

    With the shape's surface point nearest ``p`` and the outward unit normal there; None for
    a shape with no closed form here.
    """
    if isinstance(shape, coal.Sphere):
        radius = float(shape.radius)
        direction = _unit(p, np.array([0.0, 0.0, 1.0]))
        return float(np.linalg.norm(p)) - radius, radius * direction, direction
    if isinstance(shape, coal.Box):
        return _box(np.asarray(shape.halfSide, dtype=float), p)
    if isinstance(shape, coal.Capsule):
        radius, half = float(shape.radius), float(shape.halfLength)
        axis_point = np.array([0.0, 0.0, min(max(float(p[2]), -half), half)])
        direction = _unit(p - axis_point, np.array([1.0, 0.0, 0.0]))
        distance = float(np.linalg.norm(p - axis_point)) - radius
        return distance, axis_point + radius * direction, direction
    if isinstance(shape, coal.Cylinder):
        return _cylinder(float(shape.radius), float(shape.halfLength), p)
    return None


def _box(half: np.ndarray, p: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """:func:`_nearest_surface` of a box of half sides ``half`` (m), centred at the origin."""
    excess = np.abs(p) - half
    if np.any(excess > 0.0):  # outside: the nearest point of the box
        point = np.clip(p, -half, half)
        return float(np.linalg.norm(p - point)), point, _unit(p - point, np.zeros(3))
    k = int(np.argmax(excess))  # inside: out through the nearest face
    sign = 1.0 if p[k] >= 0.0 else -1.0
    point, normal = p.copy(), np.zeros(3)
    point[k], normal[k] = sign * half[k], sign
    return float(excess[k]), point, normal


def _cylinder(radius: float, half: float, p: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """:func:`_nearest_surface` of a cylinder (m) about z, centred at the origin."""
    rho = math.hypot(float(p[0]), float(p[1]))
    radial = _unit(np.array([p[0], p[1], 0.0]), np.array([1.0, 0.0, 0.0]))
    sign = 1.0 if p[2] >= 0.0 else -1.0
    side, cap = rho - radius, abs(float(p[2])) - half
    if side <= 0.0 and cap <= 0.0:  # inside: out through the side or a cap, the nearer
        if side >= cap:
            return side, np.array([radius * radial[0], radius * radial[1], p[2]]), radial
        return cap, np.array([p[0], p[1], sign * half]), np.array([0.0, 0.0, sign])
    point = np.array(
        [min(rho, radius) * radial[0], min(rho, radius) * radial[1], sign * min(abs(p[2]), half)]
    )
    return float(np.linalg.norm(p - point)), point, _unit(p - point, radial)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """``v`` made unit length; ``fallback`` when it has none (a point on the surface)."""
    norm = float(np.linalg.norm(v))
    return v / norm if norm > 0.0 else fallback
