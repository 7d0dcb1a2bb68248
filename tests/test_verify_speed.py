"""The faster sampling and verification paths against the computations they replace.

Truth here never comes from the faster code: SciPy's DOP853 on the embedded configuration, the
replay's fifth-order method written out on numpy arrays (renormalised per stage), Pinocchio's
per-instant inverse dynamics, the quaternion rebuilt from
the Euler angles by SciPy, Pinocchio's momentum map for the planar yaw rate, STL triangles
read without coal (:mod:`geometry_truth`) for the leaf spheres' coverage, coal's exact mesh
distances for their bounds, and a certificate that measures every pair at many instants.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import freefloat as ff
from freefloat.physics.attitude import zyx_from_quat, zyx_from_quats
from freefloat.physics.dynamics import inverse_dynamics, inverse_dynamics_batch
from freefloat.physics.momentum import MomentumMap
from freefloat.physics.replay import replay
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.verify import certificate, first_pass
from freefloat.verify.certificate import certify
from freefloat.verify.clearance import ACCURACY, SLACK_FRACTION, MeshClearance
from freefloat.verify.motion import reach_coefficients
from freefloat.verify.sphere_tree import leaf_spheres

import urdfs
from conftest import ROOT, quintic_motion
from geometry_truth import world_meshes

UR5 = ROOT / "robots" / "ur5_servicer.urdf"
UR5_START = np.radians([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
UR5_GOAL = np.radians([57.3, -57.3, 68.8, -68.8, -57.3, 28.6])


#: Butcher's six-stage fifth-order method, written out here: a_ij, b_i, and each stage's
#: instant in quarters of the step.
_A = [[], [1 / 4], [1 / 8, 1 / 8], [0, -1 / 2, 1], [3 / 16, 0, 0, 9 / 16]]
_A.append([-3 / 7, 2 / 7, 12 / 7, -12 / 7, 8 / 7])
_B = [7 / 90, 0, 32 / 90, 12 / 90, 32 / 90, 7 / 90]
_QUARTER = [0, 1, 1, 2, 3, 4]


def _embedded(mmap):
    """``rate(q, v)`` of the embedded configuration and ``project(q)`` (unit quaternions)."""
    model, joints = mmap.model, mmap.robot.joints
    plain = [(j.idx_q, j.idx_v) for j in joints if j.kind != "continuous"]
    turning = [(j.idx_q, j.idx_v) for j in joints if j.kind == "continuous"]

    def rate(q, v):
        out = np.zeros(model.nq)
        x, y, z, w = q[3:7]
        vx, vy, vz, wx, wy, wz = v[:6]
        tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
        out[:7] = (
            vx + w * tx + y * tz - z * ty,
            vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx,
            0.5 * (w * wx + y * wz - z * wy),
            0.5 * (w * wy + z * wx - x * wz),
            0.5 * (w * wz + x * wy - y * wx),
            -0.5 * (x * wx + y * wy + z * wz),
        )
        for iq, iv in plain:
            out[iq] = v[iv]
        for iq, iv in turning:
            out[iq], out[iq + 1] = -q[iq + 1] * v[iv], q[iq] * v[iv]
        return out

    def project(q):
        q = np.array(q, dtype=float)
        x, y, z, w = q[3:7].tolist()
        q[3:7] /= math.sqrt(x * x + y * y + z * z + w * w)
        for iq, _ in turning:
            q[iq : iq + 2] /= np.hypot(q[iq], q[iq + 1])
        return q

    return rate, project


def _array_replay(mmap, start, quat, table, duration, steps):
    """The fifth-order method on the embedded configuration with numpy arrays, renormalised
    per stage; ``table``: torques at the quarters of the steps."""
    model, data = mmap.model, mmap.model.createData()
    rate, project = _embedded(mmap)
    q = mmap.configuration(np.asarray(start, float), np.asarray(quat, float))
    v = np.zeros(model.nv)
    forces = np.zeros((len(table), model.nv))
    forces[:, [j.idx_v for j in mmap.robot.joints]] = table
    for k, dt in enumerate(np.diff(np.linspace(0.0, duration, steps + 1)).tolist()):
        rates, accelerations = [], []
        for i, row in enumerate(_A):
            qi = project(q + dt * sum(a * r for a, r in zip(row, rates, strict=True)))
            vi = v + dt * sum(a * acc for a, acc in zip(row, accelerations, strict=True))
            accelerations.append(pin.aba(model, data, qi, vi, forces[4 * k + _QUARTER[i]]))
            rates.append(rate(qi, vi))
        q = project(q + dt * sum(b * r for b, r in zip(_B, rates, strict=True)))
        v = v + dt * sum(b * a for b, a in zip(_B, accelerations, strict=True))
    return q, v


def _dop853_replay(mmap, start, quat, torque, duration):
    """SciPy's DOP853 (rtol 1e-12) on the embedded configuration under ``torque(t)``."""
    model, data = mmap.model, mmap.model.createData()
    rate, _ = _embedded(mmap)
    columns = [j.idx_v for j in mmap.robot.joints]

    def rhs(t, y):
        q, v = y[: model.nq], y[model.nq :]
        force = np.zeros(model.nv)
        force[columns] = torque(t)
        return np.concatenate([rate(q, v), pin.aba(model, data, q, v, force)])

    q0 = mmap.configuration(np.asarray(start, float), np.asarray(quat, float))
    y0 = np.concatenate([q0, np.zeros(model.nv)])
    end = solve_ivp(rhs, (0.0, duration), y0, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
    q, v = end[: model.nq], end[model.nq :]
    q[3:7] /= np.linalg.norm(q[3:7])
    return q, v


@pytest.mark.parametrize(
    ("urdf", "newton_metres", "first"),
    [("planar_2dof.urdf", 1.0, 12), ("ur5_servicer.urdf", 0.1, 24)],
)
def test_the_replay_is_fifth_order_against_another_integrator(urdf, newton_metres, first):
    """Against SciPy's DOP853 (rtol 1e-12) on the embedded configuration: once the steps
    resolve the motion, the replay's error falls more than 20-fold per doubling (fifth order:
    32; fourth order would give 16) for the attitude, joints and rates alike;
    with revolute joints only (UR5) its joints and rates are those of the method written out
    on the embedded configuration with numpy arrays on the same steps, to rounding (the base
    pose does not enter ABA, and no renormalisation touches them)."""
    robot = ff.load_robot(ROOT / "robots" / urdf)
    mmap = MomentumMap(robot)
    rng = np.random.default_rng(3)
    duration = 2.0
    freq, phase = rng.uniform(0.5, 2.0, robot.n), rng.uniform(0, 3, robot.n)

    def torque(t):
        return newton_metres * np.sin(np.asarray(t)[..., None] * freq + phase)

    def table(steps):
        return torque(np.linspace(0.0, duration, 4 * steps + 1))

    start = rng.uniform(-1.0, 1.0, robot.n)
    quat = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9])
    q_ref, v_ref = _dop853_replay(mmap, start, quat, torque, duration)
    rates_ref = np.array([v_ref[j.idx_v] for j in robot.joints])
    errors = []
    for steps in (first, 2 * first):
        got = replay(mmap, start, quat, table(steps), duration, steps, track_momentum=False)
        errors.append(
            [
                ff.geodesic_angle(got.quaternion_xyzw, q_ref[3:7]),
                float(np.abs(got.joints - robot.joint_values(q_ref)).max()),
                float(np.abs(got.rates - rates_ref).max()),
            ]
        )
    coarse, fine = np.array(errors)
    assert np.all(coarse > 1e-11) and np.all(coarse < 1e-5)
    assert np.all(fine < coarse / 20.0)
    if urdf == "ur5_servicer.urdf":
        q, v = _array_replay(mmap, start, quat, table(12), duration, 12)
        got = replay(mmap, start, quat, table(12), duration, 12, track_momentum=False)
        np.testing.assert_allclose(got.joints, robot.joint_values(q), rtol=0, atol=1e-12)
        rates = np.array([v[j.idx_v] for j in robot.joints])
        np.testing.assert_allclose(got.rates, rates, rtol=0, atol=1e-12)
        assert ff.geodesic_angle(got.quaternion_xyzw, q[3:7]) < 1e-10


def test_a_replay_on_uneven_steps_agrees_with_even_steps():
    """``nodes`` (the public replay's uneven step ends, denser at the start): on 300 steps the
    same final state as 300 even steps, to what fifth order leaves (both against 2400)."""
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mmap = MomentumMap(robot)
    duration = 2.0
    freq = np.linspace(0.6, 1.6, robot.n)

    def torque(t: float) -> np.ndarray:
        return 0.1 * np.sin(freq * t)

    start, quat = np.linspace(-0.5, 0.5, robot.n), np.array([0.0, 0.0, 0.0, 1.0])
    fine = replay(mmap, start, quat, torque, duration, 2400, track_momentum=False)
    uneven = duration * np.linspace(0.0, 1.0, 301) ** 1.5
    runs = [
        replay(mmap, start, quat, torque, duration, 300, track_momentum=False, nodes=nodes)
        for nodes in (uneven, None)
    ]
    for got in runs:
        assert float(np.abs(got.joints - fine.joints).max()) < 1e-9
        assert ff.geodesic_angle(got.quaternion_xyzw, fine.quaternion_xyzw) < 1e-9
    assert not np.array_equal(runs[0].joints, runs[1].joints)  # the steps did differ


def test_a_replay_that_blows_up_says_so_quietly():
    """Torques far too large for the steps: the replay's state and attitude blow up to
    non-finite values (the verification then reports no verdict), without a warning on the
    user's terminal."""
    import warnings

    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mmap = MomentumMap(robot)
    steps, duration = 2, 10.0
    table = np.full((4 * steps + 1, robot.n), 1e6)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = replay(mmap, np.zeros(robot.n), quat, table, duration, steps, track_momentum=False)
    assert not np.all(np.isfinite(got.quaternion_xyzw)) or not np.all(np.isfinite(got.joints))


def test_kept_inverse_dynamics_are_pinocchios_per_instant_and_never_stale():
    """Asked twice, changed in place by a caller, then asked with other accelerations: every
    answer is Pinocchio's single-instant inverse dynamics of its own inputs."""
    robot = ff.load_robot(UR5)
    mmap = MomentumMap(robot)
    rng = np.random.default_rng(5)
    q, qd, qdd = (rng.uniform(-1.0, 1.0, (7, robot.n)) for _ in range(3))

    def truth(accelerations):
        return np.array(
            [inverse_dynamics(mmap, q[k], qd[k], accelerations[k]).tau for k in range(len(q))]
        )

    first = inverse_dynamics_batch(mmap, q, qd, qdd)
    np.testing.assert_allclose(first.tau, truth(qdd), rtol=1e-12, atol=1e-12)
    first.tau[:] = 0.0  # a caller writing into its answer
    again = inverse_dynamics_batch(mmap, q, qd, qdd)
    np.testing.assert_allclose(again.tau, truth(qdd), rtol=1e-12, atol=1e-12)
    other = qdd.copy()
    other[3, 2] += 0.5
    changed = inverse_dynamics_batch(mmap, q, qd, other)
    np.testing.assert_allclose(changed.tau, truth(other), rtol=1e-12, atol=1e-12)
    assert not np.allclose(changed.tau[3], again.tau[3])


def test_euler_angles_of_many_quaternions_rebuild_them():
    """SciPy's intrinsic ZYX rotation of the angles is the quaternion (up to sign), gimbal
    lock included; and each row is the single-quaternion function's (plain floats and the
    math module), to rounding; angles wrapped across +-pi as it wraps them."""
    rng = np.random.default_rng(11)
    quats = rng.normal(size=(50, 4))
    half = math.sqrt(0.5)
    quats = np.vstack([quats, [[0.0, half, 0.0, half], [0.0, -half, 0.0, half], [0, 0, 0, 1]]])
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    angles = zyx_from_quats(quats)
    rebuilt = Rotation.from_euler("ZYX", angles).as_quat()
    sign = np.sign(np.sum(rebuilt * quats, axis=1))[:, None]
    np.testing.assert_allclose(rebuilt * sign, quats, atol=1e-12)
    single = np.array([zyx_from_quat(q) for q in quats])
    assert np.abs(angles - single).max() <= 4e-16 * math.pi
    # On the seams, where the last bit of atan2 decides a side of the wrap at +-pi or the
    # gimbal-lock branch, the very row of the single-quaternion function: yaw and roll at
    # +-180 deg with pitches near and at the lock (SciPy's quaternions), and a quaternion whose
    # yaw lands within rounding of -pi.
    seams = [
        (a, b, c)
        for a in (180.0, -180.0)
        for b in (0.3, 89.9999, 90.0, -90.0)
        for c in (0.0, 180.0)
    ]
    on_seam = Rotation.from_euler("ZYX", seams, degrees=True).as_quat()
    on_seam = np.vstack(
        [
            on_seam,
            [-0.12941721901624123, 0.49438553896802095, 0.8563008720199357, 0.07471906623679953],
        ]
    )
    np.testing.assert_array_equal(zyx_from_quats(on_seam), [zyx_from_quat(q) for q in on_seam])
    assert np.all(np.abs(zyx_from_quats(rng.normal(size=(400, 4)) * 9.0)) <= math.pi)


def test_planar_sampled_attitudes_follow_pinocchios_momentum_map(worked_scenario):
    """The worked example's sampled attitudes (the identified planar map) against the same
    integration on Pinocchio's centroidal map at every node: equal to rounding."""
    problem = ff.problem_from_scenario(worked_scenario)
    assert problem.planar_map is not None
    beta = np.full(problem.n_free, 0.3)
    s = np.linspace(0.0, 1.0, 41)
    fast = problem.attitudes(beta, s)
    problem.planar_map, kept = None, problem.planar_map
    try:
        reference = problem.attitudes(beta, s)
    finally:
        problem.planar_map = kept
    np.testing.assert_allclose(fast, reference, atol=1e-13)
    assert not np.allclose(reference[0], reference[-1])  # the base does turn


def test_leaf_spheres_hold_every_triangle_of_the_stl_files():
    """Each triangle of every UR5 mesh, read from its STL file without coal, lies with its
    three corners in one leaf sphere (so in their union), placed by Pinocchio's kinematics."""
    robot = ff.load_robot(UR5)
    mesh = MeshClearance(robot, known_srdf(robot))
    solver = CollisionModel(robot, known_srdf(robot))
    joints = UR5_START + 0.3 * (UR5_GOAL - UR5_START)
    placements = mesh.placements(joints)
    triangles = world_meshes(solver, joints)
    assert triangles
    for g, corners in triangles.items():
        centres, radii = leaf_spheres(*mesh.meshes[g])
        world = centres @ placements[g, :3, :3].T + placements[g, :3, 3]
        # (F, 3 corners, L spheres): corner's distance to each centre
        gap = np.linalg.norm(corners[:, :, None, :] - world[None, None], axis=-1)
        inside = np.all(gap <= radii[None, None, :] + 1e-9, axis=1)
        assert inside.any(axis=1).all(), mesh.names


@pytest.mark.parametrize("name", ["ur5_servicer", "panda_servicer"])
def test_leaf_bounds_never_exceed_coals_mesh_distances(name):
    """At configurations along the shipped scenario's motion, every pair's leaf-sphere (and
    box) bound is at most coal's exact distance on the original geometry, and tighter than the
    single spheres' bound for some pairs (the certificate takes the larger of the two)."""
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    mesh = MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot))
    pairs = np.arange(len(mesh.pairs))
    tighter = 0
    for u in np.linspace(0.0, 1.0, 3):
        joints = np.asarray(s.start) + u * (np.asarray(s.goal) - np.asarray(s.start))
        placements = mesh.placements(joints)
        bound = mesh.leaves.bounds(placements[None], np.zeros_like(pairs), pairs)
        single = mesh.sphere_bounds(placements)
        exact = np.array([mesh.exact(placements, int(k)) for k in pairs])
        assert np.all(bound <= exact + 1e-9), [mesh.names[k] for k in np.flatnonzero(bound > exact)]
        tighter += int(np.sum(bound > single + 1e-3))
    assert tighter > 0


@pytest.mark.parametrize(("name", "instants"), [("panda_servicer", 101), ("ur5_servicer", 121)])
def test_the_culled_certificate_holds_against_every_pair_measured_densely(
    name, instants, monkeypatch
):
    """A shipped servicer's quintic motion: the certificate (leaf spheres cull pairs before any
    exact query, leaf pairs bound their own motion) bounds the smallest distance of every pair
    measured at many instants, agrees with the certificate of single spheres and whole-body
    speeds, and queries less or as much (the UR5's halvings: fewer)."""
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    mesh = MeshClearance(s.robot, s.safety.srdf or known_srdf(s.robot))
    motion = quintic_motion(np.asarray(s.start), np.asarray(s.goal), s.duration)
    counted = {"exact": 0}
    exact, exact_placed = mesh.exact, mesh.exact_placed

    def counting(placed, k):  # every exact query of the certificate goes through here
        counted["exact"] += 1
        return exact_placed(placed, k)

    mesh.exact_placed = counting  # type: ignore[method-assign]
    culled = certify(mesh, motion, 0.01)
    culled_queries = counted["exact"]
    counted["exact"] = 0
    with monkeypatch.context() as patch:  # the certificate as it was: whole bodies only
        patch.setattr(first_pass, "_tighten", lambda *args: None)
        patch.setattr(certificate, "_leaf_value", lambda *args, **kwargs: -math.inf)
        plain = certify(mesh, motion, 0.01)
    plain_queries = counted["exact"]
    mesh.exact_placed = exact_placed  # type: ignore[method-assign]
    assert culled_queries > 0
    dense = min(
        exact(mesh.placements(joints), k)
        for joints in motion.path(np.linspace(0.0, motion.duration, instants))[0]
        for k in range(len(mesh.pairs))
    )
    assert culled.lower_bound <= dense + 1e-12
    accuracy = max(ACCURACY, SLACK_FRACTION * (culled.measured - 0.01))
    assert culled.measured - culled.lower_bound <= accuracy + 1e-12
    assert culled.certified == plain.certified
    assert culled.pair == plain.pair
    assert culled.measured == pytest.approx(plain.measured, abs=1e-4)
    assert culled_queries <= plain_queries
    assert culled.bisections <= plain.bisections


def test_leaf_speed_bounds_hold_for_every_vertex_they_hold():
    """UR5: every mesh vertex inside a leaf sphere moves (finite differences of Pinocchio's
    kinematics) no faster than that leaf's reach times the joint rates."""
    robot = ff.load_robot(UR5)
    mesh = MeshClearance(robot, known_srdf(robot))
    leaves = mesh.leaves
    reach = reach_coefficients(robot, mesh.geometry, leaves.local, leaves.radii, leaves.owner)
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(4):
        joints, rates = rng.uniform(-2.0, 2.0, robot.n), rng.uniform(-1.0, 1.0, robot.n)
        dt = 1e-7
        before, after = mesh.placements(joints), mesh.placements(joints + dt * rates)
        for leaf, g in enumerate(leaves.owner.tolist()):
            if g not in mesh.meshes:
                continue
            vertices = mesh.meshes[g][0]
            near = np.linalg.norm(vertices - leaves.local[leaf], axis=1) <= leaves.radii[leaf]
            points = vertices[near]
            moved = [p[g, :3, :3] @ points.T + p[g, :3, 3:] for p in (before, after)]
            speed = np.linalg.norm(moved[1] - moved[0], axis=0).max() / dt
            assert speed <= reach[:, leaf] @ np.abs(rates) * (1 + 1e-5) + 1e-9
            checked += 1
    assert checked > 20


def test_shared_path_dynamics_are_pinocchios_per_instant(worked_scenario, worked_plan):
    """The replay's torques and the attitude check's base rates, shared per instant, are
    Pinocchio's single-instant inverse dynamics and the base rate of zero total momentum along
    the file's paths, whichever check asked first; instants asked again are the rows kept."""
    from freefloat.verify.along import PathDynamics
    from freefloat.verify.path_eval import file_path

    mmap = MomentumMap(worked_scenario.robot)
    path = file_path(worked_plan)
    shared = PathDynamics(mmap, path)
    coarse = np.linspace(0.0, worked_plan.duration, 9)
    fine = np.linspace(0.0, worked_plan.duration, 17)  # holds every coarse instant, to the bit
    tau = shared.torques(coarse)
    omega = shared.omega(fine)  # the coarse ones from the torques' batch, the rest anew
    q, qd, qdd = path(fine)
    truth_tau = np.array([inverse_dynamics(mmap, q[k], qd[k], qdd[k]).tau for k in range(0, 17, 2)])
    np.testing.assert_allclose(tau, truth_tau, rtol=1e-12, atol=1e-12)
    # Truth for the base rate: zero total momentum, Pinocchio's centroidal map solved here
    # for the base twist (base at the identity) at each instant.
    model, data = mmap.model, mmap.model.createData()
    robot = worked_scenario.robot
    for k in range(17):
        ag = pin.computeCentroidalMap(model, data, robot.configuration(q[k]))
        twist = -np.linalg.lstsq(ag[:, :6], ag[:, 6:] @ qd[k], rcond=None)[0]
        np.testing.assert_allclose(omega[k], twist[3:], rtol=1e-10, atol=1e-12)
    assert np.array_equal(shared.torques(fine[::2]), tau)


def test_batched_torques_are_pinocchios_rnea_per_instant_for_every_joint_kind(tmp_path):
    """The batch's one RNEA call over all instants gives, to rounding, Pinocchio's single-instant
    RNEA at each instant's configuration, velocity and acceleration, rebuilt here: the base
    twist and acceleration of zero momentum solved from Pinocchio's centroidal map and its
    time variation, on an arm whose joints are continuous (cos, sin in the configuration),
    prismatic and revolute."""
    path = tmp_path / "mixed.urdf"
    path.write_text(urdfs.spatial_arm(kinds=("continuous", "prismatic", "revolute")))
    robot = ff.load_robot(path)
    mmap = MomentumMap(robot)
    rng = np.random.default_rng(11)
    q, qd, qdd = (rng.uniform(-0.2, 0.2, (9, robot.n)) for _ in range(3))
    batch = inverse_dynamics_batch(mmap, q, qd, qdd)
    model, data = mmap.model, mmap.model.createData()
    for k in range(len(q)):
        config = robot.configuration(q[k])
        ag = pin.computeCentroidalMap(model, data, config).copy()
        twist = -np.linalg.solve(ag[:, :6], ag[:, 6:] @ qd[k])
        v = np.concatenate([twist, qd[k]])
        d_ag = pin.computeCentroidalMapTimeVariation(model, data, config, v)
        a_base = -np.linalg.solve(ag[:, :6], ag[:, 6:] @ qdd[k] + d_ag @ v)
        full = pin.rnea(model, data, config, v, np.concatenate([a_base, qdd[k]]))
        np.testing.assert_allclose(batch.tau[k], full[6:], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(batch.base_wrench[k], full[:6], rtol=0, atol=1e-9)
    assert np.abs(batch.base_wrench).max() < 1e-9 * max(1.0, np.abs(batch.tau).max())
