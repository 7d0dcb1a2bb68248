"""The root nearest the quintic, free and within constraints: optimality, against SciPy's SLSQP."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import minimize

import freefloat as ff
from freefloat.problem.constraints import DEFAULT_INSTANTS
from freefloat.problem.constraints.joint_position import JointPositionLimits
from freefloat.solvers import least_norm
from freefloat.solvers.least_norm import (
    least_norm_root,
    least_norm_root_within,
    nearest_root_within,
)
from freefloat.solvers.newton import polish

from conftest import ROOT, worked_problem


def test_least_norm_root_is_a_kkt_point_and_matches_slsqp(worked_scenario):
    scenario = worked_scenario.resolved()
    problem = ff.problem_from_scenario(scenario, extra=[2, 2])
    start = ff.solve(problem, ff.SolveOptions(), []).beta
    found = least_norm_root(problem, start, ff.SolveOptions())
    beta = found.beta
    residual, jac = problem.residual_and_jacobian(beta)
    assert np.linalg.norm(residual) < 1e-9
    np.testing.assert_array_equal(found.residual, residual)  # what it returns is at its root
    # KKT of min |beta|^2 s.t. h = 0: beta lies in the row space of the Jacobian
    null = np.linalg.svd(jac)[2][jac.shape[0] :]
    assert np.linalg.norm(null @ beta) < 1e-6 * np.linalg.norm(beta)
    assert beta @ beta <= start @ start
    # independent optimiser from the same start
    other = minimize(
        lambda b: b @ b,
        start,
        jac=lambda b: 2 * b,
        method="SLSQP",
        constraints=[{"type": "eq", "fun": problem.residual, "jac": problem.jacobian}],
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert other.success
    np.testing.assert_allclose(beta @ beta, other.x @ other.x, rtol=1e-6)


def _capped(worked_scenario, effort: float = math.inf):  # type: ignore[no-untyped-def]
    """The worked example with 3 free coefficients per joint and q1 capped at 1.45 rad.

    ``effort``: q1's effort limit (N m).
    """
    scenario = worked_scenario.resolved()
    joints = list(scenario.robot.joints)
    joints[0] = dataclasses.replace(joints[0], upper=1.45, effort_limit=effort)
    robot = dataclasses.replace(scenario.robot, joints=tuple(joints))
    return worked_problem(dataclasses.replace(scenario, robot=robot), {"q1": 3, "q2": 3})


def test_effort_limits_the_eager_steps_break_are_imposed_in_a_second_pass(worked_scenario):
    """Capped q1 (1.45 rad), then an effort limit on q1 at 0.9 of the torque peak of the root
    found within the position limits alone: the nearest root's steps keep the eager limits
    first, find that root breaks the (lazy) effort limit and take the steps again with it.
    The root returned is on h = 0, within the cap, and its torques, by inverse dynamics at
    4001 instants (another algorithm than the effort rows' torque derivatives), stay within
    the limit, while it deviates less than the start."""
    from freefloat.physics.dynamics import inverse_dynamics_batch
    from freefloat.problem.constraints.joint_effort import JointEffortLimits
    from freefloat.solvers.nearest import _within

    def peaks(problem, beta):  # type: ignore[no-untyped-def]
        samples = problem.polynomials(beta).evaluate(np.linspace(0.0, problem.duration, 4001))
        batch = inverse_dynamics_batch(problem.mmap, samples.q, samples.qd, samples.qdd)
        return np.abs(batch.tau).max(axis=0)

    problem, options, limits = _capped(worked_scenario), ff.SolveOptions(), JointPositionLimits()
    least = ff.solve(problem, options, []).beta
    null = np.linalg.svd(problem.jacobian(least))[2][3:]
    start = polish(problem, least + 0.5 * null[0], 1e-10)[0]
    eager = least_norm_root_within(problem, start, [limits], options, least).beta
    cap = 0.9 * peaks(problem, eager)[0]
    capped = _capped(worked_scenario, effort=cap)
    found = _within(capped, start, [limits, JointEffortLimits()], options, least).beta
    assert np.linalg.norm(capped.residual(found)) < 1e-10
    assert limits.violation(capped, found).value <= limits.tolerance
    assert peaks(capped, found)[0] <= cap
    assert found @ found < start @ start


def _slsqp_rows(problem, limits):  # type: ignore[no-untyped-def]
    """SciPy's rows: the cap at 401 instants and the attitude residual."""
    rows = limits.rows(problem, np.zeros(problem.n_free), np.linspace(0.0, 1.0, 401))
    return [
        {
            "type": "ineq",
            "fun": lambda b: -(rows.values + rows.jacobian @ b),
            "jac": lambda b: -rows.jacobian,
        },
        {"type": "eq", "fun": problem.residual, "jac": problem.jacobian},
    ]


def test_least_norm_root_within_a_binding_limit_matches_slsqp_on_a_dense_grid(worked_scenario):
    """Joint q1 capped at 1.45 rad, below the least-norm root's 1.516 rad: from a feasible root
    further out, the root found honours the cap everywhere (the polynomial's exact extremes),
    has the least norm SciPy's SLSQP finds with the cap imposed at 401 instants (another
    optimiser, another grid), and touches the cap (the constraint binds)."""
    problem = _capped(worked_scenario)
    options = ff.SolveOptions()
    least = ff.solve(problem, options, []).beta
    limits = JointPositionLimits()
    assert limits.violation(problem, least).value > 0.05  # the free least-norm root breaks it
    null = np.linalg.svd(problem.jacobian(least))[2][3:]
    start = polish(problem, least + 0.5 * null[0], 1e-10)[0]
    assert limits.violation(problem, start).value < 0.0
    found = least_norm_root_within(problem, start, [limits], options, settled=1e-9)
    assert found.honoured
    beta = found.beta
    assert np.linalg.norm(problem.residual(beta)) < 1e-10
    # the residual it carries is the one a fresh integration of its path gives, to rounding
    assert found.residual == pytest.approx(np.linalg.norm(problem.residual(beta)), abs=1e-15)
    excess = limits.violation(problem, beta).value
    assert -1e-6 < excess <= limits.tolerance
    cap = _slsqp_rows(problem, limits)
    other = minimize(
        lambda b: b @ b,
        start,
        jac=lambda b: 2 * b,
        method="SLSQP",
        constraints=cap,
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert other.success
    assert beta @ beta < start @ start
    np.testing.assert_allclose(beta @ beta, other.x @ other.x, rtol=1e-5)
    # with the planner's default, steps stop once one gains less than 1 %: about as low
    default = least_norm_root_within(problem, start, [limits], options).beta
    assert other.x @ other.x * (1 - 1e-6) <= default @ default <= 1.05 * (other.x @ other.x)


def test_corrections_bring_a_root_inside_a_cap_it_breaks(worked_scenario, monkeypatch):
    """The free least-norm root breaks the 1.45 rad cap on q1 by 0.066 rad: least-norm
    corrections with the rows at its tightest instants give a root within the cap everywhere
    (exact polynomial extremes), moved about as little as the nearest such root SciPy's SLSQP
    finds with the cap at 401 instants."""
    problem = _capped(worked_scenario)
    options = ff.SolveOptions()
    start = ff.solve(problem, options, []).beta
    limits = JointPositionLimits()
    found = nearest_root_within(problem, start, [limits], DEFAULT_INSTANTS, options)
    assert found.honoured
    assert np.linalg.norm(problem.residual(found.beta)) < 1e-10
    fresh = np.linalg.norm(problem.residual(found.beta))
    assert found.residual == pytest.approx(fresh, abs=1e-15)  # carried, not integrated again
    # a correction that fails returns its start, with the residual there: off the root set,
    # so a residual carried from anywhere else would not match a fresh integration
    off = start + 0.05
    with monkeypatch.context() as patch:
        patch.setattr(least_norm, "_corrected", lambda *args, **kwargs: None)
        failed = nearest_root_within(problem, off, [limits], DEFAULT_INSTANTS, options)
    assert not failed.honoured and np.array_equal(failed.beta, off)
    truth = np.linalg.norm(problem.residual(off))
    assert truth > 1e-3 and failed.residual == pytest.approx(truth, rel=1e-12)
    assert limits.violation(problem, found.beta).value <= limits.tolerance
    cap = _slsqp_rows(problem, limits)
    nearest = minimize(
        lambda b: (b - start) @ (b - start),
        start,
        jac=lambda b: 2 * (b - start),
        method="SLSQP",
        constraints=cap,
        options={"ftol": 1e-14, "maxiter": 500},
    )
    assert nearest.success
    moved, least = np.linalg.norm(found.beta - start), np.linalg.norm(nearest.x - start)
    assert least <= moved <= 1.1 * least


def test_a_level_whose_rounds_press_past_a_limit_keeps_the_root_brought_inside():
    """The Panda servicer's goal rolled 65 deg: at each freedom level the steps within the
    joint limits end just past a limit between their instants (1e-5 rad), while the free
    least-norm root brought inside passed the dense check. That root is kept: the plan
    deviates far less from the quintic than the search's root (|beta|^2 below half of it),
    and its samples stay within the URDF's limits (read from the file here, not from the
    planner's robot) and its verification passed."""
    import dataclasses as dc
    import xml.etree.ElementTree as ET

    from freefloat.physics import attitude as att

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    rolled = att.quat_multiply(scenario.goal_attitude, att.quat_exp(np.radians([65.0, 0, 0])))
    plan = ff.plan(dc.replace(scenario, goal_attitude=rolled))
    levels = [t for t in plan.solver.tried if t.startswith("nearest root")]
    assert levels and all("deviation" in t for t in levels), levels
    assert plan.objective.value < 0.5 * plan.objective.start_value
    assert all(c.passed for c in plan.verification.checks)
    limits = {
        j.get("name"): (float(j.find("limit").get("lower")), float(j.find("limit").get("upper")))
        for j in ET.parse(scenario.robot.urdf).getroot().iter("joint")
        if j.find("limit") is not None and j.get("type") == "revolute"
    }
    q = np.asarray(plan.samples.q, dtype=float)
    for i, name in enumerate(plan.robot.joints):
        lower, upper = limits[name]
        assert lower - 1e-9 <= q[:, i].min() and q[:, i].max() <= upper + 1e-9, name


def test_the_free_least_norm_root_settles_far_enough_to_make_the_path_natural():
    """The Panda servicer's goal turned 10 deg about y from the quintic's attitude: the search's
    path swings a joint far beyond its span, and the least-norm steps from three free
    coefficients per joint on (without the constraint's curvature) creep along the root set.
    Within their budgets (three per joint, then four when three is not natural yet) they end on
    a root whose largest excursion, measured here on 2001 samples of the file's Jacobi series
    (verification's evaluator, not the planner's Chebyshev series), is within the natural
    60 deg, so no further freedom level is tried; the plan deviates less from the quintic than
    the search's root and verifies."""
    import dataclasses as dc

    from freefloat.physics import attitude as att
    from freefloat.solvers.nearest import NATURAL_EXCURSION
    from freefloat.verify.path_eval import file_path

    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    problem = ff.problem_from_scenario(scenario, extra=[1, 1, 1] + [0] * (scenario.robot.n - 3))
    drift = problem.achieved(np.zeros(problem.n_free))
    turned = att.quat_multiply(drift, att.quat_exp(np.radians([0.0, 10.0, 0.0])))
    plan = ff.plan(dc.replace(scenario, goal_attitude=turned))
    levels = [t for t in plan.solver.tried if t.startswith("nearest root")]
    assert levels[0].startswith("nearest root, freedom 3: deviation")
    assert len(levels) <= 2 and all("not kept" not in level for level in levels)
    dense = file_path(plan).positions(np.linspace(0.0, plan.duration, 2001))  # (2001, N)
    start, goal = np.asarray(plan.request.start_joints), np.asarray(plan.request.goal_joints)
    low, high = np.minimum(start, goal), np.maximum(start, goal)
    beyond = np.maximum(dense - high, low - dense).max()
    assert beyond <= NATURAL_EXCURSION
    assert plan.objective.value < plan.objective.start_value
    assert plan.verification.passed


def test_a_root_past_a_limit_by_less_than_the_row_slack_is_brought_inside(worked_scenario):
    """q1's cap set 3e-7 rad below the root's largest q1 (closed form of the polynomial's
    extreme): beyond the limit's 1e-9 rad tolerance, within the 1e-6 a row may be broken by
    (``ROW_SLACK``). The corrections do not return the root as it is, which the dense check
    rejects again; they bring it inside: q1 within the cap on 200001 samples, on the root set."""
    problem = _capped(worked_scenario)
    options = ff.SolveOptions()
    start = ff.solve(problem, options, []).beta
    t = np.linspace(0.0, problem.duration, 200001)
    peak = float(problem.polynomials(start).evaluate(t).q[:, 0].max())
    joints = list(problem.robot.joints)
    joints[0] = dataclasses.replace(joints[0], upper=peak - 3e-7)
    robot = dataclasses.replace(problem.robot, joints=tuple(joints))
    scenario = worked_scenario.resolved()
    tight = worked_problem(dataclasses.replace(scenario, robot=robot), {"q1": 3, "q2": 3})
    assert np.linalg.norm(tight.residual(start)) < 1e-10  # the same family: still a root
    limits = JointPositionLimits()
    assert limits.violation(tight, start).value > 1e-7  # broken beyond the tolerance
    found = nearest_root_within(tight, start, [limits], DEFAULT_INSTANTS, options)
    assert found.honoured and not np.array_equal(found.beta, start)
    sampled = tight.polynomials(found.beta).evaluate(t).q[:, 0]
    assert float(sampled.max()) <= peak - 3e-7 + 1e-9
    assert np.linalg.norm(tight.residual(found.beta)) < 1e-10
