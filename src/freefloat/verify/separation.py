"""Lower bounds of a pair's distance from a direction that separates it, on the original geometry.

For any unit direction ``n``, two bodies lie at least as far apart as they do along ``n``:

    distance(A, B)  >=  min over B of n.x  -  max over A of n.x,

a plane normal to ``n`` runs between them when that is positive. Each maximum (the body's
support) is taken over **every vertex of its mesh** (a linear function's extremes over a
triangle lie at its corners), and in closed form for a box, sphere, capsule or cylinder: the
bound rests on the verification's own geometry and on nothing a solver computed. The direction
is only *proposed*: by coal's GJK between the two bodies' convex hulls (a primitive is its own
hull). For convex bodies it is the direction of their distance and the bound is that distance;
for others it is the hulls' distance, at most the meshes'. A poor proposal (a wrong hull, a
GJK that stopped early) makes the bound looser, never larger than the distance; rounding in
the supports is about 1e-16 m per metre of body size.

The certificate (:mod:`freefloat.verify.certificate`) takes these bounds at the ends of the
intervals it refines, where they cost tens of microseconds against a mesh-to-mesh query's
hundreds, and measures the exact distance only where the bound leaves an interval open.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import coal
import numpy as np

from ..errors import ModelError

__all__ = ["Separation"]

#: A body's support: the largest n.x over the body (m), for a unit n in its own frame.
Support = Callable[[np.ndarray], float]


class Separation:
    """Separating-direction lower bounds of pair distances (see the module's text).

    Args:
        shapes: every geometry object's coal shape, by object index.
        vertices: each mesh object's vertices in its own frame (V, 3) (m), by object index.
        hulls: for each mesh object, a function giving its convex hull as a coal shape (built
            when first needed; it only proposes directions).
    """

    def __init__(
        self,
        shapes: Sequence[coal.CollisionGeometry],
        vertices: dict[int, np.ndarray],
        hulls: dict[int, Callable[[], coal.CollisionGeometry]],
    ) -> None:
        self._shapes = list(shapes)
        self._vertices = vertices
        self._make_hull = hulls
        self._hulls: dict[int, coal.CollisionGeometry | None] = {}
        self._supports: dict[int, Support | None] = {}
        self._request = coal.DistanceRequest()  # GJK's default guess, every query
        self._request.enable_signed_distance = False

    def bound(
        self,
        a: int,
        b: int,
        placement_a: np.ndarray,
        placement_b: np.ndarray,
        transforms: tuple[coal.Transform3s, coal.Transform3s],
    ) -> float:
        """A lower bound (m) of the distance between objects ``a`` and ``b``; -inf if none.

        ``placement_a``, ``placement_b``: (4, 4) poses of the objects in one frame;
        ``transforms``: the same as coal takes them. -inf when the hulls touch (no direction
        separates them), coal's GJK fails, or a body has no support here.
        """
        n = self.direction(a, b, transforms)
        if n is None:
            return -math.inf
        return self.along(a, b, placement_a, placement_b, n)

    def direction(
        self, a: int, b: int, transforms: tuple[coal.Transform3s, coal.Transform3s]
    ) -> np.ndarray | None:
        """The unit direction (from ``a`` to ``b``) GJK proposes between their hulls, or None.

        None when the hulls touch, coal's GJK fails, or a body has no hull or support here.
        """
        hull_a, hull_b = self._hull(a), self._hull(b)
        if hull_a is None or hull_b is None or None in (self._support(a), self._support(b)):
            return None
        result = coal.DistanceResult()
        try:
            gap = coal.distance(hull_a, transforms[0], hull_b, transforms[1], self._request, result)
        except (RuntimeError, ValueError):  # no direction: the exact query decides
            return None
        if not gap > 0.0:
            return None
        direction = result.getNearestPoint2() - result.getNearestPoint1()
        length = math.sqrt(float(direction @ direction))
        if not length > 0.0 or not math.isfinite(length):
            return None
        return np.asarray(direction / length, dtype=float)

    def along(
        self, a: int, b: int, placement_a: np.ndarray, placement_b: np.ndarray, n: np.ndarray
    ) -> float:
        """``min over b of n.x - max over a of n.x`` (m) for a unit ``n``; -inf if not > 0."""
        support_a, support_b = self._support(a), self._support(b)
        if support_a is None or support_b is None:
            return -math.inf
        rotation_a, rotation_b = placement_a[:3, :3], placement_b[:3, :3]
        top_a = float(n @ placement_a[:3, 3]) + support_a(rotation_a.T @ n)
        bottom_b = float(n @ placement_b[:3, 3]) - support_b(rotation_b.T @ -n)
        value = bottom_b - top_a
        return value if value > 0.0 else -math.inf

    def points(self, i: int) -> tuple[np.ndarray, float] | None:
        """Object ``i`` as points and a radius: within ``radius`` of their hull (own frame, m).

        Every vertex of a mesh or a box (radius 0), a sphere's centre, a capsule's two ends;
        None for a cylinder and shapes not known (their rims are no finite set of points).
        A linear function's extremes over the body lie at these points, offset by the radius.
        """
        if i in self._vertices:
            return self._vertices[i], 0.0
        shape = self._shapes[i]
        if isinstance(shape, coal.Box):
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            return corners * np.asarray(shape.halfSide, dtype=float), 0.0
        if isinstance(shape, coal.Sphere):
            return np.zeros((1, 3)), float(shape.radius)
        if isinstance(shape, coal.Capsule):
            ends = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]) * float(shape.halfLength)
            return ends, float(shape.radius)
        return None

    def _hull(self, i: int) -> coal.CollisionGeometry | None:
        """Object ``i``'s convex hull for GJK: a primitive itself, a mesh's hull (or None)."""
        if i not in self._hulls:
            if i in self._make_hull:
                try:
                    self._hulls[i] = self._make_hull[i]()
                except ModelError:  # no hull (a flat mesh): no direction from it
                    self._hulls[i] = None
            else:
                shape = self._shapes[i]
                known = isinstance(shape, (coal.Box, coal.Sphere, coal.Capsule, coal.Cylinder))
                self._hulls[i] = shape if known else None
        return self._hulls[i]

    def _support(self, i: int) -> Support | None:
        """Object ``i``'s support function (its own frame), or None for a shape not known."""
        if i not in self._supports:
            self._supports[i] = _support_of(self._shapes[i], self._vertices.get(i))
        return self._supports[i]


def _support_of(shape: coal.CollisionGeometry, vertices: np.ndarray | None) -> Support | None:
    """The support function of a mesh (its vertices) or a primitive (closed form)."""
    if vertices is not None:
        return lambda n: float(np.max(vertices @ n))
    if isinstance(shape, coal.Box):
        sides = np.asarray(shape.halfSide, dtype=float)
        return lambda n: float(np.abs(n) @ sides)
    if isinstance(shape, coal.Sphere):
        radius = float(shape.radius)
        return lambda n: radius * math.sqrt(float(n @ n))
    if isinstance(shape, coal.Capsule):
        radius, axial = float(shape.radius), float(shape.halfLength)
        return lambda n: abs(float(n[2])) * axial + radius * math.sqrt(float(n @ n))
    if isinstance(shape, coal.Cylinder):
        radius, axial = float(shape.radius), float(shape.halfLength)
        return lambda n: abs(float(n[2])) * axial + radius * math.hypot(float(n[0]), float(n[1]))
    return None
