"""Second-order interval bounds of the clearance certificate (verify.taylor).

Truth never comes from the code under test: accelerations sampled densely along the
polynomials, finite differences of the bodies' vertices placed by Pinocchio in the frame of
the link both bodies hang from, coal's exact distances on the original meshes sampled densely
over each interval, and the certificate without these bounds.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.collision import Obstacle, known_srdf
from freefloat.verify import taylor as taylor_module
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import MeshClearance, Placed
from freefloat.verify.instants import Instants
from freefloat.verify.motion import PolynomialMotion
from freefloat.verify.taylor import IntervalTaylor

from conftest import ROOT, quintic_motion

UR5 = ROOT / "robots" / "ur5_servicer.urdf"
PANDA = ROOT / "robots" / "panda_servicer.urdf"
OBSTACLES = [
    Obstacle("ball", "sphere", (0.12,), (0.7, 0.4, 0.9)),
    Obstacle("post", "capsule", (0.05, 0.4), (0.9, -0.3, 0.9)),
    Obstacle("slab", "box", (0.2, 0.3, 0.05), (0.6, 0.0, 1.6)),
]


def test_acceleration_bounds_cover_dense_samples_and_are_tight():
    """Degree-7 polynomials, 40 random intervals: the bound is at least every |qdd| of 20,001
    samples and within 1e-6 (relative) of the largest."""
    rng = np.random.default_rng(3)
    duration = 5.0
    coefficients = rng.normal(size=(4, 8)) / np.array([1, 1, 1, 3, 9, 27, 81, 243])
    motion = PolynomialMotion.from_monomials(coefficients, duration)
    for _ in range(40):
        t0, t1 = np.sort(rng.uniform(0.0, duration, 2))
        ends = np.abs(np.concatenate([motion.path(np.array([t0]))[2], motion.path([t1])[2]]))
        bound = motion.acceleration_bounds(np.array([t0]), np.array([t1]), ends)[0]
        dense = np.abs(motion.path(np.linspace(t0, t1, 20001))[2]).max(axis=0)
        assert np.all(bound >= dense)
        assert np.all(bound <= dense * (1 + 1e-6) + 1e-12)


def _vertices(mesh: MeshClearance, i: int) -> np.ndarray:
    """Object i's vertices in its own frame (a mesh's own, a box's corners; m)."""
    if i in mesh.meshes:
        return mesh.meshes[i][0]
    half = np.asarray(mesh.shapes[i].halfSide, dtype=float)
    return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half


def _in_common_frame(mesh: MeshClearance, k: int, joints: np.ndarray) -> list[np.ndarray]:
    """Pair k's two bodies' vertices in the frame of the deepest joint moving both (m)."""
    robot, objects = mesh.robot, mesh.geometry.geometryObjects
    model, data = robot.model, robot.model.createData()
    q = robot.configuration(joints)
    pin.forwardKinematics(model, data, q)
    geometry_data = pin.GeometryData(mesh.geometry)
    pin.updateGeometryPlacements(model, data, mesh.geometry, geometry_data)
    pair = mesh.pairs[k]
    supports = [set(model.supports[objects[i].parentJoint]) for i in pair]
    shared = max(supports[0] & supports[1])
    frame = data.oMi[shared].inverse()
    out = []
    for i in pair:
        placed = frame * geometry_data.oMg[i]
        out.append(_vertices(mesh, i) @ placed.rotation.T + placed.translation)
    return out


@pytest.mark.parametrize(("seed", "steady"), [(0, False), (1, False), (2, True), (3, True)])
def test_points_accelerate_no_faster_than_the_spread(seed, steady):
    """UR5 servicer (meshes, the spacecraft box, a keep-out slab), random quintic motions and
    steady ones (every joint at a constant rate of about 1 rad/s: only the rates' products
    accelerate the points): the second differences of every vertex of both bodies of every
    mesh or box pair, in the frame of the link both hang from, stay within the spread of the
    interval."""
    robot = ff.load_robot(UR5)
    mesh = MeshClearance(robot, known_srdf(robot), OBSTACLES[2:])
    rng = np.random.default_rng(seed)
    start = rng.uniform(-1.5, 1.5, robot.n)
    if steady:
        rates = rng.choice([-1.0, 1.0], robot.n) * rng.uniform(0.8, 1.2, robot.n)
        motion = PolynomialMotion.from_monomials(np.stack([start, rates], axis=1), 6.0)
    else:
        motion = quintic_motion(start, start + rng.uniform(-1.5, 1.5, robot.n), 6.0)
    taylor = IntervalTaylor(Instants(mesh, motion))
    step = 1e-3
    checked = 0
    for _ in range(4):
        t0 = float(rng.uniform(0.5, 4.5))
        t1 = t0 + 1.0
        for k in range(len(mesh.pairs)):
            if not all(
                i in mesh.meshes or hasattr(mesh.shapes[i], "halfSide") for i in mesh.pairs[k]
            ):
                continue
            spread = taylor.spread(t0, t1, k)
            worst = 0.0
            for t in np.linspace(t0 + step, t1 - step, 5):
                before, here, after = (
                    _in_common_frame(mesh, k, motion.joints(float(s)))
                    for s in (t - step, t, t + step)
                )
                worst = max(
                    worst,
                    sum(
                        float(np.linalg.norm((b - 2 * h + a) / step**2, axis=1).max())
                        for b, h, a in zip(before, here, after, strict=True)
                    ),
                )
            assert worst <= spread * (1 + 1e-6) + 1e-6
            checked += 1
    assert checked > 40


def _sampled_minimum(
    mesh: MeshClearance, motion, t0: float, t1: float, samples: int = 41
) -> np.ndarray:
    """(P,) coal's exact distance of every pair, least over ``samples`` instants of [t0, t1]."""
    rows = []
    for t in np.linspace(t0, t1, samples):
        placed = Placed(mesh, mesh.placements(motion.joints(float(t))))
        rows.append([mesh.exact_placed(placed, k) for k in range(len(mesh.pairs))])
    return np.min(rows, axis=0)


@pytest.mark.parametrize(("urdf", "obstacles"), [(UR5, OBSTACLES), (PANDA, [])])
def test_the_interval_bound_never_exceeds_the_distance_in_it(urdf, obstacles):
    """Meshes, boxes, a sphere and a capsule; random quintic motions and intervals of 0.1 to
    3 s: every bound lies at or below coal's distance at 41 instants of its interval, most
    are given, and on 0.1 s intervals they lie within a millimetre of it (median)."""
    robot = ff.load_robot(urdf)
    mesh = MeshClearance(robot, known_srdf(robot), obstacles)
    rng = np.random.default_rng(7)
    given, total, gaps = 0, 0, []
    for _ in range(3):
        start = rng.uniform(-1.5, 1.5, robot.n)
        motion = quintic_motion(start, start + rng.uniform(-1.2, 1.2, robot.n), 10.0)
        store = Instants(mesh, motion)
        taylor = IntervalTaylor(store)
        for width in (0.1, 1.0, 3.0):
            t0 = float(rng.uniform(0.0, 10.0 - width))
            t1 = t0 + width
            truth = _sampled_minimum(mesh, motion, t0, t1)
            for k in range(len(mesh.pairs)):
                value = taylor.bound(t0, t1, k, taylor.spread(t0, t1, k))
                total += 1
                assert value <= truth[k]
                if math.isfinite(value):
                    given += 1
                    if width == 0.1:
                        gaps.append(truth[k] - value)
    assert given >= 0.7 * total
    assert np.median(gaps) < 1e-3


def test_the_certificate_with_them_halves_less_for_the_same_verdict(monkeypatch):
    """The shipped dual UR5 servicer's plan (a flat 3 cm box / mesh stretch): with the bounds
    the certificate halves fewer intervals, and with or without them it certifies, each
    certified bound at or below coal's distance of every pair at 201 instants."""
    from freefloat.verify.path_eval import file_path

    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml")
    path = file_path(ff.plan(s))
    motion = PolynomialMotion(path, path.duration, path.degree, path.positions)
    mesh = MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot))
    with_bounds = certify(mesh, motion, 0.01)
    with monkeypatch.context() as patch:
        patch.setattr(taylor_module.IntervalTaylor, "bound", lambda *args: -math.inf)
        without = certify(mesh, motion, 0.01)
    truth = float(_sampled_minimum(mesh, motion, 0.0, path.duration, 201).min())
    for found in (with_bounds, without):
        assert found.certified and found.lower_bound <= truth
    assert with_bounds.bisections < without.bisections
