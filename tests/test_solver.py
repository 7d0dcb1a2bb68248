"""Solvers: minimum norm, square systems, spatial arms, met goals, infeasible requests."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import freefloat as ff
from freefloat.physics import attitude as att

import reference as ref
import urdfs
from conftest import deg


def _independent_final_attitude(problem: ff.Problem, beta: np.ndarray) -> np.ndarray:
    """Adaptive DOP853 on the quaternion ODE in seconds: not the planner's Magnus scheme."""
    mmap, family, T = ff.MomentumMap(problem.robot), problem.family, problem.duration

    def rhs(t, y):
        at = family.at_times(beta, np.array([t]), T)
        omega = mmap.f1(at.q[0]) @ at.qd[0]
        return 0.5 * att.quat_multiply(y, np.concatenate([omega, [0.0]]))

    sol = solve_ivp(
        rhs, (0.0, T), problem.start_quaternion, method="DOP853", rtol=1e-12, atol=1e-13
    )
    end = sol.y[:, -1]
    return end / np.linalg.norm(end)


def _worked_problem(robot, extra):
    return ff.build_problem(
        robot,
        [deg(80), deg(30)],
        [deg(-60), deg(90)],
        ff.quat_from_zyx(deg(-50)),
        ff.quat_from_zyx(0.0),
        10.0,
        extra=extra,
    )


@pytest.mark.parametrize("extra", [{"q1": 1, "q2": 1}, {"q1": 2, "q2": 1}])
def test_sqp_gives_a_minimum_norm_solution(planar_robot, extra):
    problem = _worked_problem(planar_robot, extra)
    solution = ff.solve(problem)
    assert solution.residual < 1e-9
    beta = solution.beta
    # First-order optimality of min |beta| s.t. h = 0: beta lies in the row space of dh/dbeta.
    eps = 1e-5
    jac = np.array(
        [
            (problem.residual(beta + eps * e) - problem.residual(beta - eps * e)) / (2 * eps)
            for e in np.eye(len(beta))
        ]
    ).T
    projected = beta - jac.T @ np.linalg.solve(jac @ jac.T, jac @ beta)
    assert np.linalg.norm(projected) < 1e-5 * np.linalg.norm(beta)


def test_met_goal_needs_no_motion(planar_robot):
    q = [deg(20), deg(-35)]
    problem = ff.build_problem(
        planar_robot, q, q, ff.quat_from_zyx(0.4), ff.quat_from_zyx(0.4), 5.0, extra={"q2": 1}
    )
    solution = ff.solve(problem)
    assert np.all(solution.beta == 0.0)
    assert solution.residual == 0.0
    plan = ff.plan_from_solution(problem, solution)
    assert np.abs(np.array(plan.samples.qd)).max() == 0.0
    assert np.abs(np.array(plan.samples.base_position) - plan.samples.base_position[0]).max() == 0


def test_planar_request_outside_bounds_is_refused_before_searching(planar_robot):
    with pytest.raises(ff.InfeasibleError) as info:
        ff.build_problem(
            planar_robot,
            [deg(80), deg(30)],
            [deg(-60), deg(90)],
            ff.quat_from_zyx(deg(-50)),
            ff.quat_from_zyx(deg(40)),
            10.0,
        )
    err = info.value
    assert err.requested_deg == pytest.approx(90.0)
    # against the closed form's extremes on a dense grid, refined (tests/reference.py)
    assert err.bounds_deg == pytest.approx(ref.worked_bounds_deg(), abs=1e-6)
    assert f"outside the reachable interval {ref.worked_bounds_text()} deg" in str(err)


def test_planar_goal_tilted_off_the_plane_is_refused(planar_robot):
    with pytest.raises(ff.InfeasibleError, match="only about its z axis"):
        ff.build_problem(
            planar_robot,
            [0.0, 0.0],
            [0.1, 0.1],
            ff.quat_from_zyx(0.0),
            ff.quat_from_zyx(0.0, 0.2, 0.0),
            10.0,
        )


def test_no_root_in_bracket_raises_with_best_residual(planar_robot):
    problem = _worked_problem(planar_robot, {"q2": 1})
    with pytest.raises(ff.SolverError) as info:
        ff.solve(problem, ff.SolveOptions(max_deviation=0.05))
    assert info.value.best_residual == pytest.approx(
        abs(problem.residual(np.zeros(1))[0]), rel=1e-12
    )
    assert "reaches the goal attitude" in str(info.value)
    assert "no sign change" in str(info.value)


@pytest.fixture(scope="module")
def spatial_robot(tmp_path_factory):
    path = tmp_path_factory.mktemp("arm") / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    return ff.load_robot(path)


def _spatial_problem(robot, extra):
    """A three-axis goal that is reachable by construction: reached by some known path."""
    args = ([0.2, -0.3, 0.1], [1.1, 0.4, -0.6], ff.quat_from_zyx(0.1, 0.05, -0.02))
    known = ff.build_problem(robot, *args, ff.quat_from_zyx(0.0), 8.0, extra=[1, 1, 1])
    goal = known.achieved(np.array([0.06, -0.04, 0.08]))  # rad RMS deviations
    assert att.geodesic_angle(goal, known.achieved(np.zeros(3))) > 0.01  # the quintic misses
    return ff.build_problem(robot, *args, goal, 8.0, extra=extra)


@pytest.mark.parametrize("extra,method", [([1, 1, 1], "Broyden"), ([2, 1, 1], "continuation")])
def test_spatial_three_axis_goal(spatial_robot, extra, method):
    problem = _spatial_problem(spatial_robot, extra)
    assert problem.n_equations == 3
    solution = ff.solve(problem)
    assert method in solution.method
    assert solution.residual < 1e-9
    reached = _independent_final_attitude(problem, solution.beta)
    assert att.geodesic_angle(reached, problem.goal_quaternion) < 1e-7
    plan = ff.plan_from_solution(problem, solution)
    assert plan.base.attitude_error_rad < 1e-9
    assert not plan.feasibility.planar and plan.feasibility.yaw_change_bounds_deg is None


def test_a_root_polished_on_a_finer_grid_records_its_own_path_length(spatial_robot, tmp_path):
    """Solved on a grid too coarse for it, the root is certified on a finer one and polished
    there: the path length recorded is that of the polished path (summed joint travel of
    its polynomials at 401 instants), and the plan written passes verification, which
    recomputes every solution's length from its coefficients."""
    problem = _spatial_problem(spatial_robot, [2, 1, 1]).with_steps(4)
    assert problem.integration_error(np.zeros(problem.n_free)) > 1e-10  # too coarse
    solution = ff.solve(problem)
    path = problem.polynomials(solution.beta)
    travel = float(np.abs(np.diff(path.evaluate(np.linspace(0.0, 8.0, 401)).q, axis=0)).sum())
    assert solution.roots[0].path_length == pytest.approx(travel, rel=1e-12)
    assert solution.steps > problem.steps  # certified on a finer grid
    plan = ff.plan_from_solution(problem.with_steps(solution.steps), solution)
    plan.save(tmp_path / "polished.plan.json")
    assert ff.verify_plan(ff.Plan.load(tmp_path / "polished.plan.json")).passed


def test_too_few_free_coefficients_is_refused(spatial_robot):
    with pytest.raises(ff.InputError, match=r"1 free path coefficient\(s\) for 3 attitude"):
        _spatial_problem(spatial_robot, [1, 0, 0])


def test_duration_leaves_the_attitude_reached_unchanged(spatial_robot):
    beta = np.array([0.3, -0.2, 0.5])
    reached = []
    for duration in (1.0, 8.0, 60.0):
        problem = ff.build_problem(
            spatial_robot,
            [0.2, -0.3, 0.1],
            [1.1, 0.4, -0.6],
            ff.quat_from_zyx(0.0),
            ff.quat_from_zyx(0.0),
            duration,
            extra=[1, 1, 1],
        )
        reached.append(problem.achieved(beta))
    assert att.geodesic_angle(reached[0], reached[1]) < 1e-14
    assert att.geodesic_angle(reached[0], reached[2]) < 1e-14
    assert math.isfinite(float(np.sum(reached)))


def test_exact_jacobian_matches_central_differences_on_the_worked_example(planar_robot):
    for extra in ({"q2": 1}, {"q1": 2, "q2": 1}):
        problem = _worked_problem(planar_robot, extra)
        beta = np.linspace(-40.0, 30.0, problem.n_free)
        jac = problem.jacobian(beta)
        eps = 1e-4
        fd = ref.central_jacobian(problem.residual, beta, eps)
        assert np.abs(jac - fd).max() <= 1e-6 * np.abs(fd).max()


def test_spatial_exact_jacobian(spatial_robot):
    problem = _spatial_problem(spatial_robot, [2, 1, 1])
    beta = np.array([0.5, -1.0, 2.0, 0.3])
    jac = problem.jacobian(beta)
    eps = 1e-5
    fd = ref.central_jacobian(problem.residual, beta, eps)
    assert np.abs(jac - fd).max() <= 1e-6 * np.abs(fd).max()


def test_polishing_a_diverged_candidate_never_reaches_least_squares():
    """Found by a sweep: a diverged SQP candidate sent NaN into LAPACK (which printed noise)."""
    from freefloat.solvers.newton import polish

    class Diverged:
        def residual(self, beta):
            return np.array([np.nan, 1.0, 0.0])

        def jacobian(self, beta):
            raise AssertionError("the Jacobian of a non-finite residual must not be asked for")

    beta = np.array([1e200, -3.0, 2.0])
    out, r = polish(Diverged(), beta, 1e-9)
    assert out is beta and np.isnan(r[0])


def test_polish_at_takes_polish_steps_and_brings_the_jacobian_at_its_result(spatial_robot):
    """From a point 0.05 rad RMS off a root of a three-axis goal with six unknowns,
    :func:`polish_at` (h and its Jacobian evaluated together) lands on the same point as
    :func:`polish` bit for bit, with the same residual; the Jacobian it brings is the one at
    that point, against central differences; it integrates fewer paths than polish and the
    Jacobian a caller then asks for; given ``(h, J)`` at its start, it evaluates none there."""
    from freefloat.solvers.newton import polish, polish_at

    problem = _spatial_problem(spatial_robot, [2, 2, 2])
    root = ff.solve(problem).beta
    direction = np.random.default_rng(5).normal(size=problem.n_free)
    start = root + 0.05 * np.sqrt(problem.n_free) * direction / np.linalg.norm(direction)
    before = problem.evaluations
    beta, r = polish(problem, start, 1e-9)
    problem.jacobian(beta)
    old_cost, before = problem.evaluations - before, problem.evaluations
    found = polish_at(problem, start, 1e-9)
    new_cost = problem.evaluations - before
    assert new_cost < old_cost
    assert np.linalg.norm(r) < 1e-13 < np.linalg.norm(problem.residual(start))
    assert np.array_equal(found.beta, beta) and np.array_equal(found.residual, r)
    fd = ref.central_jacobian(problem.residual, found.beta, 1e-5)
    assert np.abs(found.jacobian - fd).max() <= 1e-6 * np.abs(fd).max()
    h, jac = problem.residual_and_jacobian(start)
    before = problem.evaluations
    again = polish_at(problem, start, 1e-9, evaluated=(h, jac))
    assert np.array_equal(again.beta, beta)
    assert problem.evaluations - before == new_cost - 1


def test_remembered_residuals_and_jacobians_are_those_computed_afresh(spatial_robot):
    """A problem remembers the last point's residual and Jacobian, and residuals shared with
    its copies at other step counts: every value it gives back equals that of a problem built
    afresh (nothing remembered), including after the caller changed a returned array, on a
    copy at another step count and on a copy with another goal (which must not reuse them);
    and a repeated point costs no evaluation."""

    def afresh(steps: int = 64) -> ff.Problem:
        return _spatial_problem(spatial_robot, [2, 2, 2]).with_steps(steps)

    problem = afresh()
    beta = np.linspace(-0.1, 0.1, problem.n_free)
    h, jac = problem.residual_and_jacobian(beta)
    h[:] = 7.0
    jac[:] = 7.0
    before = problem.evaluations
    again, jac_again = problem.residual_and_jacobian(beta)
    value = problem.residual(beta)
    assert problem.evaluations == before
    h_fresh, jac_fresh = afresh().residual_and_jacobian(beta)
    assert np.array_equal(again, h_fresh) and np.array_equal(jac_again, jac_fresh)
    assert np.array_equal(value, afresh().residual(beta))
    fine = problem.with_steps(256)
    assert np.array_equal(fine.residual(beta), afresh(256).residual(beta))
    assert np.array_equal(fine.jacobian(beta), afresh(256).jacobian(beta))
    before = problem.evaluations
    assert np.array_equal(problem.with_steps(256).residual(beta), afresh(256).residual(beta))
    assert problem.evaluations == before  # the copy's value, remembered
    goal = att.quat_multiply(problem.goal_quaternion, att.quat_exp(np.array([0.0, 0.0, 0.1])))
    turned = problem.with_goal(goal)
    assert not np.allclose(turned.residual(beta), value)
    assert np.array_equal(turned.residual(beta), afresh().with_goal(goal).residual(beta))
    assert np.array_equal(turned.jacobian(beta), afresh().with_goal(goal).jacobian(beta))


def test_broyden_steps_past_a_start_where_the_map_loses_rank(spatial_robot):
    """At the quintic path the three-axis problem's Jacobian has rank 2 (a symmetric path):
    the full inverse would step ~1e10 rad away; Broyden must land on the known root."""
    from freefloat.solvers.newton import broyden

    problem = _spatial_problem(spatial_robot, [1, 1, 1])
    singular = np.linalg.svd(problem.jacobian(np.zeros(3)), compute_uv=False)
    assert singular[-1] < 1e-12 * singular[0]  # the start is singular indeed
    beta, _ = broyden(problem, np.zeros(3), ff.SolveOptions())
    assert np.linalg.norm(problem.residual(beta)) < 1e-9
    np.testing.assert_allclose(beta, [0.06, -0.04, 0.08], atol=1e-7)
