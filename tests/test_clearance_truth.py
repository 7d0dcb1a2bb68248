"""Clearance against geometry computed here: true hulls, the original meshes, between samples.

Truth never comes from the code under test: exact point-to-triangle distances over the STL
files' own triangles (read by :mod:`geometry_truth`, not by coal), exact distances to convex
hulls by quadratic programming (quadprog), a hull known in closed form (a U's bounding box),
and closed-form sphere and plate positions.
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot import collision, meshes
from freefloat.robot.collision import (
    RETRY_TOLERANCES,
    CollisionModel,
    Obstacle,
    checked_distance,
    known_srdf,
)
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import CHECK_TOLERANCE, MeshClearance
from freefloat.verify.hull_agreement import compared, hull_slack, shape_excess
from freefloat.verify.motion import PolynomialMotion

from conftest import ROOT, coal_hull, quintic_motion
from geometry_truth import (
    box_hull_distance,
    point_hull_distance,
    point_mesh_distance,
    world_meshes,
    write_stl,
)

UR5 = ROOT / "robots" / "ur5_servicer.urdf"
UR5_START = np.radians([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
UR5_GOAL = np.radians([57.3, -57.3, 68.8, -68.8, -57.3, 28.6])


@pytest.mark.parametrize(
    ("shape", "size", "xyz"),
    [
        ("sphere", (0.05,), (0.85, 0.14, -0.20)),
        ("sphere", (0.03,), (0.70, 0.30, -0.45)),
        ("box", (0.06, 0.1, 0.04), (0.95, 0.05, -0.30)),
    ],
)
def test_solver_distances_are_exact_hull_distances_and_never_exceed_the_mesh(shape, size, xyz):
    """Solver (true hull) == quadprog on the STL's vertices; <= the exact mesh distance."""
    robot = ff.load_robot(UR5)
    obstacle = Obstacle("o", shape, size, xyz)
    model = CollisionModel(robot, known_srdf(robot), [obstacle])
    checked = 0
    for s in np.linspace(0.0, 1.0, 5):
        joints = UR5_START + s * (UR5_GOAL - UR5_START)
        values = model.distances(joints).values
        meshes = world_meshes(model, joints)
        for k, (a, _) in enumerate(model.pairs):
            if not model.names[k].endswith("obstacle:o") or a not in meshes:
                continue
            vertices = meshes[a].reshape(-1, 3)
            if shape == "sphere":
                hull = point_hull_distance(np.array(xyz), vertices) - size[0]
                mesh = point_mesh_distance(np.array(xyz), meshes[a]) - size[0]
            else:
                hull = box_hull_distance(np.array(xyz), np.eye(3), np.array(size) / 2, vertices)
                mesh = math.inf  # no closed form for box to triangles here; the bound below
            if hull > 1e-3:  # the quadratic programme measures separation only
                assert values[k] == pytest.approx(hull, abs=1e-6), model.names[k]
                assert values[k] <= mesh + 1e-9
                checked += 1
    assert checked >= 10


def test_a_u_shaped_mesh_gets_its_true_hull_and_verification_its_true_surface(tmp_path):
    """A U whose hull is its bounding box (closed form): a ball in the notch overlaps the hull
    by 7 cm (solver) while the mesh is 3 cm away (verification), and a ball inside an arm of the
    U is reported as penetration though no triangle touches it."""
    bars = [
        ((0, 0, 0), (0.1, 0.3, 0.1)),
        ((0.1, 0, 0), (0.3, 0.1, 0.1)),
        ((0.1, 0.2, 0), (0.3, 0.3, 0.1)),
    ]
    triangles = np.concatenate(
        [_box_triangles(np.array(lo, float), np.array(hi, float)) for lo, hi in bars]
    )
    write_stl(tmp_path / "u.stl", triangles)
    urdf = tmp_path / "u.urdf"
    urdf.write_text(_U_ROBOT)
    robot = ff.load_robot(urdf)
    notch = Obstacle("notch", "sphere", (0.02,), (1.25, 0.15, 0.05))
    solver = CollisionModel(robot, None, [notch])
    k = solver.names.index("u_0 / obstacle:notch")
    # Hull = box [1, 1.3] x [0, 0.3] x [0, 0.1]: the centre is 0.05 m from its nearest face.
    assert solver.distances(np.zeros(1)).values[k] == pytest.approx(-0.07, abs=1e-7)
    mesh = MeshClearance(robot, None, [notch])
    truth = point_mesh_distance(np.array([0.25, 0.15, 0.05]), triangles) - 0.02
    assert truth == pytest.approx(0.03, abs=1e-12)
    assert mesh.exact(mesh.placements(np.zeros(1)), k) == pytest.approx(truth, abs=1e-7)
    # Inside the left bar: no triangle is within 3 cm, but the ball is inside the solid.
    inside = Obstacle("inside", "sphere", (0.02,), (1.05, 0.15, 0.05))
    mesh = MeshClearance(robot, None, [inside])
    still = PolynomialMotion.from_monomials([[0.0]], 1.0)
    cert = certify(mesh, still, 0.0)
    assert cert.penetration and not cert.certified and "contained" in cert.kind
    assert cert.measured == pytest.approx(-0.03, abs=1e-7)


_U_ROBOT = """<?xml version="1.0"?>
<robot name="u">
  <link name="base"><inertial><mass value="100"/><inertia ixx="10" iyy="10" izz="10" ixy="0"
    ixz="0" iyz="0"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="u"/><origin xyz="1 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="u"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0"
    ixz="0" iyz="0"/></inertial>
    <collision><geometry><mesh filename="u.stl"/></geometry></collision></link>
</robot>
"""


def _box_triangles(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    return corners[np.array(faces)]


def test_coal_epa_failures_are_retried_never_passed_on():
    """Two penetrating cylinders where coal's EPA at 1e-9 m returns -DBL_MAX: the checked query
    answers a finite depth within what the bounding spheres allow, and counts its retries."""
    a, b = coal.Cylinder(0.06, 0.35), coal.Cylinder(0.06, 0.53)
    offset = np.array([0.1195, -0.2570, -0.0549])
    rng = np.random.default_rng(0)
    request = coal.DistanceRequest()
    request.enable_signed_distance, request.gjk_tolerance, request.epa_tolerance = True, 1e-9, 1e-9
    ra, rb = math.hypot(0.06, 0.175), math.hypot(0.06, 0.265)
    gap = float(np.linalg.norm(offset))
    broken = retried = 0
    for _ in range(400):
        ta = coal.Transform3s(pin.Quaternion(*_unit(rng)).toRotationMatrix(), np.zeros(3))
        tb = coal.Transform3s(pin.Quaternion(*_unit(rng)).toRotationMatrix(), offset)
        raw = coal.distance(a, ta, b, tb, request, coal.DistanceResult())
        answer = checked_distance(a, ta, b, tb, (gap - ra - rb, gap + ra + rb), "a / b")
        assert math.isfinite(answer.value) and gap - ra - rb <= answer.value <= gap + ra + rb
        if not math.isfinite(raw) or raw < -1.0:
            broken += 1
            retried += answer.retries > 0
            assert answer.value < 0.0  # they do overlap: the retry gives a depth
    assert broken >= 1, "coal no longer fails here: the retry path went untested"
    assert retried == broken and RETRY_TOLERANCES[0] > 1e-9


def _unit(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def test_a_thin_plate_crossed_between_samples_is_caught(tmp_path):
    """A 2 mm ball sweeps through a 2 mm plate between two of 401 instants (the sampled check
    verification made before) where it is clear of it (closed form): the certificate refines
    and reports the penetration."""
    from test_collision import SPHERE_ARM

    path = tmp_path / "sphere_arm.urdf"
    path.write_text(SPHERE_ARM.replace('radius="0.1"', 'radius="0.002"'))
    robot = ff.load_robot(path)
    duration = 1.0
    motion = quintic_motion(np.array([-1.5, 0.0]), np.array([1.5, 0.0]), duration)
    times = np.linspace(0.0, duration, 401)
    angles = np.array([motion.joints(t)[0] for t in times])
    k = int(np.argmax(np.diff(angles)))  # the widest step, mid-path
    crossing = 0.5 * (angles[k] + angles[k + 1])
    # The ball's centre moves on a 1.6 m circle about (0.5, 0, 0); the plate is radial there.
    plate = Obstacle(
        "plate", "box", (2.0, 0.002, 0.5),
        (0.5 + 1.6 * math.cos(crossing), 1.6 * math.sin(crossing), 0.0), (0.0, 0.0, crossing),
    )  # fmt: skip
    sampled = 1.6 * np.abs(np.sin(angles - crossing)) - 0.001 - 0.002  # closed form, per instant
    assert sampled.min() > 0.0  # every instant is clear: a sampled check sees no contact
    mesh = MeshClearance(robot, None, [plate])
    cert = certify(mesh, motion, 0.0)
    assert cert.penetration and not cert.certified
    assert cert.measured == pytest.approx(-0.003, abs=1e-6)  # centred in the plate
    assert times[k] <= cert.time <= times[k + 1]


@pytest.mark.parametrize("above", [20e-6, 1e-5, 3e-7, 5e-9])
def test_a_path_just_clear_of_the_margin_is_certified_clear(tmp_path, above):
    """A 2 mm ball passes a wall at the margin plus 20 um to 5 nm at mid-path (closed form:
    the wall is the plane x = x_wall, the ball's centre on a 1.6 m circle). Verification once
    settled every interval within 0.1 mm of the smallest clearance measured, and so left its
    bound below the margin and refused the plan (ETS-VII holding a payload); the bound is now
    brought to the margin (within the check's 1e-6 m when the wall is closer than that),
    stays below the closed-form minimum, and never spends the halving budget."""
    from test_collision import SPHERE_ARM

    path = tmp_path / "sphere_arm.urdf"
    path.write_text(SPHERE_ARM.replace('radius="0.1"', 'radius="0.002"'))
    robot = ff.load_robot(path)
    margin, thickness, duration = 0.01, 0.002, 1.0
    x_wall = 0.5 + 1.6 + 0.002 + margin + above  # the face nearest the ball
    wall = Obstacle(
        "wall", "box", (thickness, 0.4, 0.5), (x_wall + thickness / 2, 0.0, 0.0), (0.0, 0.0, 0.0)
    )
    motion = quintic_motion(np.array([-1.5, 0.0]), np.array([1.5, 0.0]), duration)
    times = np.linspace(0.0, duration, 20001)
    angles = np.array([motion.joints(t)[0] for t in times])
    truth = x_wall - (0.5 + 1.6 * np.cos(angles)) - 0.002  # ball to wall face, closed form
    assert truth.min() == pytest.approx(margin + above, abs=1e-12)
    cert = certify(MeshClearance(robot, None, [wall]), motion, margin)
    assert cert.certified and not cert.exhausted
    floor = margin if above >= CHECK_TOLERANCE else margin - CHECK_TOLERANCE
    assert floor <= cert.lower_bound <= truth.min() + 1e-9
    assert cert.measured == pytest.approx(margin + above, abs=1e-9)


def test_the_ur5_keep_out_ball_plans_clear_on_the_true_meshes(tmp_path):
    """Issue 21's case: a 5 cm ball the plain unfolding motion passes through. The plan keeps
    1 cm on the meshes (exact point-to-triangle distances along its polynomials, densely), and
    its reported clearance agrees with that truth to 1 mm."""
    scenario = tmp_path / "ur5_ball.toml"
    scenario.write_text(
        (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
        + '\n[safety]\nmargin_m = 0.01\n[[obstacles]]\nname = "ball"\nsphere = 0.05\n'
        "xyz = [0.85, 0.14, -0.20]\n"
    )
    s = ff.Scenario.from_toml(scenario)
    quintic = quintic_motion(np.asarray(s.start), np.asarray(s.goal), s.duration)
    model = CollisionModel(s.robot, known_srdf(s.robot), s.safety.obstacles)
    centre = np.array([0.85, 0.14, -0.20])
    before = min(
        point_mesh_distance(centre, tri) - 0.05
        for t in np.linspace(0, s.duration, 41)
        for tri in world_meshes(model, quintic.joints(t)).values()
    )
    assert before < 0.0  # the plain motion goes through the ball
    plan = ff.plan(s)
    check = plan.verification["clearance"]
    assert "obstacle:ball" in check.detail
    t = np.linspace(0.0, plan.duration, 801)
    truth = min(
        point_mesh_distance(centre, tri) - 0.05
        for q in plan.joint_positions(t)
        for tri in world_meshes(model, q).values()
    )
    assert truth >= 0.01
    certified = plan.safety.margin_m - check.value  # the certified lower bound
    reported = float(check.detail.split("min clearance ", 1)[1].split(" m", 1)[0])
    assert certified <= truth + 1e-9 and abs(truth - reported) < 1e-3


@pytest.mark.parametrize("name", ["ur5_servicer", "panda_servicer", "dual_ur5_servicer"])
def test_solver_mesh_and_brute_force_agree_on_the_shipped_servicers(name):
    """Every pair at configurations along the shipped scenario's plain motion: hull (solver)
    <= mesh (verification) <= nearest vertex pair or vertex-box distance (brute force, numpy),
    and mesh <= hull + the hull's slack."""
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    srdf = s.safety.srdf or known_srdf(s.robot)
    solver = CollisionModel(s.robot, srdf)
    mesh = MeshClearance(s.robot, srdf)
    worst = 0.0
    for u in np.linspace(0.0, 1.0, 4):
        joints = np.asarray(s.start) + u * (np.asarray(s.goal) - np.asarray(s.start))
        hull = solver.distances(joints).values
        placements = mesh.placements(joints)
        meshes = world_meshes(solver, joints)
        for k, (a, b) in enumerate(mesh.pairs):
            true = mesh.exact(placements, k)
            assert hull[k] <= true + 1e-6, mesh.names[k]
            if true > 0.0:
                slack = hull_slack(solver, a) + hull_slack(solver, b)
                assert true <= hull[k] + slack + 1e-6, mesh.names[k]
                if a in meshes and b in meshes:
                    va, vb = meshes[a].reshape(-1, 3), meshes[b].reshape(-1, 3)
                    brute = min(float(np.linalg.norm(va - v, axis=1).min()) for v in vb[::3])
                    assert true <= brute + 1e-9, mesh.names[k]
            worst = max(worst, hull[k] - true)
    assert worst <= 1e-6


def test_bulk_distances_do_not_depend_on_what_was_asked_before():
    """All pairs in one C++ pass, from coal's default guess: the distances at a configuration
    are the same bits after any other query, and equal to a fresh model's."""
    robot = ff.load_robot(UR5)
    walked = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    target = UR5_START + 0.4 * (UR5_GOAL - UR5_START)
    first = fresh.distances(target).values
    for u in np.linspace(0.0, 1.0, 7):
        walked.distances(UR5_START + u * (UR5_GOAL - UR5_START))
    assert np.array_equal(walked.distances(target).values, first)
    assert np.array_equal(fresh.distances(target).values, first)


def test_a_mesh_file_changed_in_place_is_measured_anew(tmp_path):
    """The same path, new content (a notebook user edits a mesh and plans again): the solver's
    hull and verification's triangles are those of the new file (closed form: box faces)."""
    urdf = tmp_path / "u.urdf"
    urdf.write_text(_U_ROBOT)
    ball = Obstacle("ball", "sphere", (0.02,), (1.5, 0.05, 0.05))
    for width in (0.1, 0.3):  # the box spans x in [1, 1 + width] in the spacecraft frame
        write_stl(tmp_path / "u.stl", _box_triangles(np.zeros(3), np.array([width, 0.1, 0.1])))
        robot = ff.load_robot(urdf)
        k = CollisionModel(robot, None, [ball]).names.index("u_0 / obstacle:ball")
        truth = 1.5 - (1.0 + width) - 0.02  # the ball's centre faces the box's +x face
        solver = CollisionModel(robot, None, [ball]).distances(np.zeros(1)).values[k]
        assert solver == pytest.approx(truth, abs=1e-7)
        mesh = MeshClearance(robot, None, [ball])
        assert mesh.exact(mesh.placements(np.zeros(1)), k) == pytest.approx(truth, abs=1e-7)


@pytest.mark.parametrize("direction", ["farther", "nearer"])
def test_the_hull_agreement_catches_a_wrong_hull_on_any_body(direction):
    """UR5 servicer, quintic motion: the solver's figures of every pair holding one body are
    made 5 mm too large (a fake hull: more clearance than its mesh) or 5 mm beyond its slack
    too small (a hull of the wrong mesh), one body at a time; the agreement, which compares a
    few pairs at the smallest clearance's instant, catches every body's error (known by
    construction: the honest hull lies at most its slack below the mesh, never above) and
    passes the honest model."""
    robot = ff.load_robot(UR5)
    srdf = known_srdf(robot)
    mesh = MeshClearance(robot, srdf)
    solver = CollisionModel(robot, srdf)
    motion = quintic_motion(UR5_START, UR5_GOAL, 12.0)
    honest = certify(mesh, motion, 0.01, solver)
    assert honest.hull_excess <= 1e-6, honest.hull_detail
    slack = np.array([hull_slack(solver, i) for i in range(len(mesh.shapes))])
    first, second = mesh.first, mesh.second
    distances = solver.pair_distances
    bodies = sorted(set(first) | set(second))
    assert len(bodies) > 5
    for body in bodies:
        held = (first == body) | (second == body)
        error = 0.005 if direction == "farther" else -(slack[first] + slack[second] + 0.005)

        def wrong(joints, pairs, held=held, error=error):
            pairs = np.asarray(pairs, dtype=int)
            values = distances(joints, pairs).copy()
            wrong_pairs = held[pairs]
            values[wrong_pairs] += np.broadcast_to(error, held.shape)[pairs][wrong_pairs]
            return values

        solver.pair_distances = wrong  # type: ignore[method-assign]
        try:
            cert = certify(mesh, motion, 0.01, solver)
        finally:
            del solver.pair_distances
        assert cert.hull_excess > 1e-3, (direction, body, cert.hull_detail)  # fails its 1e-6 m
        assert cert.lower_bound == honest.lower_bound  # the mesh certificate is the solver's


def test_the_hull_agreement_compares_every_body_preferring_a_primitive_partner():
    """UR5 servicer at its start: with no pair measured, the pairs compared hold every body of
    a checked pair, and each mesh body that has a pair with a primitive (the spacecraft's box,
    the end-effector box; told here by the shapes' coal types) is compared through one."""
    robot = ff.load_robot(UR5)
    mesh = MeshClearance(robot, known_srdf(robot))
    placements = mesh.placements(UR5_START)
    pairs = compared(mesh, placements, set())
    held = {int(g) for k in pairs for g in mesh.pairs[k]}
    assert held == set(mesh.first.tolist()) | set(mesh.second.tolist())
    objects = mesh.geometry.geometryObjects
    primitive = {i for i, o in enumerate(objects) if not isinstance(o.geometry, coal.BVHModelBase)}
    assert primitive  # the box spacecraft and end effector
    for body in held - primitive:
        partners = {a if b == body else b for a, b in mesh.pairs if body in (a, b)}
        if partners & primitive:
            through = [mesh.pairs[k] for k in pairs if body in mesh.pairs[k]]
            assert any(set(p) & primitive for p in through), (objects[body].name, through)


def _moved_hull(obj: pin.GeometryObject, axis: int, move: float) -> coal.ConvexBase:
    """The true hull of ``obj``'s mesh with its vertices on the side facing +``axis`` (within
    8 mm of it) moved ``move`` (m) along that axis: in (negative) or out (positive)."""
    vertices, triangles = meshes.object_triangles(obj)
    vertices = vertices.copy()
    top = vertices[:, axis].max()
    vertices[vertices[:, axis] > top - 0.008, axis] += move
    return coal_hull(vertices, triangles)


@pytest.mark.parametrize("move", [-0.005, 0.005])
def test_a_hull_of_the_wrong_shape_is_caught_on_every_mesh_body(monkeypatch, move):
    """UR5 servicer: each mesh body's solver hull in turn is built with one side moved 5 mm in
    (a hull that misses part of its mesh) or out (a hull of more than its mesh). By
    construction a vertex then lies 5 mm from the other model's hull along the axis, so its
    distance outside it is in (0, 5 mm]; the shape comparison reports that much on that body
    whatever the configuration, and the honest hulls agree to rounding. One certificate shows
    the figure reaching the check."""
    robot = ff.load_robot(UR5)
    srdf = known_srdf(robot)
    mesh = MeshClearance(robot, srdf)
    assert shape_excess(mesh, CollisionModel(robot, srdf))[0] <= 1e-12
    bodies = [mesh.geometry.geometryObjects[i].name for i in mesh.meshes]
    assert len(bodies) >= 6
    honest = meshes.true_hull
    for body in bodies:
        for axis in range(3):

            def wrong(obj, key=None, body=body, axis=axis):
                return _moved_hull(obj, axis, move) if obj.name == body else honest(obj, key)

            monkeypatch.setattr(collision, "true_hull", wrong)
            excess, where = shape_excess(mesh, CollisionModel(robot, srdf))
            assert 0.5 * abs(move) < excess <= abs(move) + 1e-9, (body, axis, excess)
            assert where.startswith(body)
    motion = quintic_motion(UR5_START, UR5_GOAL, 12.0)
    cert = certify(mesh, motion, 0.01, CollisionModel(robot, srdf))  # the last body's
    assert 0.5 * abs(move) < cert.hull_excess <= abs(move) + 1e-9
    assert cert.hull_detail.startswith(bodies[-1])
