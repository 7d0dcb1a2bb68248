"""Sphere trees of the original geometry: cheap, conservative lower bounds of pair distances.

The clearance certificate (:mod:`freefloat.verify.certificate`) bounds every checked pair's
distance from below before it measures it exactly. One bounding sphere per body is loose for a
long link (an upper arm's sphere is as wide as the arm is long), so pairs of such links far
apart would still be measured at every instant. Here each mesh's triangles are split
:data:`LEAF_DEPTH` times (at the median of their centroids along the widest axis), and each
group gets the sphere around its own vertices (the centre of their box, the farthest vertex):
every triangle lies in its group's sphere, since a sphere is convex and holds its vertices.
For two bodies with leaf spheres ``(c_i, r_i)`` and ``(c_j, r_j)``

    d(A, B)  >=  min over i, j of  |c_i - c_j| - r_i - r_j,

a valid lower bound (m) from the URDF's own mesh vertices, nothing of the solvers' hulls.
Primitives, and a mesh without triangles, keep their single bounding sphere (that of
:class:`~freefloat.verify.clearance.MeshClearance`), but a box (a spacecraft body, often the
largest shape) facing another body's leaf sphere counts as itself: the distance from the
sphere's centre to the box (clamped in the box's frame) less the sphere's radius, which is
never below the bound of the box's own bounding sphere.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LEAF_DEPTH", "LeafSpheres", "leaf_spheres"]

#: Halvings of a mesh's triangles: 2 ** LEAF_DEPTH leaf spheres per mesh.
LEAF_DEPTH = 3


def leaf_spheres(
    vertices: np.ndarray, triangles: np.ndarray, depth: int = LEAF_DEPTH
) -> tuple[np.ndarray, np.ndarray]:
    """Centres (L, 3) and radii (L,) (m, mesh frame) of spheres that together hold every triangle.

    Args:
        vertices: (V, 3) mesh vertices (m).
        triangles: (F, 3) vertex indices of the triangles.
        depth: how many times the triangle groups are halved.
    """
    centroids = vertices[triangles].mean(axis=1)
    groups = [np.arange(len(triangles))]
    for _ in range(depth):
        halves = []
        for group in groups:
            if len(group) < 2:
                halves.append(group)
                continue
            points = centroids[group]
            axis = int(np.argmax(points.max(axis=0) - points.min(axis=0)))
            order = group[np.argsort(points[:, axis], kind="stable")]
            halves += [order[: len(order) // 2], order[len(order) // 2 :]]
        groups = halves
    centres, radii = [], []
    for group in groups:
        points = vertices[np.unique(triangles[group])]
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        centres.append(centre)
        radii.append(float(np.linalg.norm(points - centre, axis=1).max()))
    return np.array(centres), np.array(radii)


#: Leaf spheres per mesh, by the identity of its (shared, read-only) vertex array.
_LEAVES: dict[int, tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]] = {}


def _cached_leaves(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`leaf_spheres` of a mesh whose arrays are shared and never written (kept alive)."""
    if vertices.flags.writeable:
        return leaf_spheres(vertices, triangles)
    kept = _LEAVES.get(id(vertices))
    if kept is None or kept[0] is not vertices:
        kept = _LEAVES[id(vertices)] = (vertices, leaf_spheres(vertices, triangles))
    return kept[1]


class LeafSpheres:
    """Every body's leaf spheres, and the lower bound of a pair's distance at given placements.

    The leaf pairs' speed coefficients (:attr:`row_reach`) need the robot's kinematics: they are
    set by :meth:`set_reach` (:class:`~freefloat.verify.clearance.MeshClearance` does).

    Args:
        centres: (G, 3) each body's single bounding-sphere centre (its own frame, m).
        radii: (G,) their radii (m).
        meshes: per mesh body, its (vertices, triangles).
        pairs: (P, 2) the checked pairs' body indices.
        boxes: per box body, its half extents (m, along its own axes, centred on its origin).
    """

    def __init__(
        self,
        centres: np.ndarray,
        radii: np.ndarray,
        meshes: dict[int, tuple[np.ndarray, np.ndarray]],
        pairs: np.ndarray,
        boxes: dict[int, np.ndarray] | None = None,
    ) -> None:
        local: list[np.ndarray] = []
        size: list[np.ndarray] = []
        owner: list[int] = []
        first_leaf: list[int] = []
        for g in range(len(centres)):
            if g in meshes and len(meshes[g][1]):
                c, r = _cached_leaves(*meshes[g])
            else:
                c, r = centres[g][None, :], radii[g : g + 1]
            first_leaf.append(len(owner))
            local.append(c)
            size.append(r)
            owner += [g] * len(r)
        first_leaf.append(len(owner))
        #: (L, 3) leaf centres in their body's frame, (L,) radii, (L,) owning body.
        self.local = np.concatenate([np.zeros((0, 3)), *local])  # none: a robot without bodies
        self.radii = np.concatenate([np.zeros(0), *size])
        self.owner = np.array(owner, dtype=int)
        left: list[int] = []
        right: list[int] = []
        count: list[int] = []
        for a, b in np.asarray(pairs, dtype=int).reshape(-1, 2).tolist():
            la = range(first_leaf[a], first_leaf[a + 1])
            lb = list(range(first_leaf[b], first_leaf[b + 1]))
            for i in la:  # every leaf of a against every leaf of b, a's leaf the slower index
                left += [i] * len(lb)
                right += lb
            count.append(len(la) * len(lb))
        #: Every pair's leaf pairs, pair after pair: first and second leaf, and their count.
        self.left = np.array(left, dtype=int)
        self.right = np.array(right, dtype=int)
        self.count = np.array(count, dtype=int)
        self.start = np.concatenate([[0], np.cumsum(self.count)[:-1]]).astype(int)
        self.reach = self.radii[self.left] + self.radii[self.right]
        #: Half extents of every box body (zero rows for the others), and which leaves are boxes.
        boxes = boxes or {}
        self.half = np.zeros((len(centres), 3))
        for g, half in boxes.items():
            self.half[g] = half
        box_leaf = np.isin(self.owner, list(boxes))
        #: Leaf pairs one of whose bodies is a box and the other not: (row, box leaf, other leaf).
        self.box_rows = np.flatnonzero(box_leaf[self.left] != box_leaf[self.right])
        in_left = box_leaf[self.left[self.box_rows]]
        self.box_leaf = np.where(in_left, self.left[self.box_rows], self.right[self.box_rows])
        self.sphere_leaf = np.where(in_left, self.right[self.box_rows], self.left[self.box_rows])
        #: Per leaf pair, its index in the three arrays above, or -1.
        self.box_of_row = np.full(len(self.left), -1, dtype=int)
        self.box_of_row[self.box_rows] = np.arange(len(self.box_rows))
        #: Per pair, what :meth:`pair_gaps` needs of its leaf pairs, worked out when first asked.
        self._pair_parts: dict[int, tuple[np.ndarray, ...]] = {}

    def bounds(self, placements: np.ndarray, cells: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """Lower bounds (m) of pair ``pairs[c]``'s distance at placement set ``cells[c]``.

        Args:
            placements: (K, G, 4, 4) body poses at K instants (spacecraft frame).
            cells: (C,) index into the K instants for each bound asked for.
            pairs: (C,) the pair of each bound asked for.
        """
        if len(cells) == 0:
            return np.zeros(0)
        counts = self.count[pairs]
        ends = np.cumsum(counts)
        # every asked cell's leaf pairs, one run per cell
        offsets = np.arange(int(ends[-1])) - np.repeat(ends - counts, counts)
        rows = np.repeat(self.start[pairs], counts) + offsets
        gap = self.row_gaps(placements, np.repeat(cells, counts), rows)
        return np.minimum.reduceat(gap, ends - counts)

    def rows_of(self, pair: int) -> np.ndarray:
        """The leaf pairs (rows) of one pair."""
        return np.arange(self.start[pair], self.start[pair] + self.count[pair])

    def row_gaps(
        self, placements: np.ndarray, instants: np.ndarray, rows: np.ndarray
    ) -> np.ndarray:
        """(R,) lower bounds (m) of the distance between the two leaves of each leaf pair.

        Args:
            placements: (K, G, 4, 4) body poses at K instants (spacecraft frame).
            instants: (R,) index into the K instants for each row.
            rows: (R,) leaf pairs.
        """
        # every leaf's centre at the instants asked for, once
        used, which_instant = np.unique(instants, return_inverse=True)
        poses = placements[used]
        return self.gaps_at(self.centres_at(poses), poses, which_instant, rows)

    def centres_at(self, placements: np.ndarray) -> np.ndarray:
        """(K, L, 3) every leaf's centre (m, spacecraft frame) at K sets of body poses."""
        rotations = placements[:, :, :3, :3][:, self.owner]  # (K, L, 3, 3)
        return (
            np.einsum("kLij,Lj->kLi", rotations, self.local)
            + placements[:, :, :3, 3][:, self.owner]
        )

    def gaps_at(
        self, world: np.ndarray, placements: np.ndarray, instants: np.ndarray, rows: np.ndarray
    ) -> np.ndarray:
        """:meth:`row_gaps` from the leaves' centres already placed.

        Args:
            world: (K, L, 3) leaf centres at K instants (:meth:`centres_at`).
            placements: (K, G, 4, 4) body poses at the same instants.
            instants: (R,) index into the K instants for each row.
            rows: (R,) leaf pairs.
        """
        # rows of the (K L, 3) centres by one flat index each (numpy's 2-D gather is slower)
        flat, base = world.reshape(-1, 3), instants * world.shape[1]
        gap = _norms(
            np.take(flat, base + self.left[rows], axis=0)
            - np.take(flat, base + self.right[rows], axis=0)
        )
        gap -= self.reach[rows]
        # leaf pairs with a box: the sphere's centre to the box itself
        boxed = np.flatnonzero(self.box_of_row[rows] >= 0)
        if len(boxed):
            which = self.box_of_row[rows[boxed]]
            box = self.owner[self.box_leaf[which]]
            other = self.sphere_leaf[which]
            at = instants[boxed]  # flat gathers, as above
            pose = np.take(placements.reshape(-1, 4, 4), at * placements.shape[1] + box, axis=0)
            offset = np.take(flat, at * world.shape[1] + other, axis=0) - pose[:, :3, 3]
            local = np.einsum("bji,bj->bi", pose[:, :3, :3], offset)  # R^T (c - p)
            outside = np.maximum(np.abs(local) - self.half[box], 0.0)
            gap[boxed] = _norms(outside) - self.radii[other]
        return gap

    def pair_gaps(self, placements: np.ndarray, pair: int) -> np.ndarray:
        """:meth:`row_gaps` of one pair's leaf pairs at one instant (the same figures).

        Only that pair's leaves are placed. ``placements``: (G, 4, 4) body poses.
        """
        if pair not in self._pair_parts:
            rows = self.rows_of(pair)
            leaves, where = np.unique(
                np.concatenate([self.left[rows], self.right[rows]]), return_inverse=True
            )
            boxed = np.flatnonzero(self.box_of_row[rows] >= 0)
            which = self.box_of_row[rows[boxed]]
            other = np.searchsorted(leaves, self.sphere_leaf[which])
            self._pair_parts[pair] = (rows, leaves, where, boxed, which, other)
        rows, leaves, where, boxed, which, other = self._pair_parts[pair]
        poses = placements[None, self.owner[leaves]]  # (1, l, 4, 4)
        world = np.einsum("kLij,Lj->kLi", poses[..., :3, :3], self.local[leaves])[0]
        world += poses[0, :, :3, 3]
        half = len(rows)
        gap = _norms(world[where[:half]] - world[where[half:]])
        gap -= self.reach[rows]
        if len(boxed):
            box = self.owner[self.box_leaf[which]]
            pose = placements[box]  # (B, 4, 4)
            offset = world[other] - pose[:, :3, 3]
            local = np.einsum("bji,bj->bi", pose[:, :3, :3], offset)  # R^T (c - p)
            outside = np.maximum(np.abs(local) - self.half[box], 0.0)
            gap[boxed] = _norms(outside) - self.radii[self.sphere_leaf[which]]
        return gap

    def set_reach(self, leaf_reach: np.ndarray) -> None:
        """Take each leaf's reach from every joint, (N, L) (m per rad; 1 for prismatic joints).

        Sets :attr:`row_reach`, (N, R): how fast the distance between the two leaves of each
        leaf pair can change per unit rate of each joint; a joint that moves both leaves moves
        them as one rigid whole and does not count.
        """
        a, b = leaf_reach[:, self.left], leaf_reach[:, self.right]
        self.row_reach = np.where((a > 0.0) & (b > 0.0), 0.0, a + b)
        #: (R, N) the same, one leaf pair a row (contiguous: rows are gathered from it).
        self.row_reach_t = np.ascontiguousarray(self.row_reach.T)


def _norms(vectors: np.ndarray) -> np.ndarray:
    """(R,) Euclidean lengths of (R, 3) vectors: ``np.linalg.norm(vectors, axis=1)``'s figures.

    The same sums in the same order, ``(x^2 + y^2) + z^2``, without its reduction machinery.
    ``vectors`` is overwritten.
    """
    vectors *= vectors
    return np.sqrt(vectors[:, 0] + vectors[:, 1] + vectors[:, 2])
