"""The clearance models' faster paths against the computations they replace, to the bit.

The certificate keeps what its first pass computed (leaf-pair gaps, interval rate bounds),
loads the instants halving will ask for in one evaluation, bounds every instant's spheres at
once, gathers leaf pairs by flat index and places only one pair's leaves at a new instant;
the solver's model measures only the pairs asked
for; both models share the parsed meshes and the checked pairs worked out once. Each is
compared here with the plain computation (numpy's own norm, one instant at a time, the old
construction, every pair measured), and a certificate with each shortcut undone must be the
same certificate.
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path

import coal
import numpy as np
import pytest

import freefloat as ff
from freefloat.robot import geometry, meshes
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.verify import certificate
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import MeshClearance
from freefloat.verify.instants import Instants
from freefloat.verify.motion import PolynomialMotion, reach_coefficients
from freefloat.verify.path_eval import file_path
from freefloat.verify.sphere_tree import _norms

from conftest import ROOT, quintic_motion

SCENARIOS = ROOT / "robots" / "scenarios"


def _models(name: str) -> tuple[ff.Scenario, MeshClearance, CollisionModel]:
    s = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    srdf = s.safety.srdf or known_srdf(s.robot)
    obstacles = s.safety.obstacles
    return s, MeshClearance(s.robot, srdf, obstacles), CollisionModel(s.robot, srdf, obstacles)


def _configurations(s: ff.Scenario, count: int, seed: int) -> np.ndarray:
    """Joint vectors between (and a little around) the scenario's start and goal."""
    start, goal = np.asarray(s.start, float), np.asarray(s.goal, float)
    rng = np.random.default_rng(seed)
    u = rng.uniform(-0.2, 1.2, (count, 1))
    return start + u * (goal - start) + rng.normal(0.0, 0.05, (count, len(start)))


def test_norms_are_numpys_to_the_bit():
    rng = np.random.default_rng(3)
    vectors = rng.normal(size=(5000, 3)) * 10.0 ** rng.integers(-9, 3, (5000, 1))
    assert np.array_equal(_norms(vectors.copy()), np.linalg.norm(vectors, axis=1))


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
def test_sphere_bounds_of_many_instants_are_those_of_each(name):
    s, mesh, _ = _models(name)
    placements = np.array([mesh.placements(q) for q in _configurations(s, 20, 1)])
    each = np.array([mesh.sphere_bounds(p) for p in placements])
    assert np.array_equal(mesh.sphere_bounds(placements), each)


def test_leaf_pairs_are_every_leaf_of_one_against_every_leaf_of_the_other():
    _, mesh, _ = _models("panda_servicer")
    leaves = mesh.leaves
    first = np.concatenate([[0], np.cumsum(np.bincount(leaves.owner))])
    for k, (a, b) in enumerate(mesh.pairs):
        la, lb = np.arange(first[a], first[a + 1]), np.arange(first[b], first[b + 1])
        rows = leaves.rows_of(k)
        assert np.array_equal(leaves.left[rows], np.repeat(la, len(lb)))
        assert np.array_equal(leaves.right[rows], np.tile(lb, len(la)))
    assert np.array_equal(leaves.row_reach_t, leaves.row_reach.T)
    s = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")
    placements = np.array([mesh.placements(q) for q in _configurations(s, 7, 5)])
    poses = placements[:, leaves.owner]  # every leaf's body pose, gathered whole
    whole = np.einsum("kLij,Lj->kLi", poses[..., :3, :3], leaves.local) + poses[..., :3, 3]
    assert np.array_equal(leaves.centres_at(placements), whole)


def _plain_rates(self: Instants, t0: list[float], t1: list[float]) -> np.ndarray:
    """Interval rate bounds computed afresh every time, none kept."""
    for t in (*t0, *t1):
        self.at(t)
    ends = np.array([self.speeds[t] for t in (*t0, *t1)])
    return self.motion.rate_bounds(np.array(t0), np.array(t1), ends)


_OWN_MIDDLES = [0]


def _own_middles(store: Instants, heap: list, t0: float, t1: float) -> np.ndarray:
    """The middle of the interval refined and those of its halves, alone (calls counted)."""
    _OWN_MIDDLES[0] += 1
    mid = 0.5 * (t0 + t1)
    return np.array([mid, 0.5 * (t0 + mid), 0.5 * (mid + t1)])


def _plan_motion(name: str) -> tuple[MeshClearance, CollisionModel, PolynomialMotion]:
    s, mesh, solver = _models(name)
    path = file_path(ff.plan(s))
    return mesh, solver, PolynomialMotion(path, path.duration, path.degree, path.positions)


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
def test_a_certificate_without_its_shortcuts_is_the_same_certificate(monkeypatch, name):
    """The shipped servicer's plan (the UR5's refines 15 intervals past the first pass, by
    second-order bounds): first-pass gaps and rate bounds computed afresh, each refinement
    loading its own instants alone; every field of the certificate and every exact query the
    same."""
    mesh, solver, motion = _plan_motion(name)
    queries: list[tuple[int, int]] = []
    exact = MeshClearance.exact_placed

    def counted(self, placed, k):
        queries.append((hash(placed.placements.tobytes()), k))
        return exact(self, placed, k)

    monkeypatch.setattr(MeshClearance, "exact_placed", counted)
    fast = certify(mesh, motion, 0.01, solver)
    fast_queries, queries[:] = list(queries), []
    with monkeypatch.context() as undone:
        undone.setattr(Instants, "_kept_gaps", lambda self, t, k: None)
        undone.setattr(Instants, "rates", _plain_rates)
        undone.setattr(certificate, "_middles", _own_middles)
        _OWN_MIDDLES[0] = 0
        plain = certify(mesh, motion, 0.01, solver)
    assert dataclasses.asdict(fast) == dataclasses.asdict(plain)
    assert fast_queries == queries
    assert fast.certified and (_OWN_MIDDLES[0] > 0) == (name == "ur5_servicer")


def test_motion_roots_are_those_of_the_fitted_series():
    """Chebyshev fit and roots called directly: the same rate peaks as the series objects."""
    _, _, motion = _plan_motion("ur5_servicer")
    points = max(motion.path.degree - 1, 1)
    x = np.cos(np.pi * (np.arange(points) + 0.5) / points)
    acceleration = motion.path(0.5 * (x + 1.0) * motion.duration)[2]
    roots = []
    for j in range(acceleration.shape[1]):
        series = np.polynomial.Chebyshev.fit(x, acceleration[:, j], points - 1, domain=[-1, 1])
        if np.any(np.abs(series.coef[1:]) > 0.0):
            roots += [
                (0.5 * (float(r.real) + 1.0) * motion.duration, j)
                for r in np.atleast_1d(series.roots())
                if abs(r.imag) <= 1e-9 and -1.0 < r.real < 1.0
            ]
    roots.sort()
    assert roots, "the plan's joint rates peak inside"
    assert motion._root_times.tolist() == [t for t, _ in roots]
    assert motion._root_joints.tolist() == [j for _, j in roots]


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
def test_pair_distances_are_those_of_every_pair(name):
    s, _, solver = _models(name)
    rng = np.random.default_rng(7)
    for q in _configurations(s, 12, 2):
        values = solver.distances(q).values
        pairs = rng.choice(len(values), size=5, replace=False)
        assert np.array_equal(solver.pair_distances(q, pairs), values[pairs])


def test_shared_geometry_copies_objects_and_primitives_keeps_keys_never_changes_a_mesh(
    monkeypatch,
):
    robot = ff.Scenario.from_toml(SCENARIOS / "ur5_servicer.toml").robot
    shared, again = (geometry.load_shared_geometry(robot) for _ in range(2))
    first, keys, second = shared.model, shared.keys, again.model
    objects = list(first.geometryObjects)
    # each mesh's key, kept from parsing, is the one its vertices give now
    assert keys == {
        i: meshes.mesh_key(o)
        for i, o in enumerate(objects)
        if isinstance(o.geometry, coal.BVHModelBase)
    }
    mesh = next(i for i, o in enumerate(objects) if isinstance(o.geometry, coal.BVHModelBase))
    box = next(i for i, o in enumerate(objects) if isinstance(o.geometry, coal.Box))
    # a hull built anew (none kept) leaves the shared mesh as it was
    monkeypatch.setattr(meshes, "_HULLS", {})
    hull = meshes.true_hull(objects[mesh])
    assert hull.num_points > 3
    assert first.geometryObjects[mesh].geometry.convex is None
    assert second.geometryObjects[mesh].geometry.convex is None
    # objects and primitives are each caller's own
    first.geometryObjects[mesh].geometry = coal.Sphere(0.1)
    first.geometryObjects[box].geometry.halfSide = np.array([9.0, 9.0, 9.0])
    assert isinstance(second.geometryObjects[mesh].geometry, coal.BVHModelBase)
    assert not np.allclose(second.geometryObjects[box].geometry.halfSide, 9.0)
    first.addGeometryObject(first.geometryObjects[0].copy())
    assert len(second.geometryObjects) == len(first.geometryObjects) - 1


def test_checked_pairs_kept_are_those_worked_out_and_follow_an_edited_srdf(monkeypatch, tmp_path):
    """Panda servicer: the pairs (and the geometry's collision pairs) from the kept list are
    those worked out afresh; an SRDF rewritten with one more disabled pair drops that pair."""
    s = ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")
    robot = s.robot
    srdf = tmp_path / "robot.srdf"
    original = Path(known_srdf(robot)).read_text()
    srdf.write_text(original)

    def pairs() -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
        model = geometry.load_shared_geometry(robot).model
        found = geometry.checked_pairs(robot, model, srdf)
        return found, [(int(p.first), int(p.second)) for p in model.collisionPairs]

    monkeypatch.setattr(geometry, "_PAIRS", {})
    fresh = pairs()
    assert fresh[0] == fresh[1] and len(geometry._PAIRS) == 1
    assert pairs() == fresh  # kept
    model = geometry.load_shared_geometry(robot).model
    frames = robot.model.frames
    a, b = fresh[0][0]
    link_a = frames[model.geometryObjects[a].parentFrame].name
    link_b = frames[model.geometryObjects[b].parentFrame].name
    extra = f'<disable_collisions link1="{link_a}" link2="{link_b}" reason="test"/>'
    srdf.write_text(original.replace("</robot>", extra + "\n</robot>"))
    os.utime(srdf, ns=(srdf.stat().st_atime_ns, srdf.stat().st_mtime_ns + 10**9))
    edited = pairs()
    assert (a, b) not in edited[0] and set(edited[0]) < set(fresh[0])
    assert edited[0] == edited[1]


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
def test_one_pairs_leaf_gaps_are_those_of_every_leaf_placed(name):
    s, mesh, _ = _models(name)
    leaves = mesh.leaves
    for q in _configurations(s, 6, 4):
        placements = mesh.placements(q)
        for k in range(len(mesh.pairs)):
            rows = leaves.rows_of(k)
            plain = leaves.row_gaps(placements[None], np.zeros(len(rows), dtype=int), rows)
            assert np.array_equal(leaves.pair_gaps(placements, k), plain), mesh.names[k]


def test_spheres_and_reaches_are_those_worked_out_apart():
    """The single spheres of the meshes (kept per vertex array) and the speed coefficients of
    the bodies and of the leaves (one pass) against each worked out on its own."""
    s, mesh, _ = _models("panda_servicer")
    again = MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot), s.safety.obstacles)
    for i, (vertices, _) in mesh.meshes.items():
        centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        assert np.array_equal(mesh.centres[i], centre) and np.array_equal(again.centres[i], centre)
        assert mesh.radii[i] == float(np.linalg.norm(vertices - centre, axis=1).max())
    leaves = mesh.leaves
    bodies = reach_coefficients(s.robot, mesh.geometry, mesh.centres, mesh.radii)
    own = reach_coefficients(s.robot, mesh.geometry, leaves.local, leaves.radii, leaves.owner)
    ra, rb = bodies[:, mesh.first], bodies[:, mesh.second]
    assert np.array_equal(mesh.pair_reach, np.where((ra > 0.0) & (rb > 0.0), 0.0, ra + rb))
    la, lb = own[:, leaves.left], own[:, leaves.right]
    assert np.array_equal(leaves.row_reach, np.where((la > 0.0) & (lb > 0.0), 0.0, la + lb))


def test_a_robot_without_collision_geometry_has_no_pairs_to_certify(tmp_path):
    """Two links and no collision element: the original-geometry model builds with no pair,
    and the certificate says so (clear at every instant) instead of failing on empty arrays."""
    inertial = (
        '<inertial><mass value="{m}"/><inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" '
        'iyz="0"/></inertial>'
    )
    joint = (
        '<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
        '<origin xyz="{x} 0 0"/><axis xyz="0 0 1"/>'
        '<limit lower="-3" upper="3" effort="10" velocity="1"/></joint>'
    )
    urdf = (
        '<robot name="bare">'
        f'<link name="base">{inertial.format(m=100, i=10)}</link>'
        + joint.format(n="j1", p="base", c="l1", x=0)
        + f'<link name="l1">{inertial.format(m=1, i=0.1)}</link>'
        + joint.format(n="j2", p="l1", c="l2", x=1)
        + f'<link name="l2">{inertial.format(m=1, i=0.1)}</link></robot>'
    )
    (tmp_path / "bare.urdf").write_text(urdf)
    mesh = MeshClearance(ff.load_robot(tmp_path / "bare.urdf"), None)
    assert mesh.pairs == []
    found = certify(mesh, quintic_motion(np.zeros(2), np.ones(2), 5.0), 0.01)
    assert found.certified and found.lower_bound == math.inf and found.pair == ""
    assert "no pairs" in found.kind
    assert found.detail == "no pairs to check: clear at every instant; margin 0.01 m"
