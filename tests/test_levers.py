"""The certificate's speed bounds from lever arms against brute force.

Reach from each joint's axis (:func:`~freefloat.verify.motion.reach_coefficients`) against the
distance of every mesh vertex from Pinocchio's joint axes in random configurations; the
lever arms of leaf spheres over an interval (:class:`~freefloat.verify.levers.Levers`) against
the distance of every vertex they hold from Pinocchio's joint axes inside it; a pair's
lever-arm speed weights (:class:`~freefloat.verify.interval_levers.IntervalLevers`) against
the speeds of the mesh vertices and the rates of coal's distances, by finite differences along
the path; and the joints' axes from the objects' poses against Pinocchio's joint frames.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.collision import known_srdf
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import MeshClearance
from freefloat.verify.instants import Instants
from freefloat.verify.interval_levers import IntervalLevers
from freefloat.verify.levers import Levers
from freefloat.verify.motion import PolynomialMotion, reach_coefficients

from conftest import ROOT

SERVICERS = ["panda_servicer", "ur5_servicer"]


def _scenario(name: str) -> tuple[ff.Scenario, MeshClearance]:
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    return s, MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot), s.safety.obstacles)


def _motion(s: ff.Scenario) -> PolynomialMotion:
    """A quintic from the start to the goal, with a sine-like bump so that no joint rests."""
    start, goal, duration = np.asarray(s.start), np.asarray(s.goal), s.duration
    d = goal - start
    bump = np.linspace(0.3, -0.3, len(start))
    return PolynomialMotion.from_monomials(
        [
            [
                a,
                0,
                0,
                10 * x / duration**3 + 16 * b / duration**3,
                -15 * x / duration**4 - 32 * b / duration**4,
                6 * x / duration**5 + 16 * b / duration**5,
            ]
            for a, x, b in zip(start, d, bump, strict=True)
        ],
        duration,
    )


def _world_axes(s: ff.Scenario, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's joint origins and world axes (from the world Jacobian), (N, 3) each."""
    model, data = s.robot.model, s.robot.model.createData()
    q = s.robot.configuration(joints)
    pin.computeJointJacobians(model, data, q)
    origins, axes = [], []
    for j in s.robot.joints:
        origins.append(data.oMi[j.index].translation.copy())
        axes.append(pin.getJointJacobian(model, data, j.index, pin.WORLD)[3:, j.idx_v])
    return np.array(origins), np.array(axes)


def _vertices(mesh: MeshClearance, placements: np.ndarray, body: int) -> np.ndarray:
    """(V, 3) a mesh body's vertices in the spacecraft frame (m)."""
    vertices = mesh.meshes[body][0]
    return vertices @ placements[body, :3, :3].T + placements[body, :3, 3]


@pytest.mark.parametrize("name", SERVICERS)
def test_reach_from_the_axes_holds_every_vertex_in_any_configuration(name):
    """Every mesh vertex lies no farther from a joint's axis than its body's reach from it, and
    every vertex a leaf sphere holds no farther than the leaf's."""
    s, mesh = _scenario(name)
    leaves = mesh.leaves
    bodies = reach_coefficients(s.robot, mesh.geometry, mesh.centres, mesh.radii)
    own = reach_coefficients(s.robot, mesh.geometry, leaves.local, leaves.radii, leaves.owner)
    rng = np.random.default_rng(11)
    lower = np.array([j.lower for j in s.robot.joints])
    upper = np.array([j.upper for j in s.robot.joints])
    tight = 0.0
    for _ in range(12):
        joints = rng.uniform(lower, upper)
        placements = mesh.placements(joints)
        origins, axes = _world_axes(s, joints)
        for g in mesh.meshes:
            points = _vertices(mesh, placements, g)
            local = mesh.meshes[g][0]
            for n in np.flatnonzero(bodies[:, g] > 0.0):
                offset = points - origins[n]
                off_axis = np.linalg.norm(np.cross(offset, axes[n]), axis=1)
                assert off_axis.max() <= bodies[n, g] + 1e-12, (name, g, n)
                tight = max(tight, off_axis.max() / bodies[n, g])
                for leaf in np.flatnonzero(leaves.owner == g):
                    held = np.linalg.norm(local - leaves.local[leaf], axis=1) <= leaves.radii[leaf]
                    if held.any():
                        assert off_axis[held].max() <= own[n, leaf] + 1e-12, (name, leaf, n)
    assert tight > 0.5  # the bounds are not vacuous


@pytest.mark.parametrize("name", SERVICERS)
def test_joint_axes_from_the_objects_are_pinocchios(name):
    s, mesh = _scenario(name)
    joints = np.asarray(s.goal, float)
    origins, axes = _world_axes(s, joints)
    found = mesh.levers.axes_from(mesh.placements(joints))
    assert found is not None
    assert np.allclose(found[0], origins, atol=1e-12)
    assert np.allclose(found[1], axes, atol=1e-12)
    from_frames = mesh.levers.axes_at(mesh.frames(joints))
    assert np.allclose(from_frames[0], origins, atol=1e-12)
    assert np.allclose(from_frames[1], axes, atol=1e-12)


@pytest.mark.parametrize("name", SERVICERS)
def test_lever_speed_weights_bound_vertex_speeds_and_coal_distance_rates(name):
    """The first pass's speeds at once are those of each pair one by one. Along a path, on parts
    of first-pass intervals: every pair's coal distance changes no faster (finite
    differences) than its lever-arm bound, and for a pair with a body fixed to
    the spacecraft every vertex of the other body moves no faster (finite differences of
    Pinocchio's placements); never above the reach's bound, and well below it somewhere."""
    s, mesh = _scenario(name)
    motion = _motion(s)
    store = Instants(mesh, motion)
    times = np.linspace(0.0, motion.duration, 11)
    store.load(times)
    levers, h = IntervalLevers(store, times), 1e-6
    rates_all = store.rates(times[:-1].tolist(), times[1:].tolist())
    rows, pairs = np.nonzero(np.ones((len(times) - 1, len(mesh.pairs)), dtype=bool))
    placements = np.array([store.at(t) for t in times.tolist()])
    batch = levers.first_pass(rates_all, (rows, pairs), placements)
    one = [float(rates_all[i] @ levers.pair(i, k)) for i, k in zip(rows, pairs, strict=True)]
    assert np.allclose(batch, one, rtol=1e-12, atol=1e-15)  # all at once, or one by one
    own = reach_coefficients(s.robot, mesh.geometry, mesh.centres, mesh.radii)
    still = {g for g in range(len(mesh.centres)) if not own[:, g].any()}
    ratios = []
    for i in (1, 4, 8):
        a, b = (times[i] + f * (times[i + 1] - times[i]) for f in (0.3, 0.7))
        rates = motion.rate_bounds(np.array([a]), np.array([b]))[0]
        for k in np.flatnonzero(mesh.pair_reach.sum(axis=0) > 0.0):
            speed, reach = float(rates @ levers.pair(i, k)), float(rates @ mesh.pair_reach[:, k])
            assert speed <= reach * (1 + 1e-12)
            ratios.append(speed / reach)
            first, second = mesh.pairs[k]
            for t in np.linspace(a, b - h, 4):
                p0, p1 = mesh.placements(motion.joints(t)), mesh.placements(motion.joints(t + h))
                rate = abs(mesh.exact(p1, k) - mesh.exact(p0, k)) / h
                assert rate <= speed * (1 + 1e-4) + 1e-6, (name, mesh.names[k], t)
                if len({first, second} & still) != 1:
                    continue
                body = second if first in still else first
                if body in mesh.meshes:
                    moved = _vertices(mesh, p1, body) - _vertices(mesh, p0, body)
                    v = np.linalg.norm(moved, axis=1).max() / h
                    assert v <= speed * (1 + 1e-4) + 1e-9, (name, mesh.names[k], t)
    assert min(ratios) < 0.8


@pytest.mark.parametrize("name", SERVICERS)
def test_lever_arms_hold_every_vertex_over_the_interval(name):
    """Each leaf sphere's lever arm about each joint over an interval (from its arms at the two
    ends) is at least the distance from Pinocchio's joint axis of every vertex it holds, at
    every instant sampled densely inside; and it is tight for some (the drift over the
    interval counts)."""
    s, mesh = _scenario(name)
    motion, leaves = _motion(s), mesh.leaves
    reach = reach_coefficients(s.robot, mesh.geometry, leaves.local, leaves.radii, leaves.owner)
    levers = Levers(s.robot, mesh.geometry, reach, leaves.radii)
    spheres = np.arange(len(leaves.radii))
    held = {
        leaf: mesh.meshes[g][0][
            np.linalg.norm(mesh.meshes[g][0] - leaves.local[leaf], axis=1) <= leaves.radii[leaf]
        ]
        for leaf, g in enumerate(leaves.owner.tolist())
        if g in mesh.meshes
    }
    worst = 0.0
    for a, b in ((2.0, 4.0), (7.0, 8.5), (11.0, 14.0)):
        b = min(b, motion.duration)
        rates = motion.rate_bounds(np.array([a]), np.array([b]))
        ends = []
        for t in (a, b):
            placements = mesh.placements(motion.joints(t))
            origins, axes = _world_axes(s, motion.joints(t))
            centres = np.einsum("lij,lj->li", placements[leaves.owner, :3, :3], leaves.local)
            centres += placements[leaves.owner, :3, 3]
            ends.append(levers.arms(origins[None], axes[None], centres, spheres)[None])
        lever = levers.lever(
            np.array([b - a]),
            rates,
            (ends[0], ends[1]),
            levers.centre_t[spheres],
            levers.reach_t[spheres],
        )[0]
        for t in np.linspace(a, b, 41):
            joints = motion.joints(t)
            placements = mesh.placements(joints)
            origins, axes = _world_axes(s, joints)
            for leaf, local in held.items():
                g = leaves.owner[leaf]
                points = local @ placements[g, :3, :3].T + placements[g, :3, 3]
                for n in np.flatnonzero(levers.reach_t[leaf] > 0.0):
                    if not levers.revolute[n]:
                        continue
                    off = np.linalg.norm(np.cross(points - origins[n], axes[n]), axis=1).max()
                    assert off <= lever[leaf, n] + 1e-12, (name, leaf, n, t)
                    worst = max(worst, off / lever[leaf, n])
    assert worst > 0.98


def test_a_joint_without_objects_takes_its_axes_from_pinocchios_frames():
    """A robot one of whose joints' links carries no object gets its joints' axes from
    Pinocchio's frames: the same certificate, to rounding, as from the objects' poses."""
    s, mesh = _scenario("ur5_servicer")
    motion = _motion(s)
    with_objects = certify(mesh, motion, 0.01)
    mesh.levers.carriers = None  # this model only
    from_frames = certify(mesh, motion, 0.01)
    assert from_frames.lower_bound == pytest.approx(with_objects.lower_bound, abs=1e-12)
    assert from_frames.measured == with_objects.measured
    assert (from_frames.instants, from_frames.bisections) == (
        with_objects.instants,
        with_objects.bisections,
    )
