"""Clearance work shared between solver calls at one path: the same answers as asked afresh.

Truth here: a fresh constraint (nothing remembered) asked the same question, every pair's
distance measured densely along the path, and the dense check itself.
"""

from __future__ import annotations

import numpy as np
import pytest

import freefloat as ff
from freefloat.problem.constraints import DEFAULT_INSTANTS
from freefloat.problem.constraints.clearance import SOLVER_SLACK, Clearance
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.solvers.restore import broken_constraint, broken_rows_first

from conftest import ROOT

UR5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"


@pytest.fixture(scope="module")
def ur5():  # type: ignore[no-untyped-def]
    """The UR5 servicer's problem (2 free coefficients per joint) and its robot."""
    scenario = ff.Scenario.from_toml(UR5)
    robot = scenario.robot
    return ff.problem_from_scenario(scenario, extra=[2] * robot.n), robot


def _fresh(robot: ff.Robot) -> Clearance:
    return Clearance(CollisionModel(robot, known_srdf(robot)), 0.01)


def test_rows_asked_again_at_one_path_measure_only_new_instants(ur5, monkeypatch):
    """Rows at a path asked with the corrector's instants, then with fewer (the predictor's)
    and more (a dip): each answer is a fresh constraint's (to rounding: an instant measured in
    another batch has its joints from another matrix product), and the later calls measure no
    instant twice (counted at the collision model)."""
    problem, robot = ur5
    check = _fresh(robot)
    measured: list[int] = []
    original = CollisionModel.closest_many

    def counting(self, joints, slots=None, gradients=False, among=None):  # type: ignore[no-untyped-def]
        measured.append(len(np.atleast_2d(joints)))
        return original(self, joints, slots, gradients, among)

    monkeypatch.setattr(CollisionModel, "closest_many", counting)
    beta = np.random.default_rng(3).normal(0.0, 0.4, problem.n_free)
    picked = np.array([0.1234, 0.5678])
    first = check.rows(problem, beta, np.union1d(DEFAULT_INSTANTS, picked))
    count = sum(measured)
    fewer = check.rows(problem, beta, DEFAULT_INSTANTS)
    assert sum(measured) == count  # every instant known: nothing measured
    more = check.rows(problem, beta, np.union1d(DEFAULT_INSTANTS, [0.9001]))
    assert sum(measured) == count + 1  # the new instant alone
    for asked, rows in (
        (np.union1d(DEFAULT_INSTANTS, picked), first),
        (DEFAULT_INSTANTS, fewer),
        (np.union1d(DEFAULT_INSTANTS, [0.9001]), more),
    ):
        truth = _fresh(robot).rows(problem, beta, asked)
        np.testing.assert_allclose(rows.values, truth.values, rtol=0.0, atol=1e-15)
        np.testing.assert_allclose(rows.jacobian, truth.jacobian, rtol=0.0, atol=1e-13)
    other = beta + 1e-3
    moved = check.rows(problem, other, DEFAULT_INSTANTS)  # another path: measured again
    truth = _fresh(robot).rows(problem, other, DEFAULT_INSTANTS)
    np.testing.assert_allclose(moved.values, truth.values, rtol=0.0, atol=1e-15)


def _densely_smallest(problem, robot, beta) -> float:  # type: ignore[no-untyped-def]
    """Smallest distance (m) of every pair at 2001 instants, no pair spared."""
    everything = CollisionModel(robot, known_srdf(robot))
    t = np.linspace(0.0, problem.duration, 2001)
    q = problem.polynomials(beta).evaluate(t).q
    return float(min(everything.distances(row).values.min() for row in q))


def test_a_path_broken_by_its_rows_is_broken_by_the_dense_check(ur5):
    """A path deep in collision (every pair measured densely: below the margin) is called
    broken by its solver rows alone, by a row that many mm beyond the limit, and the dense
    check calls it broken too; a path that keeps the margin everywhere is broken by neither."""
    problem, robot = ur5
    deep = np.random.default_rng(11).normal(0.0, 1.5, problem.n_free)
    smallest = _densely_smallest(problem, robot, deep)
    assert smallest < 0.01 - 0.005
    said = broken_rows_first(problem, [_fresh(robot)], deep)
    assert said.startswith("clearance (a solver row ") and "beyond the limit" in said
    beyond = float(said.split("a solver row ")[1].split(" m")[0])
    assert beyond == pytest.approx(0.01 - smallest, abs=0.05)  # the rows' instants, not all
    assert beyond > SOLVER_SLACK
    assert broken_constraint(problem, [_fresh(robot)], deep).startswith("clearance")
    free = np.zeros(problem.n_free)
    assert _densely_smallest(problem, robot, free) > 0.01
    assert broken_rows_first(problem, [_fresh(robot)], free) == ""
    assert broken_constraint(problem, [_fresh(robot)], free) == ""


def test_rows_leave_out_the_pairs_no_free_coefficient_moves():
    """The dual UR5 servicer as shipped gives its right arm no free coefficients (it holds
    its pose): each solver row is the margin and slack less the smallest distance over the
    pairs the left arm moves (a fresh model measuring every pair), its gradient that of
    central differences of the row, and a held pair that is the smallest at an instant
    hides no moved pair. The dense check still takes every pair."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "dual_ur5_servicer.toml")
    problem = ff.problem_from_scenario(scenario, extra=scenario.extra)
    robot = scenario.robot
    constraint = _fresh(robot)
    fresh = CollisionModel(robot, known_srdf(robot))
    left = np.array([j.name.startswith("left_") for j in robot.joints])
    moved = fresh.pairs_moved_by(left)
    beta = np.random.default_rng(3).normal(0.0, 0.2, problem.n_free)
    grid = len(DEFAULT_INSTANTS)  # the first rows: the grid's instants, in order
    rows = constraint.rows(problem, beta, DEFAULT_INSTANTS)
    base, dq, _ = problem.family.linear_map(DEFAULT_INSTANTS)
    joints = base.q + dq @ beta
    held_smallest = 0
    for i, q in enumerate(joints):
        every = fresh.distances(q).values
        want = 0.01 + SOLVER_SLACK - every[moved].min()
        assert rows.values[i] == want
        held_smallest += every[~moved].min() < every[moved].min()
    assert held_smallest > 0
    h = 1e-6
    for k in range(0, problem.n_free, 5):
        e = np.zeros(problem.n_free)
        e[k] = h
        up = _fresh(robot).rows(problem, beta + e, DEFAULT_INSTANTS).values[:grid]
        down = _fresh(robot).rows(problem, beta - e, DEFAULT_INSTANTS).values[:grid]
        assert np.allclose(rows.jacobian[:grid, k], (up - down) / (2 * h), atol=1e-5)
    path = problem.polynomials(beta)
    assert (
        constraint.smallest(path, 201)[0]
        <= min(
            fresh.distances(q).values.min()
            for q in path.positions(np.linspace(0, path.duration, 201))
        )
        + 1e-12
    )


def test_the_dense_checks_bound_is_that_of_its_final_intervals(ur5):
    """The dense check bounds an interval once and keeps the bound until a sample splits it:
    its bound is the smallest of the bounds of the intervals between the samples it measured,
    each bounded afresh (and no sample it spared lies below the margin: every pair measured
    there)."""
    from freefloat.problem.constraints.clearance_samples import bounds_between

    problem, robot = ur5
    rng = np.random.default_rng(21)
    fresh = CollisionModel(robot, known_srdf(robot))
    for scale in (0.05, 0.3, 0.6):
        constraint = _fresh(robot)
        path = problem.polynomials(rng.normal(0.0, scale, problem.n_free))
        measured = constraint._measured(path, 201, constraint.margin)
        nodes = np.flatnonzero(~np.isnan(measured.known))
        assert len(nodes) > 201 // 8
        a, b = nodes[:-1], nodes[1:]
        t = np.linspace(0.0, path.duration, 201)
        lower, arms = measured.lower, measured.arms
        between = bounds_between(
            constraint.model, path, (t[a], t[b]), (lower[a], lower[b]), (arms[a], arms[b])
        )
        want = float(min(between.min(), np.nanmin(measured.known)))
        assert measured.bound == pytest.approx(want, abs=1e-12)
        spared = np.flatnonzero(np.isnan(measured.known))
        for k in spared[:: max(1, len(spared) // 20)]:
            assert fresh.distances(path.positions(t[k : k + 1])[0]).values.min() >= 0.01
