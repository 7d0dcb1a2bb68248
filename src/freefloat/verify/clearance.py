"""Clearance verified on the URDF's original geometry, certified between samples.

The solvers keep clearance on true convex hulls (:mod:`freefloat.robot.collision`). This check
shares none of their shapes: it takes the URDF's collision elements as parsed
(:func:`~freefloat.robot.geometry.load_shared_geometry`) and measures the **original**
geometry, meshes as bounding-volume hierarchies of their own triangles and primitives as
themselves (coal). Only the list of checked pairs is common, since it defines what is checked.

**Continuous time.** Every checked body moves no faster than a bound taken from the exact
joint-rate extremes of the polynomials on each interval (the real roots of the joint
accelerations) and the body's reach from each joint axis (link offsets plus the body's
bounding sphere, independent of the configuration). The distance of a pair is then Lipschitz
on the interval with constant ``L``: the sum of its two bodies' bounds over the joints that do
not move both (a joint that moves both moves them as one rigid whole), and

    min over [t0, t1] of d(t)  >=  (d(t0) + d(t1)) / 2 - L (t1 - t0) / 2.

Intervals where that bound lies more than :data:`ACCURACY` (or :data:`SLACK_FRACTION` of the
slack above the margin, if larger) below the smallest measured clearance are halved (a counted
budget, :data:`MAX_BISECTIONS`), so the reported lower bound holds for every instant and, once
refined, lies that close to the measured minimum: within 0.1 mm near the margin. Pairs whose
bounding spheres are far apart are bounded by the spheres alone (a valid lower bound) and never
queried; the intervals those leave open are bounded again from each mesh's leaf spheres, whose
gaps and own speed bounds (a leaf near a joint's axis moves slowly) often settle them without
a query or with fewer halvings (:mod:`freefloat.verify.sphere_tree`,
:mod:`freefloat.verify.certificate`).

**Penetration** is reported as such, with a depth: coal's signed distance for a mesh against a
primitive, the deepest triangle contact for two meshes (whose distance query stops at 0), and a
body found inside a closed mesh at the start (winding number) counts its surface distance as
depth. A body cannot enter a mesh later without crossing its surface, which the certificate
would see.

**Agreement with the solver.** At the instant of the smallest clearance the solver's hull
distances are compared pair by pair (the pairs measured there, and each other body's nearest
pair): a hull may never report more clearance than its mesh (:data:`HULL_TOLERANCE`), nor
less than the mesh minus the hulls' slack (for each hull face, every point lies within the
longest edge over sqrt(3) of a mesh vertex).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from ..robot.collision import Obstacle, checked_distance
from ..robot.geometry import add_obstacles, checked_pairs, load_shared_geometry
from ..robot.meshes import object_triangles, true_hull
from ..robot.model import Robot
from .levers import Levers
from .motion import reach_coefficients
from .separation import Separation
from .sphere_tree import LeafSpheres

__all__ = [
    "ACCURACY",
    "CHECK_TOLERANCE",
    "HULL_TOLERANCE",
    "MAX_BISECTIONS",
    "SLACK_FRACTION",
    "ClearanceCertificate",
    "MeshClearance",
    "Placed",
]

#: Instants of the first pass (uniform in time).
FIRST_INSTANTS = 51
#: How close (m) the certified lower bound is brought to the smallest measured clearance...
ACCURACY = 1e-4
#: ... or this fraction of that clearance's slack above the margin, whichever is larger.
SLACK_FRACTION = 0.25
#: Most interval halvings of one certificate (a count, so the verdict is reproducible).
MAX_BISECTIONS = 20000
#: How far (m) the certified lower bound may lie below the margin and the path still pass
#: the ``clearance`` check; the certificate refines towards it near the margin
#: (:func:`~freefloat.verify.certificate.certify`).
CHECK_TOLERANCE = 1e-6
#: A hull may report at most this much more clearance than its mesh (m): GJK's tolerance.
HULL_TOLERANCE = 1e-6


@dataclass(frozen=True)
class ClearanceCertificate:
    """The clearance of a path on the original geometry, for every instant.

    Attributes:
        margin: required clearance (m).
        lower_bound: certified smallest clearance over the whole path (m).
        measured: smallest clearance measured at an instant (m); >= ``lower_bound``.
        time: when ``measured`` occurs (s).
        pair: the pair that has it (``"a / b"``).
        kind: how that pair was measured (``"mesh / sphere"``...).
        penetration: whether some pair overlaps (then ``measured`` is minus its depth).
        instants: instants measured; ``bisections``: intervals halved.
        certified: whether ``lower_bound`` clears the margin within :data:`CHECK_TOLERANCE`
            (what the ``clearance`` check allows) on every interval.
        exhausted: whether the halving budget ran out before the bound came within
            :data:`ACCURACY` of ``measured`` (the bound still holds; it is only looser).
        hull_excess: how far the solver's hull figures stray outside what the meshes allow
            (m; negative when they agree, -inf when not compared).
        hull_detail: the pair and instant of ``hull_excess``.
    """

    margin: float
    lower_bound: float
    measured: float
    time: float
    pair: str
    kind: str
    penetration: bool
    instants: int
    bisections: int
    certified: bool
    exhausted: bool = False
    hull_excess: float = -math.inf
    hull_detail: str = ""

    @property
    def detail(self) -> str:
        """One line for the check's detail and the summary."""
        if not self.pair:  # a model with no pair: nothing to keep apart
            return f"no pairs to check: clear at every instant; margin {self.margin:g} m"
        what = "penetration" if self.penetration else "min clearance"
        # a depth is not Lipschitz in the motion (coal's mesh depth): no bound is claimed then
        bound = (
            "" if self.penetration else f"certified >= {self.lower_bound:.6g} m at every instant "
        )
        # the figure is the smallest at the instants measured (not refined between them: the
        # bound is what the check judges)
        text = (
            f"{what} {self.measured:.6g} m ({self.pair}, {self.kind}) at t = {self.time:.4g} s, "
            f"the smallest of the {self.instants} instants measured; margin {self.margin:g} m; "
            f"{bound}({self.bisections} halvings)"
        )
        if not self.certified:
            text += "; NOT certified between samples"
        if self.exhausted:
            text += f"; halving budget ({MAX_BISECTIONS}) spent"
        return text


class MeshClearance:
    """Distances of the checked pairs on the URDF's original collision geometry.

    Args:
        robot: the robot.
        srdf: SRDF whose disabled pairs are not checked.
        obstacles: keep-out objects fixed to the spacecraft.
    """

    def __init__(
        self, robot: Robot, srdf: str | Path | None = None, obstacles: Sequence[Obstacle] = ()
    ) -> None:
        self.robot = robot
        shared = load_shared_geometry(robot)
        geometry, keys = shared.model, shared.keys  # its meshes only read
        add_obstacles(robot, geometry, obstacles)
        self.pairs = checked_pairs(robot, geometry, srdf)
        self.geometry = geometry
        objects = list(geometry.geometryObjects)
        self.shapes = [obj.geometry for obj in objects]
        self.names = [f"{objects[a].name} / {objects[b].name}" for a, b in self.pairs]
        self.meshes = {
            i: object_triangles(objects[i], keys.get(i))
            for i, s in enumerate(self.shapes)
            if _is_mesh(s)
        }
        #: Lower bounds from separating directions, on these vertices (hulls only propose),
        #: taken for the pairs of two meshes: their exact query walks two triangle
        #: hierarchies (100 to 400 us, against 15 to 40 us with a primitive, about 20 us for
        #: a separation bound).
        self.separable = frozenset(
            k for k, (a, b) in enumerate(self.pairs) if a in self.meshes and b in self.meshes
        )
        self.separation = Separation(
            self.shapes,
            {i: vertices for i, (vertices, _) in self.meshes.items()},
            {i: partial(true_hull, objects[i], keys.get(i)) for i in self.meshes},
        )
        self.centres, self.radii = _bounding_spheres(self.shapes, self.meshes)
        #: Leaf spheres of every body: tighter lower bounds than the single spheres.
        boxes = {
            i: np.asarray(s.halfSide, float)
            for i, s in enumerate(self.shapes)
            if isinstance(s, coal.Box)
        }
        self.leaves = LeafSpheres(
            self.centres, self.radii, self.meshes, np.array(self.pairs), boxes
        )
        leaves, count = self.leaves, len(self.centres)
        reach = reach_coefficients(  # the single spheres', then the leaves' (one pass)
            robot,
            geometry,
            np.concatenate([self.centres, leaves.local]),
            np.concatenate([self.radii, leaves.radii]),
            np.concatenate([np.arange(count), leaves.owner]),
        )
        leaves.set_reach(reach[:, count:])
        reach = reach[:, :count]
        #: Lever arms of the single spheres about the joints' axes.
        self.levers = Levers(robot, geometry, reach, self.radii)
        pairs = np.array(self.pairs, dtype=int).reshape(-1, 2)
        #: First and second geometry index of every pair.
        self.first, self.second = pairs[:, 0], pairs[:, 1]
        # A joint that moves both bodies of a pair moves them as one rigid whole: it does not
        # change their distance. Only the others count in the pair's speed bound.
        ra, rb = reach[:, self.first], reach[:, self.second]
        both = (ra > 0.0) & (rb > 0.0)
        #: (N, P): how fast pair p's distance can change per unit rate of joint j (m per rad).
        self.pair_reach = np.where(both, 0.0, ra + rb)
        #: (P, 2) each pair's bodies; (P, N) 1 for the joints that count in its speed, else 0.
        self.pair_bodies = pairs
        self.free = np.ascontiguousarray(1.0 - both.T)
        self._data = robot.model.createData()
        self._gdata = pin.GeometryData(geometry)
        self._neutral = pin.neutral(robot.model)
        plain = all(j.kind != "continuous" for j in robot.joints)
        self._slots = np.array([j.idx_q for j in robot.joints]) if plain else None
        self.kinds = [f"{_kind(self.shapes[a])} / {_kind(self.shapes[b])}" for a, b in self.pairs]

    def placements(self, joints: np.ndarray) -> np.ndarray:
        """(G, 4, 4) pose of every geometry object in the spacecraft frame at ``joints``."""
        model = self.robot.model
        pin.forwardKinematics(model, self._data, self._configuration(joints))
        pin.updateGeometryPlacements(model, self._data, self.geometry, self._gdata)
        return np.array([m.homogeneous for m in self._gdata.oMg]).reshape(-1, 4, 4)

    def _configuration(self, joints: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration of joint values (rad or m), the spacecraft at the origin."""
        if self._slots is None:
            return self.robot.configuration(joints)
        q = self._neutral.copy()  # no continuous joint: the values themselves, written in
        q[self._slots] = joints
        return q

    def frames(self, joints: np.ndarray) -> np.ndarray:
        """(N, 4, 4) the arm joints' frames in the spacecraft frame at ``joints``."""
        model = self.robot.model
        pin.forwardKinematics(model, self._data, self._configuration(joints))
        oMi = self._data.oMi
        return np.array([oMi[j].homogeneous for j in self.levers.joints])

    def sphere_bounds(self, placements: np.ndarray) -> np.ndarray:
        """(P,) lower bounds of every pair's distance from bounding spheres (m).

        ``placements``: (G, 4, 4); or (K, G, 4, 4) for K instants at once, giving (K, P).
        """
        centres = _centres(placements, self.centres)
        gap = np.linalg.norm(centres[..., self.first, :] - centres[..., self.second, :], axis=-1)
        return gap - self.radii[self.first] - self.radii[self.second]

    def exact(self, placements: np.ndarray, k: int) -> float:
        """Signed distance of pair ``k`` (m): negative is the depth of an overlap.

        Two meshes that touch or cross report the deepest of their triangle contacts.
        """
        return self.exact_placed(Placed(self, placements), k)

    def exact_placed(self, placed: Placed, k: int) -> float:
        """:meth:`exact` at one instant's :class:`Placed` (its coal transforms kept)."""
        a, b = self.pairs[k]
        ta, tb = placed.transform(a), placed.transform(b)
        gap = math.dist(placed.centres[a], placed.centres[b])
        spheres = (gap - self.radii[a] - self.radii[b], gap + self.radii[a] + self.radii[b])
        value = checked_distance(
            self.shapes[a], ta, self.shapes[b], tb, spheres, self.names[k]
        ).value
        if value <= 0.0 and a in self.meshes and b in self.meshes:
            request = coal.CollisionRequest()
            request.enable_contact = True
            request.num_max_contacts = 1000
            collision = coal.CollisionResult()
            coal.collide(self.shapes[a], ta, self.shapes[b], tb, request, collision)
            depths = [abs(c.penetration_depth) for c in collision.getContacts()]
            value = -max(depths, default=0.0)
        return value

    def contained(self, placements: np.ndarray, k: int) -> bool:
        """Whether one body of pair ``k`` lies inside the other's closed mesh (winding number)."""
        a, b = self.pairs[k]
        for outer, inner in ((a, b), (b, a)):
            if outer not in self.meshes:
                continue
            vertices, triangles = self.meshes[outer]
            own = self.meshes[inner][0][0] if inner in self.meshes else self.centres[inner]
            point = placements[inner, :3, :3] @ own + placements[inner, :3, 3]
            local = placements[outer, :3, :3].T @ (point - placements[outer, :3, 3])
            if abs(_winding_number(vertices, triangles, local)) > 0.5:
                return True
        return False


class Placed:
    """One instant of a :class:`MeshClearance`, for its exact queries.

    Its placements, bounding-sphere centres (m, spacecraft frame) and each object's coal
    transform, the latter built when first asked for.

    Args:
        mesh: the model.
        placements: (G, 4, 4) pose of every geometry object (:meth:`MeshClearance.placements`).
    """

    def __init__(self, mesh: MeshClearance, placements: np.ndarray) -> None:
        self.placements = placements
        self.centres = _centres(placements, mesh.centres).tolist()
        self._transforms: dict[int, coal.Transform3s] = {}

    def transform(self, i: int) -> coal.Transform3s:
        """Object ``i``'s pose as coal takes it."""
        if i not in self._transforms:
            pose = self.placements[i]
            self._transforms[i] = coal.Transform3s(pose[:3, :3], pose[:3, 3])
        return self._transforms[i]


def _centres(placements: np.ndarray, local: np.ndarray) -> np.ndarray:
    """(..., G, 3) points given in each object's frame, in the spacecraft frame (m).

    ``placements``: (..., G, 4, 4) poses of the G objects (one set, or one per instant).
    """
    return np.einsum("...gij,gj->...gi", placements[..., :3, :3], local) + placements[..., :3, 3]


def _is_mesh(shape: coal.CollisionGeometry) -> bool:
    return isinstance(shape, coal.BVHModelBase)


def _kind(shape: coal.CollisionGeometry) -> str:
    return "mesh" if _is_mesh(shape) else type(shape).__name__.lower()


def _bounding_spheres(
    shapes: list[coal.CollisionGeometry], meshes: dict[int, tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """Centre (in each shape's frame) and radius (m) of a sphere around each shape.

    Meshes: the box of their vertices' centre and the farthest vertex (numpy); primitives:
    coal's local box.
    """
    centres, radii = [], []
    for i, shape in enumerate(shapes):
        if i in meshes:
            centre, radius = _mesh_sphere(meshes[i][0])
        else:
            shape.computeLocalAABB()
            centre, radius = np.asarray(shape.aabb_center, float), float(shape.aabb_radius)
        centres.append(centre)
        radii.append(radius)
    return np.array(centres, dtype=float).reshape(-1, 3), np.array(radii, dtype=float)


def _mesh_sphere(vertices: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre of a mesh's vertex box and its farthest vertex's distance (m).

    Kept per vertex array when the array is shared and never written
    (:func:`~freefloat.robot.meshes.object_triangles`'s).
    """
    kept = _SPHERES.get(id(vertices))
    if kept is not None and kept[0] is vertices:
        return kept[1]
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    sphere = centre, float(np.linalg.norm(vertices - centre, axis=1).max())
    if not vertices.flags.writeable:
        _SPHERES[id(vertices)] = (vertices, sphere)
    return sphere


#: Bounding sphere per shared mesh vertex array (see _mesh_sphere), the array kept alive.
_SPHERES: dict[int, tuple[np.ndarray, tuple[np.ndarray, float]]] = {}


def _winding_number(vertices: np.ndarray, triangles: np.ndarray, point: np.ndarray) -> float:
    """Generalised winding number of a triangle mesh about ``point`` (1 inside, 0 outside)."""
    a, b, c = (vertices[triangles[:, k]] - point for k in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    numerator = np.einsum("ij,ij->i", a, np.cross(b, c))
    denominator = (
        la * lb * lc
        + np.einsum("ij,ij->i", a, b) * lc
        + np.einsum("ij,ij->i", a, c) * lb
        + np.einsum("ij,ij->i", b, c) * la
    )
    return float(np.arctan2(numerator, denominator).sum() / (2.0 * math.pi))
