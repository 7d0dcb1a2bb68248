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
from scipy.optimize import minimize_scalar

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


@pytest.mark.parametrize(("degree", "declared"), [(d, d) for d in range(7)] + [(4, 9), (2, 7)])
def test_acceleration_bounds_cover_dense_samples_and_are_tight(degree, declared):
    """Polynomials of degree 0 to 6 (some declared of a higher degree, zeros on top), 40
    random intervals: the bound is at least every |qdd| of 20,001 samples and within 1e-6
    (relative) of the largest."""
    rng = np.random.default_rng(3 + degree)
    duration = 5.0
    coefficients = np.zeros((4, declared + 1))
    to_unit = np.polynomial.Polynomial([-1.0, 2.0 / duration])  # t in [0, T] to [-1, 1]
    for row in coefficients:  # random on [-1, 1]: the extremes mostly inside
        found = np.polynomial.Polynomial(rng.normal(size=degree + 1))(to_unit).coef
        row[: len(found)] = found
    motion = PolynomialMotion.from_monomials(coefficients, duration)
    for _ in range(40):
        t0, t1 = np.sort(rng.uniform(0.0, duration, 2))
        ends = np.abs(np.concatenate([motion.path(np.array([t0]))[2], motion.path([t1])[2]]))
        bound = motion.acceleration_bounds(np.array([t0]), np.array([t1]), ends)[0]
        dense = np.abs(motion.path(np.linspace(t0, t1, 20001))[2]).max(axis=0)
        assert np.all(bound >= dense)
        assert np.all(bound <= dense * (1 + 1e-6) + 1e-12)


def _tree_urdf() -> str:
    """A spacecraft box, a torso joint both arms hang from, and per arm a revolute, a
    prismatic (inside its limits), a continuous joint on a tilted axis and a revolute with a
    turned origin; boxes and spheres, some off their link's origin and turned."""

    def box(size, xyz=(0, 0, 0), rpy=(0, 0, 0)):
        return (
            f'<collision><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} '
            f'{rpy[2]}"/><geometry><box size="{size[0]} {size[1]} {size[2]}"/></geometry>'
            "</collision>"
        )

    def sphere(radius, xyz):
        return (
            f'<collision><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}"/><geometry><sphere '
            f'radius="{radius}"/></geometry></collision>'
        )

    def link(name, collision=""):
        return (
            f'<link name="{name}"><inertial><origin xyz="0.1 0 0"/><mass value="2"/><inertia '
            f'ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>{collision}'
            "</link>"
        )

    def joint(name, parent, child, kind, axis, xyz, rpy=(0, 0, 0), limits=(-3, 3)):
        limit = (
            f'<limit lower="{limits[0]}" upper="{limits[1]}" effort="50" velocity="2"/>'
            if kind != "continuous"
            else '<limit effort="50" velocity="2"/>'
        )
        return (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child '
            f'link="{child}"/><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} '
            f'{rpy[1]} {rpy[2]}"/><axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>{limit}</joint>'
        )

    body = (
        '<link name="base"><inertial><mass value="100"/><inertia ixx="10" iyy="10" izz="10" '
        'ixy="0" ixz="0" iyz="0"/></inertial>' + box((0.6, 0.6, 0.6)) + "</link>"
    )
    body += joint("torso", "base", "torso_l", "revolute", (0, 0, 1), (0, 0, 0.35))
    body += link("torso_l", box((0.2, 0.2, 0.3), (0, 0, 0.15), (0.1, 0.2, 0.3)))
    # per arm: joint kind, axis, origin, turn of the origin, limits, the child's shape
    arm = [
        (
            "revolute",
            (0, 1, 0),
            None,
            (0, 0, 0),
            (-3, 3),
            box((0.4, 0.08, 0.08), (0.2, 0, 0), (0.3, 0, 0)),
        ),
        (
            "prismatic",
            (1, 0, 0),
            (0.4, 0, 0),
            (0, 0, 0),
            (-0.2, 0.3),
            box((0.3, 0.06, 0.06), (0.15, 0, 0)),
        ),
        (
            "continuous",
            (0, 0.6, 0.8),
            (0.3, 0, 0),
            (0, 0, 0),
            (-3, 3),
            sphere(0.07, (0.1, 0.05, 0)),
        ),
        (
            "revolute",
            (1, 0, 0),
            (0.15, 0, 0),
            (0.3, 0, 0.5),
            (-3, 3),
            box((0.05, 0.2, 0.05), (0, 0.1, 0), (0, 0, 0.4)),
        ),
    ]
    for side, y in (("L", 0.25), ("R", -0.25)):
        parent = "torso_l"
        for i, (kind, axis, xyz, rpy, limits, shape) in enumerate(arm, start=1):
            child = f"{side}_l{i}"
            origin = (0, y, 0.3) if xyz is None else xyz
            body += joint(f"{side}{i}", parent, child, kind, axis, origin, rpy, limits)
            body += link(child, shape)
            parent = child
    return f'<?xml version="1.0"?>\n<robot name="tree">{body}</robot>\n'


def _tree(tmp_path) -> ff.Robot:
    (tmp_path / "tree.urdf").write_text(_tree_urdf())
    return ff.load_robot(tmp_path / "tree.urdf", ["L_l4", "R_l4"])


def _inside_limits(robot: ff.Robot, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random start and goal (rad or m), the prismatic joints kept inside their limits."""
    start = rng.uniform(-1.5, 1.5, robot.n)
    goal = start + rng.uniform(-1.2, 1.2, robot.n)
    for i, j in enumerate(robot.joints):
        if j.kind == "prismatic":
            start[i], goal[i] = rng.uniform(j.lower, j.upper, 2)
    return start, goal


def _vertices(mesh: MeshClearance, i: int) -> np.ndarray:
    """Object i's vertices in its own frame (a mesh's own, a box's corners; a sphere's centre)."""
    if i in mesh.meshes:
        return mesh.meshes[i][0]
    if not hasattr(mesh.shapes[i], "halfSide"):
        return np.zeros((1, 3))
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


def _robot_and_model(name: str, tmp_path) -> tuple[ff.Robot, MeshClearance]:
    """The UR5 servicer with a keep-out slab, or the branched tree with three keep-out objects."""
    if name == "ur5":
        robot = ff.load_robot(UR5)
        return robot, MeshClearance(robot, known_srdf(robot), OBSTACLES[2:])
    robot = _tree(tmp_path)
    return robot, MeshClearance(robot, None, TREE_OBSTACLES)


TREE_OBSTACLES = [
    Obstacle("ball", "sphere", (0.1,), (0.6, 0.5, 0.6)),
    Obstacle("post", "capsule", (0.05, 0.4), (0.5, -0.4, 0.7), (0.4, 0.2, 0.0)),
    Obstacle("slab", "box", (0.3, 0.3, 0.04), (0.3, 0.0, 1.1), (0.0, 0.2, 0.1)),
]


@pytest.mark.parametrize(
    ("name", "seed", "steady"),
    [
        ("ur5", 0, False),
        ("ur5", 1, False),
        ("ur5", 2, True),
        ("ur5", 3, True),
        ("tree", 4, False),
        ("tree", 5, True),
    ],
)
def test_points_accelerate_no_faster_than_the_spread(tmp_path, name, seed, steady):
    """The UR5 servicer (meshes, the spacecraft box, a keep-out slab) and a branched tree (a
    joint both arms hang from, prismatic and continuous joints, boxes and spheres); random
    quintic motions and steady ones (every joint at a constant rate: only the rates' products
    accelerate the points): the second differences of every vertex (a sphere's centre) of
    both bodies of every pair without a capsule, in the frame of the link both hang from, stay
    within the spread of the interval."""
    robot, mesh = _robot_and_model(name, tmp_path)
    rng = np.random.default_rng(seed)
    start, goal = _inside_limits(robot, rng)
    if steady:  # about 1 rad/s, a prismatic joint across its range
        rates = rng.choice([-1.0, 1.0], robot.n) * rng.uniform(0.8, 1.2, robot.n)
        for i, j in enumerate(robot.joints):
            if j.kind == "prismatic":
                start[i], rates[i] = j.lower, (j.upper - j.lower) / 6.0
        motion = PolynomialMotion.from_monomials(np.stack([start, rates], axis=1), 6.0)
    else:
        motion = quintic_motion(start, goal, 6.0)
    taylor = IntervalTaylor(Instants(mesh, motion))
    step = 1e-3
    checked = 0
    for _ in range(4):
        t0 = float(rng.uniform(0.5, 4.5))
        t1 = t0 + 1.0
        for k in range(len(mesh.pairs)):
            if any(type(mesh.shapes[i]).__name__ == "Capsule" for i in mesh.pairs[k]):
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
    assert checked > 20


def _exact(mesh: MeshClearance, motion, t: float, k: int) -> float:
    """Coal's exact distance of pair k at ``t`` (s), on the original geometry (m)."""
    return mesh.exact_placed(Placed(mesh, mesh.placements(motion.joints(float(t)))), k)


def _sampled_minimum(
    mesh: MeshClearance, motion, t0: float, t1: float, samples: int = 41
) -> np.ndarray:
    """(P,) coal's exact distance of every pair, least over ``samples`` instants of [t0, t1]."""
    rows = []
    for t in np.linspace(t0, t1, samples):
        placed = Placed(mesh, mesh.placements(motion.joints(float(t))))
        rows.append([mesh.exact_placed(placed, k) for k in range(len(mesh.pairs))])
    return np.min(rows, axis=0)


def _refined_minimum(mesh: MeshClearance, motion, t0: float, t1: float, k: int) -> float:
    """Pair k's least distance over [t0, t1] (m): 41 samples, the least refined in time."""
    times = np.linspace(t0, t1, 41)
    values = [_exact(mesh, motion, t, k) for t in times]
    i = int(np.argmin(values))
    around = (times[max(i - 1, 0)], times[min(i + 1, 40)])
    found = minimize_scalar(
        lambda t: _exact(mesh, motion, t, k),
        bounds=around,
        method="bounded",
        options={"xatol": 1e-9},
    )
    return min(min(values), float(found.fun))


@pytest.mark.parametrize("name", ["ur5", "panda", "tree"])
def test_the_interval_bound_never_exceeds_the_distance_in_it(tmp_path, name):
    """Meshes, boxes, spheres and a capsule, a branched tree with prismatic and continuous
    joints; random quintic motions and intervals of 0.1 to 3 s: every bound lies at or below
    coal's distance at 41 instants of its interval (and, within 2 mm of it, below the least
    of those refined in time), most are given, and on 0.1 s intervals they lie within a
    millimetre of it (median)."""
    if name == "panda":
        robot = ff.load_robot(PANDA)
        mesh = MeshClearance(robot, known_srdf(robot))
    elif name == "ur5":
        robot = ff.load_robot(UR5)
        mesh = MeshClearance(robot, known_srdf(robot), OBSTACLES)
    else:
        robot, mesh = _robot_and_model("tree", tmp_path)
    rng = np.random.default_rng(7)
    given, total, gaps = 0, 0, []
    for _ in range(3):
        start, goal = _inside_limits(robot, rng)
        motion = quintic_motion(start, goal, 10.0)
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
                    if truth[k] - value < 2e-3:
                        assert value <= _refined_minimum(mesh, motion, t0, t1, k)
                    if width == 0.1:
                        gaps.append(truth[k] - value)
    assert given >= 0.6 * total
    assert np.median(gaps) < 1e-3


@pytest.mark.parametrize(("name", "seed"), [("ur5", 11), ("tree", 12)])
def test_certified_within_microns_of_the_truth_and_never_above_it(tmp_path, name, seed):
    """A random quintic motion certified at a margin 2 um below its least distance (every
    pair at 201 instants, the least refined in time): the certificate passes, and its bound
    lies at or below that least distance (a bound pushed 0.1 mm too high fails here)."""
    robot, mesh = _robot_and_model(name, tmp_path)
    rng = np.random.default_rng(seed)
    for _ in range(40):  # the first random motion clear of every collision (the bound claimed)
        motion = quintic_motion(*_inside_limits(robot, rng), 8.0)
        if _sampled_minimum(mesh, motion, 0.0, 8.0, 21).min() > 0.02:
            break
    sampled = _sampled_minimum(mesh, motion, 0.0, 8.0, 201)
    k = int(np.argmin(sampled))
    truth = min(float(sampled[k]), _refined_minimum(mesh, motion, 0.0, 8.0, k))
    assert truth > 0.01
    found = certify(mesh, motion, truth - 2e-6)
    assert found.certified
    assert found.lower_bound <= truth


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
