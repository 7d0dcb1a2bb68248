"""Separating-direction lower bounds of the verification's pair distances (verify.separation).

Truth never comes from the code under test: coal's exact distances on the original meshes and
primitives, closed forms for primitives placed by hand, points sampled on each primitive's
surface for its support, and a certificate that measures every pair at many instants.
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pytest

import freefloat as ff
from freefloat.robot.collision import Obstacle, known_srdf
from freefloat.verify import separation as separation_module
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import ACCURACY, SLACK_FRACTION, MeshClearance, Placed
from freefloat.verify.instants import Instants
from freefloat.verify.separation import Separation

from conftest import ROOT, quintic_motion
from geometry_truth import write_stl

UR5 = ROOT / "robots" / "ur5_servicer.urdf"


def _bounds_and_exact(mesh: MeshClearance, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P,) separating-direction bounds and coal's exact distances of every pair (m)."""
    placements = mesh.placements(joints)
    placed = Placed(mesh, placements)
    bounds, exact = [], []
    for k, (a, b) in enumerate(mesh.pairs):
        transforms = (placed.transform(a), placed.transform(b))
        bounds.append(mesh.separation.bound(a, b, placements[a], placements[b], transforms))
        exact.append(mesh.exact_placed(placed, k))
    return np.array(bounds), np.array(exact)


def _exact_only(store: Instants, t: float, k: int) -> float:
    """The certificate's end values before separation bounds: exact where measured, else none."""
    return store.exact.get((t, k), -math.inf)


def _with_and_without(mesh: MeshClearance, motion, margin: float, monkeypatch):
    """The certificate with separation bounds and with exact ends only, and the exact queries
    each made: ((certificate, queries), (certificate, queries))."""
    counted = {"exact": 0}
    exact_placed = mesh.exact_placed

    def counting(placed, k):
        counted["exact"] += 1
        return exact_placed(placed, k)

    with monkeypatch.context() as patch:
        patch.setattr(mesh, "exact_placed", counting)
        with_bounds = certify(mesh, motion, margin)
        queries, counted["exact"] = counted["exact"], 0
        patch.setattr(Instants, "lower", _exact_only)  # the certificate as it was
        without = certify(mesh, motion, margin)
    return (with_bounds, queries), (without, counted["exact"])


def test_the_bound_never_exceeds_the_mesh_distance_and_is_close_where_given():
    """UR5 servicer with a keep-out box, sphere and capsule, 30 random configurations: every
    bound lies at or below coal's distance on the original meshes, a bound is given for most
    separated pairs, and where one is given it is within a few millimetres."""
    robot = ff.load_robot(UR5)
    obstacles = [
        Obstacle("ball", "sphere", (0.12,), (0.7, 0.4, 0.9)),
        Obstacle("post", "capsule", (0.05, 0.4), (0.9, -0.3, 0.9)),
        Obstacle("slab", "box", (0.2, 0.3, 0.05), (0.6, 0.0, 1.6)),
    ]
    mesh = MeshClearance(robot, known_srdf(robot), obstacles)
    rng = np.random.default_rng(11)
    given, separated, gaps = 0, 0, []
    for _ in range(30):
        bounds, exact = _bounds_and_exact(mesh, rng.uniform(-2.5, 2.5, robot.n))
        assert np.all(bounds <= exact + 1e-9)
        clear = exact > 1e-3
        separated += int(clear.sum())
        finite = np.isfinite(bounds) & clear
        given += int(finite.sum())
        gaps += (exact[finite] - bounds[finite]).tolist()
    assert given >= 0.9 * separated
    assert np.median(gaps) < 2e-3


@pytest.mark.parametrize(
    ("other", "distance"),
    [
        (coal.Sphere(0.3), 2.0 - 0.5 - 0.3),
        (coal.Box(0.6, 0.6, 0.6), 2.0 - 0.5 - 0.3),
        (coal.Capsule(0.2, 1.0), 2.0 - 0.5 - 0.2),
        (coal.Cylinder(0.25, 1.0), 2.0 - 0.5 - 0.25),
    ],
)
def test_primitives_face_to_face_give_their_closed_form_distance(other, distance):
    """A unit box and a primitive 2 m apart along x (the capsule's and cylinder's axis along
    z, so their side faces the box): the bound is the closed-form gap."""
    box = coal.Box(1.0, 1.0, 1.0)
    separation = Separation([box, other], {}, {})
    pa, pb = np.eye(4), np.eye(4)
    pb[:3, 3] = [2.0, 0.3, -0.2]
    transforms = (coal.Transform3s(pa[:3, :3], pa[:3, 3]), coal.Transform3s(pb[:3, :3], pb[:3, 3]))
    assert separation.bound(0, 1, pa, pb, transforms) == pytest.approx(distance, abs=1e-6)


def _surface_points(shape: coal.CollisionGeometry, count: int) -> np.ndarray:
    """Points sampled on a primitive's surface, its extreme points among them (m)."""
    rng = np.random.default_rng(3)
    if isinstance(shape, coal.Box):
        h = np.asarray(shape.halfSide)
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        return np.vstack([corners * h, rng.uniform(-1, 1, (count, 3)) * h])
    u = rng.normal(size=(count, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    if isinstance(shape, coal.Sphere):
        return shape.radius * u
    if isinstance(shape, coal.Capsule):
        ends = np.where(u[:, 2:3] >= 0, 1.0, -1.0) * np.array([0, 0, shape.halfLength])
        return ends + shape.radius * u
    angle = rng.uniform(0, 2 * math.pi, count)  # a cylinder: its two rims
    z = np.where(rng.uniform(size=count) < 0.5, -1.0, 1.0) * shape.halfLength
    return np.stack([shape.radius * np.cos(angle), shape.radius * np.sin(angle), z], axis=1)


@pytest.mark.parametrize(
    "shape",
    [coal.Box(0.4, 1.0, 0.2), coal.Sphere(0.3), coal.Capsule(0.2, 0.8), coal.Cylinder(0.1, 0.6)],
    ids=["box", "sphere", "capsule", "cylinder"],
)
def test_each_primitive_support_is_the_largest_projection_of_its_surface(shape):
    """The closed-form support is at least every sampled surface point's projection and
    within the sampling's resolution of the largest (100,000 points)."""
    support = separation_module._support_of(shape, None)
    assert support is not None
    points = _surface_points(shape, 100_000)
    rng = np.random.default_rng(5)
    for _ in range(20):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        sampled = float(np.max(points @ n))
        assert support(n) >= sampled - 1e-12
        assert support(n) <= sampled + 5e-3


def test_a_wrong_hull_only_loosens_the_bound():
    """Every mesh's hull swapped for a small ball somewhere else: the directions it proposes
    are poor, yet no bound exceeds coal's mesh distance (the bound is over the vertices)."""
    robot = ff.load_robot(UR5)
    mesh = MeshClearance(robot, known_srdf(robot))
    wrong = {i: (lambda: coal.Sphere(0.01)) for i in mesh.meshes}
    mesh.separation = Separation(mesh.shapes, {i: v for i, (v, _) in mesh.meshes.items()}, wrong)
    rng = np.random.default_rng(2)
    for _ in range(20):
        bounds, exact = _bounds_and_exact(mesh, rng.uniform(-2.5, 2.5, robot.n))
        assert np.all(bounds <= exact + 1e-9)


@pytest.mark.parametrize(
    ("name", "fewer"), [("panda_servicer", True), ("dual_ur5_servicer", False)]
)
def test_the_certificate_with_separations_matches_it_without_on_fewer_queries(
    name, fewer, monkeypatch
):
    """A shipped servicer's quintic motion certified with and without separating-direction
    bounds: the same verdict and smallest measured clearance, no more exact queries (fewer
    where two meshes come near: the Panda's hand and links; the dual UR5's quintic keeps its
    arms apart), and a lower bound at or below every pair measured at 101 instants and within
    the accuracy promised."""
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    mesh = MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot))
    motion = quintic_motion(np.asarray(s.start), np.asarray(s.goal), s.duration)
    (with_bounds, queries), (without, before) = _with_and_without(mesh, motion, 0.01, monkeypatch)
    assert 0 < queries <= before
    assert (queries < before) == fewer
    assert with_bounds.certified == without.certified
    assert with_bounds.measured == pytest.approx(without.measured, abs=ACCURACY)
    dense = min(
        mesh.exact(mesh.placements(joints), k)
        for joints in motion.path(np.linspace(0.0, motion.duration, 101))[0]
        for k in range(len(mesh.pairs))
    )
    assert with_bounds.lower_bound <= dense + 1e-12
    accuracy = max(ACCURACY, SLACK_FRACTION * (with_bounds.measured - 0.01))
    assert with_bounds.measured - with_bounds.lower_bound <= accuracy + 1e-12


def _box(lo, hi) -> np.ndarray:
    """(12, 3, 3) the triangles of an axis-aligned box (m)."""
    c = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1)]
    faces += [(2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    return c[np.array(faces)]


_COMB_ROBOT = """<?xml version="1.0"?>
<robot name="comb">
  <link name="base"><inertial><mass value="100"/>
    <inertia ixx="10" iyy="10" izz="10" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 -0.08 -0.1"/><geometry><mesh filename="comb.stl"/></geometry>
    </collision></link>
  <joint name="turn" type="revolute"><parent link="base"/><child link="carrier"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <link name="carrier"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="slide" type="prismatic"><parent link="carrier"/><child link="hand"/>
    <axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="10" velocity="1"/></joint>
  <link name="hand"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><mesh filename="hand.stl"/></geometry></collision></link>
</robot>
"""


@pytest.mark.parametrize(
    ("start", "goal"), [((0.0, 0.22), (0.05, 0.30)), ((-0.05, 0.24), (0.05, 0.26))]
)
def test_a_hand_between_a_combs_teeth_costs_no_more_queries_than_exact_ends(
    tmp_path, start, goal, monkeypatch
):
    """A box hand moving in the gap between two teeth of a comb (two meshes whose hulls
    overlap all along, so no direction separates them): the certificate with separation
    bounds makes no more exact queries than the one with exact ends only, reports the same
    figures, and its bound lies at or below the distance measured at 401 instants."""
    teeth = [_box((0.05, i * 0.12, 0.0), (0.35, i * 0.12 + 0.04, 0.2)) for i in range(4)]
    write_stl(tmp_path / "comb.stl", np.concatenate([_box((0, 0, 0), (0.05, 0.48, 0.2)), *teeth]))
    write_stl(tmp_path / "hand.stl", _box((-0.02, -0.02, -0.05), (0.25, 0.02, 0.05)))
    (tmp_path / "comb.urdf").write_text(_COMB_ROBOT)
    mesh = MeshClearance(ff.load_robot(tmp_path / "comb.urdf"), None)
    motion = quintic_motion(np.array(start), np.array(goal), 1.0)
    (with_bounds, queries), (without, before) = _with_and_without(mesh, motion, 0.0, monkeypatch)
    assert 0 < queries <= before
    assert (with_bounds.measured, with_bounds.lower_bound, with_bounds.certified) == (
        without.measured,
        without.lower_bound,
        without.certified,
    )
    dense = min(
        mesh.exact(mesh.placements(q), 0) for q in motion.path(np.linspace(0.0, 1.0, 401))[0]
    )
    assert with_bounds.lower_bound <= dense + 1e-12
