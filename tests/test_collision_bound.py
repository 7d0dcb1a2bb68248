"""The bound that spares distance queries: its weights, its truth, and that plans do not change.

Truth here: the weights' closed form (lever arms read off the URDF by hand), every pair's
distance measured afresh (no pair spared), and plans made with every pair measured.
"""

from __future__ import annotations

import dataclasses
import math

import coal
import numpy as np
import pytest

import freefloat as ff
import freefloat.robot.pair_queries as pair_queries
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.robot.motion_bound import BOUND_SLACK

from conftest import ROOT
from test_collision import sphere_arm, ur5_pan_scenario  # noqa: F401 (fixture)

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"
UR5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"


def test_the_weights_of_the_sphere_arm_are_its_lever_arms(sphere_arm):  # noqa: F811
    """The sphere (r 0.1 m, 0.6 m beyond joint 2, which is 1.0 m beyond joint 1) against the
    spacecraft: 1.0 + 0.6 + 0.1 m per rad of joint 1, 0.6 + 0.1 m per rad of joint 2."""
    model = CollisionModel(sphere_arm)
    assert model.n_pairs == 1
    assert np.allclose(model._weights, [[1.7, 0.7]], atol=1e-12)


def test_the_bound_holds_between_any_two_configurations():
    """|d(q) - d(q')| <= weights @ |q - q'| for every pair, measured on the Panda servicer."""
    scenario = ff.Scenario.from_toml(PANDA)
    robot = scenario.robot
    model = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(7)
    lower = np.array([max(j.lower, -math.pi) for j in robot.joints])
    upper = np.array([min(j.upper, math.pi) for j in robot.joints])
    tight = 0
    for _ in range(12):
        q = rng.uniform(lower, upper)
        q2 = np.clip(q + rng.normal(0.0, 0.2, robot.n), lower, upper)
        change = np.abs(model.distances(q).values - model.distances(q2).values)
        bound = model._weights @ np.abs(q - q2)
        assert np.all(change <= bound + BOUND_SLACK)
        tight = max(tight, float(np.max(change / np.maximum(bound, 1e-12))))
    assert tight > 0.05  # the bound is not vacuous: some pair moves a fair part of it


@pytest.mark.parametrize("slotted", [False, True])
@pytest.mark.parametrize("path", [PANDA, UR5])
def test_the_closest_pair_is_the_same_bits_as_with_every_pair_measured(path, slotted):
    """After any history of queries (in one slot, or in slots they come back to), the smallest
    distance, its pair and its gradient are those of a fresh model that measures every pair."""
    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    walked = CollisionModel(robot, known_srdf(robot))
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    rng = np.random.default_rng(3)
    for u in rng.uniform(0.0, 1.0, 30):
        joints = start + u * (goal - start) + rng.normal(0.0, 0.05, robot.n)
        slot = float(round(u, 1)) if slotted else None
        value, gradient, pair = walked.closest(joints, slot)
        fresh = CollisionModel(robot, known_srdf(robot)).distances(joints, gradients=True)
        k = int(np.argmin(fresh.values))
        assert (value, pair) == (float(fresh.values[k]), k)
        assert np.array_equal(gradient, fresh.gradients[k])


def _everything(monkeypatch: pytest.MonkeyPatch) -> None:
    """No bound: pairs spared by their bounding spheres alone (the model before the bound)."""
    monkeypatch.setattr(pair_queries, "motion_weights", lambda *args: None)


def _pan(tmp_path):  # type: ignore[no-untyped-def]
    """A plan where clearance binds: the UR5 pan whose quintic path enters the hull."""
    return lambda: ur5_pan_scenario(tmp_path)


@pytest.mark.parametrize("case", ["panda", "ur5", pytest.param("pan", marks=pytest.mark.slow)])
def test_plans_are_the_same_bits_with_every_pair_measured(case, monkeypatch, tmp_path):
    scenario = {
        "panda": lambda: ff.Scenario.from_toml(PANDA),
        "ur5": lambda: ff.Scenario.from_toml(UR5),
        "pan": _pan(tmp_path),
    }[case]
    bounded = ff.plan(scenario())
    calls = []
    _everything(monkeypatch)
    original = CollisionModel._spheres
    monkeypatch.setattr(
        CollisionModel, "_spheres", lambda self, p: calls.append(len(p)) or original(self, p)
    )
    measured = ff.plan(scenario())
    assert calls  # the spheres-only model did the measuring
    t = np.linspace(0.0, bounded.duration, 101)
    assert np.array_equal(bounded.path().evaluate(t).q, measured.path().evaluate(t).q)
    assert bounded.solver.solutions == measured.solver.solutions


def test_each_caller_gets_its_own_geometry():
    """The URDF is parsed once, but a caller that changes its geometry model changes no
    other caller's (the solver's model replaces meshes by hulls, verification keeps them)."""
    from freefloat.robot.geometry import load_collision_geometry

    robot = ff.Scenario.from_toml(UR5).robot
    first, second = load_collision_geometry(robot), load_collision_geometry(robot)
    mesh = next(
        i for i, o in enumerate(first.geometryObjects) if isinstance(o.geometry, coal.BVHModelBase)
    )
    first.geometryObjects[mesh].geometry.buildConvexHull(True, "Qt")
    assert first.geometryObjects[mesh].geometry.convex is not None
    assert second.geometryObjects[mesh].geometry.convex is None
    first.addGeometryObject(first.geometryObjects[0].copy())
    assert len(second.geometryObjects) == len(first.geometryObjects) - 1


def test_rate_bounds_hold_and_are_tight_against_dense_samples():
    """Every |qd_j| sampled densely inside each interval is within its bound, and the bound
    of a short interval is within a few per cent of the largest sample."""
    from freefloat.problem.rate_bounds import rate_bounds

    scenario = ff.Scenario.from_toml(PANDA)
    problem = ff.problem_from_scenario(scenario, extra=[2] * scenario.robot.n)
    beta = np.random.default_rng(5).normal(0.0, 0.05, problem.n_free)
    path = problem.polynomials(beta)
    edges = np.linspace(0.0, path.duration, 26)
    bounds = rate_bounds(path, edges[:-1], edges[1:])
    for k in range(25):
        inside = np.linspace(edges[k], edges[k + 1], 200)
        sampled = np.abs(path.evaluate(inside).qd).max(axis=0)
        assert np.all(sampled <= bounds[k])
        assert np.all(bounds[k] <= 1.25 * sampled + 0.02 * sampled.max())


@pytest.mark.parametrize("path", [PANDA, UR5])
def test_the_per_pair_bound_between_samples_holds_against_every_pair_measured_densely(path):
    """Between two samples, the clearance is at least the per-pair bound (each pair from its
    own bounds at both ends and its own motion): checked against every pair measured by a
    fresh model at 40 instants inside each interval (brute force). It is never looser than
    the bound from the smallest distances and the fastest pair, and tighter on some."""
    from freefloat.problem.constraints.clearance_samples import bounds_between, lever_arms
    from freefloat.problem.rate_bounds import rate_bounds

    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    model = CollisionModel(robot, known_srdf(robot))
    fresh = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(21)
    tighter = 0
    for scale in (0.0, 0.3):
        poly = problem.polynomials(rng.normal(0.0, scale, problem.n_free))
        edges = np.linspace(0.0, poly.duration, 21)
        q = poly.evaluate(edges).q
        found, arms = model.closest_many(q, edges / poly.duration), lever_arms(model, q)
        t0, t1 = edges[:-1], edges[1:]
        ends = (found.lower[:-1], found.lower[1:])
        bound = bounds_between(model, poly, (t0, t1), ends, (arms[:-1], arms[1:]))
        speed = np.max(rate_bounds(poly, t0, t1) @ model.weights.T, axis=1)
        former = 0.5 * (found.values[:-1] + found.values[1:] - speed * (t1 - t0)) - BOUND_SLACK
        assert np.all(bound >= former)
        tighter += int(np.sum(bound > former + 1e-3))
        for k in range(20):
            inside = poly.evaluate(np.linspace(t0[k], t1[k], 40)).q
            dense = min(float(fresh.distances(q).values.min()) for q in inside)
            assert dense >= bound[k]
    assert tighter > 0


@pytest.mark.parametrize("path", [PANDA, UR5])
def test_the_dense_check_does_not_depend_on_earlier_queries(path):
    """The same path checked by a fresh model and by one that answered other queries first
    (at the same instants, on other paths): the same samples, pair bounds, lower bound and
    verdict, to the bit."""
    from freefloat.problem.constraints.clearance import Clearance

    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    rng = np.random.default_rng(17)
    beta = rng.normal(0.0, 0.3, problem.n_free)
    walked = CollisionModel(robot, known_srdf(robot))
    for _ in range(3):
        other = problem.polynomials(beta + rng.normal(0.0, 0.1, problem.n_free))
        t = np.linspace(0.0, other.duration, 201)
        walked.closest_many(other.evaluate(t).q, t / other.duration)
    answers = []
    for model in (CollisionModel(robot, known_srdf(robot)), walked):
        check = Clearance(model, 0.0)
        measured = check._measured(problem.polynomials(beta), 201, 0.0)
        violation = check.violation(problem, beta)
        answers.append((measured.known.tobytes(), measured.lower.tobytes(), measured.bound))
        answers[-1] += (violation.value, violation.detail)
    assert answers[0] == answers[1]


def test_the_dense_checks_decision_is_that_of_the_refined_minimum():
    """The solvers' check decides from a bound where it can: on paths near and far from the
    margin, it breaks exactly when the refined smallest clearance (every sample measured,
    every near-minimum refined) is below the margin."""
    from freefloat.problem.constraints.clearance import Clearance

    scenario = ff.Scenario.from_toml(UR5)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    model = CollisionModel(robot, known_srdf(robot))
    everything = CollisionModel(robot, known_srdf(robot))
    everything._weights = None  # the truth: every sample measured, no bound between them
    rng = np.random.default_rng(9)
    decided = 0
    for scale in (0.0, 0.2, 0.5, 1.0, 2.0):
        beta = rng.normal(0.0, scale, problem.n_free)
        smallest = Clearance(everything, 0.01).smallest(problem.polynomials(beta), 201)[0]
        for margin in (0.005, 0.01, smallest - 1e-3, smallest + 1e-3):
            if margin < 0.0:
                continue
            check = Clearance(model, margin)
            excess = check.violation(problem, beta)
            assert (excess.value > check.tolerance) == (smallest < margin - check.tolerance)
            decided += excess.detail.startswith("min clearance >=")
    assert decided > 0  # the bound decided some, without the refined minimum


@pytest.mark.parametrize("path", [PANDA, UR5])
def test_the_smallest_clearance_is_the_same_bits_with_every_sample_measured(path):
    """Samples spared by the bound change neither the smallest clearance, nor its time, nor
    its pair (every sample measured and every near-minimum refined, by a model without the
    bound)."""
    from freefloat.problem.constraints.clearance import Clearance

    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    bounded = Clearance(CollisionModel(robot, known_srdf(robot)))
    everything = CollisionModel(robot, known_srdf(robot))
    everything._weights = None
    unbounded = Clearance(everything)
    rng = np.random.default_rng(13)
    spared = 0
    for scale in (0.0, 0.1, 0.3, 1.0):
        polynomials = problem.polynomials(rng.normal(0.0, scale, problem.n_free))
        assert bounded.smallest(polynomials, 201) == unbounded.smallest(polynomials, 201)
        spared += int(np.isnan(bounded._measured_memo[1].known).sum())
    assert spared > 0  # the bound spared some samples


def test_a_path_crossing_a_plate_between_samples_is_never_planned(tmp_path, monkeypatch):
    """A 2 mm ball on a planar arm whose plain path crosses a 2 mm plate between two of the
    dense check's samples, where every sample is clear (closed form): the planner either
    returns a path clear of the plate at every instant (closed form, densely) or refuses
    because the quintic breaks clearance on the plate, and then plans the same request once
    the plate is gone. (The motion lasts 3 s: 1 s broke q1's velocity limit before any
    clearance was checked.)"""
    from test_collision import SPHERE_ARM, _sphere_centre

    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    urdf = tmp_path / "sphere_arm.urdf"
    urdf.write_text(SPHERE_ARM.replace('radius="0.1"', 'radius="0.002"'))
    duration, start, goal = 3.0, np.array([-1.5, 0.0]), np.array([1.5, 0.0])  # q1 <= 2 rad/s
    s = np.linspace(0.0, 1.0, 201)
    angles = start[0] + (goal[0] - start[0]) * (10 * s**3 - 15 * s**4 + 6 * s**5)
    k = int(np.argmax(np.diff(angles)))
    crossing = 0.5 * (angles[k] + angles[k + 1])
    centre = np.array([0.5 + 1.6 * math.cos(crossing), 1.6 * math.sin(crossing), 0.0])
    assert np.min(1.6 * np.abs(np.sin(angles - crossing)) - 0.003) > 0.0  # samples clear
    body = (
        f'robot = "{urdf}"\nduration = {duration}\n'
        "[start]\njoints = { q1 = -85.94366926962348, q2 = 0.0 }\n"
        "[goal]\njoints = { q1 = 85.94366926962348, q2 = 0.0 }\n"
        "[safety]\nmargin_m = 0.0\n"
        '[[obstacles]]\nname = "plate"\nbox = [2.0, 0.002, 0.5]\n'
        f"xyz = [{float(centre[0])!r}, {float(centre[1])!r}, 0.0]\n"
        f"rpy_deg = [0.0, 0.0, {math.degrees(float(crossing))!r}]\n"
    )
    path = tmp_path / "plate.toml"
    path.write_text(body)
    scenario = ff.Scenario.from_toml(path)
    quintic = ff.problem_from_scenario(scenario, extra=[1, 0], check_bounds=False)
    scenario = dataclasses.replace(scenario, goal_attitude=quintic.achieved(np.zeros(1)))
    try:
        plan = ff.plan(scenario)
    except ff.SolverError as error:  # refused for the plate, not for anything else:
        assert "the quintic path breaks clearance" in str(error) and "plate" in str(error)
        clear = ff.Scenario.from_toml(path.write_text(body.split("[[obstacles]]")[0]) and path)
        ff.plan(dataclasses.replace(clear, goal_attitude=scenario.goal_attitude))  # plans
        return
    rotation = np.array(
        [[math.cos(crossing), -math.sin(crossing)], [math.sin(crossing), math.cos(crossing)]]
    )
    worst = math.inf
    for q in plan.joint_positions(np.linspace(0.0, duration, 4001)):
        local = rotation.T @ (_sphere_centre(*q)[:2] - centre[:2])
        outside = np.maximum(np.abs(local) - np.array([1.0, 0.001]), 0.0)
        worst = min(worst, float(np.linalg.norm(outside)) - 0.002)
    assert worst >= -1e-9  # planned: clear of the plate at every instant (closed form)


def test_a_plan_files_positions_alone_are_those_of_the_whole_evaluation():
    """The certificate's halving asks for joint values one instant at a time: the values alone
    are the same bits as the first of the values, rates and accelerations."""
    from freefloat.verify.path_eval import file_path

    plan = ff.plan(ff.Scenario.from_toml(UR5))
    path = file_path(plan)
    t = np.linspace(0.0, plan.duration, 37)
    assert np.array_equal(path.positions(t), path(t)[0])
    assert all(np.array_equal(path.positions(t[k : k + 1]), path(t[k : k + 1])[0]) for k in (0, 5))


class _Dip:
    """A fake collision model along one joint: clearance ``margin - 1 mm + min(|q - q0|, cap)``
    (m), its minimum exactly halfway between two of 201 samples of ``q = t`` over 1 s.

    With ``weights`` None it gives no bound between samples (as with a prismatic joint); with
    a weight of 1 m/rad the clearance changes at most 1 m per rad (true: slope 0 or 1).
    """

    n_pairs, names, levers = 1, ["a-b"], None

    def __init__(self, margin: float, cap: float, weights: np.ndarray | None) -> None:
        self.margin, self.cap, self.weights = margin, cap, weights
        self.rows = 0  # configurations asked about

    def values(self, q: np.ndarray) -> np.ndarray:
        """The clearance (m) at joint values ``q`` (rad)."""
        return self.margin - 1e-3 + np.minimum(np.abs(q - 100.5 / 200), self.cap)

    def closest_value(self, joints: np.ndarray, slot: float | None = None) -> tuple[float, int]:
        self.rows += 1
        return float(self.values(np.asarray(joints, float)[:1])[0]), 0

    def own_bounds(self):
        import contextlib

        return contextlib.nullcontext()

    def closest_many(self, joints: np.ndarray, slots=None):
        from freefloat.robot.collision import Closest

        values = self.values(np.asarray(joints, float)[:, 0])
        self.rows += len(values)
        return Closest(values, np.zeros(len(values), dtype=int), None, values[:, None])


class _OnePath:
    def __init__(self, path) -> None:
        self.path = path

    def polynomials(self, beta):
        return self.path


@pytest.mark.parametrize(
    ("cap", "weights"),
    [(0.5, None), (0.003, None), (0.5, np.array([[1.0]])), (0.003, np.array([[1.0]]))],
    ids=["no-bound", "no-bound-near", "bound", "bound-near-everywhere"],
)
def test_a_dip_below_the_margin_between_samples_is_found_whatever_was_asked_before(cap, weights):
    """Closed form: the clearance's minimum is margin - 1 mm, between samples 100 and 101.

    Whether every sample ends up measured (the clearance near the margin all along, or no bound
    between samples) or not, and whatever was asked about the path before, the solvers' check
    says the path breaks the margin by 1 mm.
    """
    from freefloat.problem.constraints.clearance import Clearance
    from freefloat.problem.paths import JointPolynomials

    margin = 0.01
    path = JointPolynomials.from_monomials([[0.0, 1.0]], 1.0)
    for first in ("violation", "smallest"):
        check = Clearance(_Dip(margin, cap, weights), margin)
        if first == "smallest":
            assert check.smallest(path, 201)[0] == pytest.approx(margin - 1e-3, abs=1e-8)
        for _ in range(2):
            value = check.violation(_OnePath(path), np.zeros(1)).value
            assert value == pytest.approx(1e-3, abs=1e-8), (first, value)


@pytest.mark.parametrize("weights", [None, np.array([[1.0]])], ids=["no-bound", "bound"])
def test_a_dip_below_the_margin_is_the_instant_a_solver_adds(weights):
    """Closed form (:class:`_Dip`): the path dips 1 mm below the margin at t = 100.5 / 200 s,
    between two of the dense check's samples; that is the clearance's critical time, and a
    margin 2 mm lower, which the path keeps, has none."""
    from freefloat.problem.constraints.clearance import Clearance
    from freefloat.problem.paths import JointPolynomials

    margin = 0.01
    path = JointPolynomials.from_monomials([[0.0, 1.0]], 1.0)
    broken = Clearance(_Dip(margin, 0.5, weights), margin)
    assert broken.violation(_OnePath(path), np.zeros(1)).value == pytest.approx(1e-3, abs=1e-8)
    times = broken.critical_times(None, path)
    assert times.shape == (1,) and times[0] == pytest.approx(100.5 / 200, abs=1e-6)
    kept = Clearance(_Dip(margin, 0.5, weights), margin - 2e-3)
    assert kept.critical_times(None, path).shape == (0,)


def test_clearance_rows_sit_at_the_instants_a_solver_adds():
    """A row at an instant off the grid: its value is the margin and slack less the smallest
    distance of every pair measured in one pass (no pair spared), and its gradient that of
    this distance by central differences in beta."""
    from freefloat.problem.constraints import DEFAULT_INSTANTS
    from freefloat.problem.constraints.clearance import SOLVER_SLACK, Clearance

    scenario = ff.Scenario.from_toml(UR5)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    model = CollisionModel(robot, known_srdf(robot))
    check = Clearance(model, 0.01)
    beta = np.random.default_rng(21).normal(0.0, 0.3, problem.n_free)
    added = 0.4937
    assert not np.any(np.isclose(DEFAULT_INSTANTS, added))
    plain = check.rows(problem, beta)
    more = check.rows(problem, beta, np.append(DEFAULT_INSTANTS, added))
    assert len(more.values) == len(plain.values) + 1
    np.testing.assert_array_equal(more.values[:-1], plain.values)

    truth = CollisionModel(robot, known_srdf(robot))

    def smallest(b: np.ndarray) -> float:
        q = problem.polynomials(b).evaluate(np.array([added * problem.duration])).q[0]
        return float(truth.distances(q).values.min())

    assert more.values[-1] == pytest.approx(0.01 + SOLVER_SLACK - smallest(beta), abs=1e-9)
    h = 1e-6
    steps = np.eye(problem.n_free) * h
    numeric = [-(smallest(beta + e) - smallest(beta - e)) / (2 * h) for e in steps]
    scale = max(1.0, float(np.abs(numeric).max()))
    np.testing.assert_allclose(more.jacobian[-1], numeric, rtol=0.0, atol=1e-5 * scale)


class _DipProblem(_OnePath):
    """The one path of :class:`_OnePath` as a problem over 1 s (no robot needed)."""

    robot, duration = None, 1.0


def test_the_solvers_impose_a_dip_on_clearance_alone_each_dip_once():
    """``with_dips`` adds the closed-form dip (t = 100.5 / 200 of 1 s) once however often it
    is found, and nothing for a path that keeps the margin; ``rows_instants`` asks clearance
    at its own grid and the dips only, every other constraint at the solver's instants."""
    from freefloat.problem.constraints import DEFAULT_INSTANTS, JointPositionLimits
    from freefloat.problem.constraints.clearance import Clearance
    from freefloat.problem.paths import JointPolynomials
    from freefloat.solvers.rows import NO_DIPS, rows_instants, with_dips

    margin = 0.01
    problem = _DipProblem(JointPolynomials.from_monomials([[0.0, 1.0]], 1.0))
    broken = Clearance(_Dip(margin, 0.5, np.array([[1.0]])), margin)
    limits = JointPositionLimits()
    dips = with_dips(problem, [limits, broken], np.zeros(1), NO_DIPS)
    assert dips.shape == (1,) and dips[0] == pytest.approx(100.5 / 200, abs=1e-6)
    again = with_dips(problem, [broken], np.zeros(1), np.array([0.25, *dips]))
    np.testing.assert_array_equal(again, [0.25, dips[0]])  # in the order found, each once
    kept = Clearance(_Dip(margin, 0.5, np.array([[1.0]])), margin - 2e-3)
    assert with_dips(problem, [kept], np.zeros(1), NO_DIPS).shape == (0,)
    asked = np.array([0.0, 0.3141, 1.0])
    np.testing.assert_array_equal(rows_instants(limits, asked, dips), asked)
    np.testing.assert_array_equal(rows_instants(broken, asked, NO_DIPS), DEFAULT_INSTANTS)
    np.testing.assert_array_equal(
        rows_instants(broken, asked, dips), np.union1d(DEFAULT_INSTANTS, dips)
    )


def test_clearance_picks_its_refinement_and_the_solvers_keep_it():
    """The instants clearance picks at a path are the off-grid instants of its rows there
    (three either side of the two lowest minima on the grid, from every pair measured), and
    ``with_picked`` keeps those of every iterate, adding nothing for other constraints."""
    from freefloat.problem.constraints import DEFAULT_INSTANTS, JointPositionLimits
    from freefloat.problem.constraints.clearance import REFINE, Clearance
    from freefloat.problem.constraints.clearance_samples import lowest_minima
    from freefloat.solvers.rows import NO_DIPS, with_picked

    scenario = ff.Scenario.from_toml(UR5)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    check = Clearance(CollisionModel(robot, known_srdf(robot)), 0.01)
    everything = CollisionModel(robot, known_srdf(robot))
    rng = np.random.default_rng(5)
    kept = NO_DIPS
    for scale in (0.2, 0.6):
        beta = rng.normal(0.0, scale, problem.n_free)
        grid = DEFAULT_INSTANTS
        q = problem.polynomials(beta).evaluate(grid * problem.duration).q
        smallest = np.array([everything.distances(row).values.min() for row in q])
        expected = []
        for k in lowest_minima(smallest):
            lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
            expected.extend(np.linspace(lo, hi, 2 * REFINE + 2)[1:-1])
        picked = check.picked_instants(problem, beta)
        np.testing.assert_allclose(picked, expected, rtol=0.0, atol=1e-15)
        assert with_picked(problem, [JointPositionLimits()], beta, NO_DIPS).shape == (0,)
        kept = with_picked(problem, [check], beta, kept)
        assert set(picked.tolist()) <= set(kept.tolist())
    assert len(kept) > 2 * 2 * REFINE  # the first iterate's instants stayed


def test_the_picked_instants_stay_with_their_path_when_a_rows_call_fails(monkeypatch):
    """A rows call that fails half way (an error in its second batch of distances) leaves
    the instants picked for the last path whose rows were made: those a fresh constraint
    picks there."""
    from freefloat.problem.constraints.clearance import Clearance

    scenario = ff.Scenario.from_toml(UR5)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    check = Clearance(CollisionModel(robot, known_srdf(robot)), 0.01)
    rng = np.random.default_rng(8)
    first, second = rng.normal(0.0, 0.3, problem.n_free), rng.normal(0.0, 0.6, problem.n_free)
    check.rows(problem, first)
    calls = []
    measured = Clearance._rows_at

    def failing(self, problem, beta, instants):
        calls.append(1)
        if len(calls) == 2:
            raise ValueError("a distance query failed")
        return measured(self, problem, beta, instants)

    monkeypatch.setattr(Clearance, "_rows_at", failing)
    with pytest.raises(ValueError):
        check.rows(problem, second)
    monkeypatch.setattr(Clearance, "_rows_at", measured)
    fresh = Clearance(CollisionModel(robot, known_srdf(robot)), 0.01)
    np.testing.assert_array_equal(
        check.picked_instants(problem, first), fresh.picked_instants(problem, first)
    )
