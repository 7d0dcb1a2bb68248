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
import pinocchio as pin

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
    place_a: coal.Transform3s | pin.SE3,
    shape_b: coal.CollisionGeometry,
    place_b: coal.Transform3s | pin.SE3,
) -> SphereWitness | None:
    """The exact signed distance of a sphere and a sphere, box, cylinder or capsule (m).

    Either shape may be the sphere; None for any other pair of shapes. The placements are
    coal's transforms or Pinocchio's (a geometry object's ``oMg``, read without a copy into
    coal's type). The arithmetic is on Python floats, three components at a time: for one
    pair, numpy's per-call cost is most of the work.
    """
    if isinstance(shape_b, coal.Sphere) and not isinstance(shape_a, coal.Sphere):
        found = sphere_distance(shape_b, place_b, shape_a, place_a)
        if found is None:
            return None
        return SphereWitness(found.min_distance, -found.normal, found.points[::-1])
    if not isinstance(shape_a, coal.Sphere):
        return None
    rotation, origin = _pose(place_b)
    at = _pose(place_a, rotation=False)[1]
    d = [at[0] - origin[0], at[1] - origin[1], at[2] - origin[2]]
    centre = [
        rotation[0][i] * d[0] + rotation[1][i] * d[1] + rotation[2][i] * d[2] for i in range(3)
    ]
    if isinstance(shape_b, coal.Cylinder):
        surface = _cylinder(float(shape_b.radius), float(shape_b.halfLength), *centre)
    else:
        nearest = _nearest_surface(shape_b, np.array(centre))
        if nearest is None:
            return None
        surface = (nearest[0], nearest[1].tolist(), nearest[2].tolist())
    signed, point, outward = surface  # the centre's signed distance, b's point, its normal
    (x, y, z), (u, v, w) = point, outward
    on_b = [r[0] * x + r[1] * y + r[2] * z + o for r, o in zip(rotation, origin, strict=True)]
    normal = [-(r[0] * u + r[1] * v + r[2] * w) for r in rotation]  # from a to b
    radius = float(shape_a.radius)
    on_a = [at[i] + radius * normal[i] for i in range(3)]
    return SphereWitness(signed - radius, np.array(normal), (np.array(on_a), np.array(on_b)))


def _pose(
    place: coal.Transform3s | pin.SE3, rotation: bool = True
) -> tuple[list[list[float]], list[float]]:
    """A placement's rotation (rows; empty unless ``rotation``) and translation (m), as floats."""
    if isinstance(place, pin.SE3):
        turn, shift = (place.rotation if rotation else None), place.translation
    else:
        turn, shift = (place.getRotation() if rotation else None), place.getTranslation()
    return ([] if turn is None else np.asarray(turn).tolist()), np.asarray(shift).tolist()


def _nearest_surface(
    shape: coal.CollisionGeometry, p: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Signed distance (m) of the point ``p`` (the shape's frame) to a sphere, box or capsule.

    With the shape's surface point nearest ``p`` and the outward unit normal there; None for
    any other shape (a cylinder: :func:`_cylinder`).
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
    return None  # a cylinder is measured by _cylinder, on floats


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


def _cylinder(
    radius: float, half: float, x: float, y: float, z: float
) -> tuple[float, list[float], list[float]]:
    """:func:`_nearest_surface` of a cylinder (m) about z, centred at the origin, at (x, y, z)."""
    rho = math.hypot(x, y)
    rx, ry = (x / rho, y / rho) if rho > 0.0 else (1.0, 0.0)  # the radial way out
    sign = 1.0 if z >= 0.0 else -1.0
    side, cap = rho - radius, abs(z) - half
    if side <= 0.0 and cap <= 0.0:  # inside: out through the side or a cap, the nearer
        if side >= cap:
            return side, [radius * rx, radius * ry, z], [rx, ry, 0.0]
        return cap, [x, y, sign * half], [0.0, 0.0, sign]
    near = min(rho, radius)
    point = [near * rx, near * ry, sign * min(abs(z), half)]
    dx, dy, dz = x - point[0], y - point[1], z - point[2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    if distance > 0.0:
        return distance, point, [dx / distance, dy / distance, dz / distance]
    return distance, point, [rx, ry, 0.0]  # on the surface


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """``v`` made unit length; ``fallback`` when it has none (a point on the surface)."""
    norm = float(np.linalg.norm(v))
    return v / norm if norm > 0.0 else fallback
