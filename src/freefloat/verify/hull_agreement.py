"""The solver's hull distances against the original meshes at one instant (a cross-check).

A true hull contains its mesh, so a pair's hull distance is at most its mesh distance (within
:data:`~freefloat.verify.clearance.HULL_TOLERANCE`, GJK's) and at least the mesh distance
minus the two hulls' slack (:func:`~freefloat.verify.clearance.hull_slack`). The certificate
(:mod:`freefloat.verify.certificate`) asks this at the instant of the smallest clearance, for
the pairs it measured there (the closest ones, where a wrong hull would matter) and, for each
body none of those holds, the pair in which it lies nearest another body by its leaf spheres:
every hull is compared with its own mesh at least once without measuring every pair.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..robot.collision import CollisionModel
from .clearance import MeshClearance, hull_slack

__all__ = ["hull_agreement"]


def hull_agreement(
    mesh: MeshClearance,
    solver: CollisionModel,
    time: float,
    joints: np.ndarray,
    placements: np.ndarray,
    measured: set[int],
    distance: Callable[[int], float],
) -> tuple[float, str]:
    """How far the solver's hull distances stray outside what their meshes allow (m).

    Args:
        mesh: the original-geometry model.
        solver: the solvers' hull model.
        time: the instant (s), for the message.
        joints: the instant's joint values (rad or m).
        placements: (G, 4, 4) the instant's body poses (:meth:`MeshClearance.placements`).
        measured: the pairs whose mesh distance is known there.
        distance: pair -> its signed mesh distance there (m).

    Returns the worst excess over the bounds (negative or within ``HULL_TOLERANCE`` when
    every pair compared agrees) and where it occurs.
    """
    if solver.names != mesh.names:
        return math.inf, "the solver checks other pairs than the URDF states"
    slack = [hull_slack(solver, i) for i in range(len(mesh.shapes))]
    hull = solver.distances(joints).values
    worst, where = -math.inf, ""
    for k in compared(mesh, placements, measured):
        a, b = mesh.pairs[k]
        true = distance(k)
        farther = hull[k] - true
        nearer = true - hull[k] - slack[a] - slack[b] if true > 0.0 else -math.inf
        if max(farther, nearer) > worst:
            worst = max(farther, nearer)
            where = (
                f"{mesh.names[k]} at t = {time:.4g} s: hull {hull[k]:.6g} m, mesh {true:.6g} m, "
                f"hull slack {slack[a] + slack[b]:.3g} m"
            )
    return worst, where


def compared(mesh: MeshClearance, placements: np.ndarray, measured: set[int]) -> list[int]:
    """The pairs compared, in pair order: ``measured``, then each other body's nearest pair.

    A body no chosen pair holds gets the pair in which it lies nearest another body by its
    leaf spheres at ``placements`` (which covers that other body too).
    """
    count = len(mesh.pairs)
    if count == 0:
        return []
    chosen = set(measured)
    every = np.arange(count)
    bounds = mesh.leaves.bounds(placements[None], np.zeros(count, dtype=int), every)
    covered = {int(g) for k in chosen for g in mesh.pairs[k]}
    for body in range(len(mesh.shapes)):
        mine = np.flatnonzero((mesh.first == body) | (mesh.second == body))
        if body in covered or len(mine) == 0:
            continue
        nearest = int(mine[np.argmin(bounds[mine])])
        chosen.add(nearest)
        covered.update(int(g) for g in mesh.pairs[nearest])
    return sorted(chosen)
