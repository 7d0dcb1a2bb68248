"""Robustness to wrong mass properties: sensitivity, perturbed replays, correction.

Truths used: central finite differences of an independent integrator (RK5 replays in models
whose URDF was changed and re-parsed by Pinocchio) for the exact sensitivity, brute-force
vertex enumeration for the worst case, the Monte Carlo replays for the first-order spread, and
a replay in the perturbed model for the correction.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import (
    InfeasibleError,
    InputError,
    ScenarioError,
    UnknownNameError,
)
from freefloat.physics.attitude import quat_from_zyx, zyx_from_quat
from freefloat.problem.inertial_sensitivity import attitude_sensitivity as path_sensitivity
from freefloat.problem.inertial_sensitivity import body_parameters
from freefloat.problem.scenario import Scenario
from freefloat.problem.uncertainty import DEFAULT_UNCERTAINTY, Uncertainty, spread, worst_case
from freefloat.robot.model import load_robot, robots_dir
from freefloat.robust import perturbed_robot, replay_attitude
from freefloat.robust.correction import correcting_plan
from freefloat.robust.inertial import link_inertials, robot_text, with_inertials
from freefloat.robust.plan_robustness import plan_spread, with_robustness
from freefloat.sweep import SweepSpec
from freefloat.verify.recompute import problem_from_plan

from conftest import as_older_format

SCENARIOS = robots_dir() / "scenarios"


def _planned(name: str, tmp: Path) -> tuple[ff.Plan, Path]:
    result = ff.plan(Scenario.from_toml(SCENARIOS / f"{name}.toml"), samples=41)
    return result, result.save(tmp / f"{name}.plan.json")


@pytest.fixture(scope="module")
def worked(tmp_path_factory):
    plan, path = _planned("worked_example", tmp_path_factory.mktemp("we"))
    return plan, path, load_robot(plan.robot.urdf, plan.robot.end_effector)


@pytest.fixture(scope="module")
def panda(tmp_path_factory):
    plan, path = _planned("panda_servicer", tmp_path_factory.mktemp("panda"))
    return plan, path, load_robot(plan.robot.urdf, plan.robot.end_effector)


def attitude_sensitivity(plan, robot):
    return path_sensitivity(*problem_from_plan(plan, robot))


def _reparsed(robot, changes, text=None):
    """The robot with changed inertial values, parsed again by Pinocchio from the URDF."""
    source = robot_text(robot) if text is None else text
    return load_robot(robot.urdf, robot.end_effector, text=with_inertials(source, changes))


def _replayed_error(plan, robot, link, key, value):
    return replay_attitude(plan, _reparsed(robot, {link: {key: value}})).error_rotvec


def _replayed_derivative(plan, robot, link, key):
    """d(final error rotation vector)/d(the link's value): central differences of replays in
    re-parsed URDFs, with step control (Richardson on two steps)."""
    value = link_inertials(robot_text(robot))[link].value(key)
    scale = 0.05 if key.startswith("com") else max(abs(value), 0.1)
    estimates = []
    for h in (1e-3 * scale, 5e-4 * scale):
        plus = _replayed_error(plan, robot, link, key, value + h)
        minus = _replayed_error(plan, robot, link, key, value - h)
        estimates.append((plus - minus) / (2 * h))
    return (4 * estimates[1] - estimates[0]) / 3


def test_changing_a_loaded_model_equals_parsing_the_changed_urdf(tmp_path):
    robot = load_robot(robots_dir() / "panda_servicer.urdf")
    text = robot_text(robot).replace(  # an inertia frame turned against its link
        '<origin xyz="-0.003141 -0.02872 0.003495" rpy="0.0 -0.0 0.0"/>',
        '<origin xyz="-0.003141 -0.02872 0.003495" rpy="0.3 -0.2 0.7"/>',
    )
    assert "0.3 -0.2 0.7" in text
    path = tmp_path / "tilted.urdf"
    path.write_text(text)
    robot = load_robot(path)
    changes = {
        "spacecraft": {"mass": 101.0, "com.1": 0.02, "inertia.ixy": 0.3},
        "panda_link0": {"mass": 0.7, "com.2": 0.06, "inertia.izz": 0.005},  # merged into the base
        "panda_link2": {"mass": 0.9, "com.0": 0.01, "inertia.ixz": 0.002},
        "panda_hand": {"mass": 0.8, "inertia.iyy": 0.0026},  # merged into link 7
    }
    fast, parsed = perturbed_robot(robot, changes, text), _reparsed(robot, changes, text)
    for a, b in zip(fast.model.inertias, parsed.model.inertias, strict=True):
        assert np.abs(a.toDynamicParameters() - b.toDynamicParameters()).max() < 1e-12
    assert fast.total_mass == pytest.approx(robot.total_mass + 1.0 + 0.070231 + 0.253074 + 0.07)


@pytest.mark.parametrize(
    ("fixture", "link", "body", "key", "column"),
    [
        ("worked", "base", 0, "inertia.izz", 6),
        ("worked", "link2", 2, "mass", 0),
        ("worked", "link1", 1, "com.0", 1),
        ("panda", "panda_link4", 4, "inertia.izz", 6),
        ("panda", "panda_link4", 4, "com.0", 1),
        ("panda", "panda_link2", 2, "mass", 0),
        ("panda", "spacecraft", 0, "inertia.ixy", 7),
        ("panda", "spacecraft", 0, "inertia.ixx", 4),
    ],
)
def test_sensitivity_matches_finite_differences_of_rk4_replays(
    request, fixture, link, body, key, column
):
    plan, _, robot = request.getfixturevalue(fixture)
    sens = attitude_sensitivity(plan, robot)
    fd = _replayed_derivative(plan, robot, link, key)
    exact = sens.jacobian[:, body, column]
    # a link joined by fixed joints moves its body's centre of mass: only moments map 1:1
    assert np.linalg.norm(fd - exact) <= 1e-5 * np.linalg.norm(exact) + 1e-12
    assert np.linalg.norm(exact) > 0.0 or key == "inertia.ixy"


@pytest.fixture(scope="module")
def held(tmp_path_factory):
    """The Panda servicer holding a 5 kg payload whose frame is turned 45 deg from its body's."""
    tmp = tmp_path_factory.mktemp("held")
    path = tmp / "held.toml"
    path.write_text(
        (SCENARIOS / "panda_servicer.toml").read_text()
        + "\n[payload]\nmass = 5.0\ncom_xyz = [0.02, -0.01, 0.1]\n"
        "inertia = [0.05, 0.04, 0.03, 0.004, -0.002, 0.001]\n"
    )
    plan = ff.plan(Scenario.from_toml(path), samples=41)
    return plan, path, load_robot(plan.robot.urdf, plan.robot.end_effector)


@pytest.mark.parametrize(
    ("link", "row", "key", "column"),
    [
        ("captured_payload", "captured_payload", "mass", 0),
        ("captured_payload", "captured_payload", "com.0", 1),
        ("captured_payload", "captured_payload", "com.2", 3),
        ("captured_payload", "captured_payload", "inertia.izz", 6),
        ("captured_payload", "captured_payload", "inertia.ixy", 7),
        ("panda_link7", "panda_link7", "inertia.izz", 6),  # the holder, payload left out
    ],
)
def test_a_payload_has_its_own_row_matching_replays_of_the_changed_urdf(
    held, link, row, key, column
):
    """The payload's parameters in its own frame (turned against its body's), by finite
    differences of RK5 replays of the URDF with the payload's values changed and parsed again
    by Pinocchio (which merges it into the hand's body); the holder's row without it."""
    plan, _, robot = held
    sens = attitude_sensitivity(plan, robot)
    assert sens.bodies[-2:] == ("panda_link7", "captured_payload")
    assert sens.nominal[-1].tolist() == [
        5.0,
        0.02,
        -0.01,
        0.1,
        0.05,
        0.04,
        0.03,
        0.004,
        -0.002,
        0.001,
    ]
    # the holder's mass is its body's less the payload's
    body = robot.model.inertias[robot.model.njoints - 1].mass
    assert sens.nominal[-2, 0] == pytest.approx(body - 5.0, rel=1e-12)
    fd = _replayed_derivative(plan, robot, link, key)
    exact = sens.jacobian[:, sens.bodies.index(row), column]
    assert np.linalg.norm(fd - exact) <= 1e-5 * np.linalg.norm(exact) + 1e-12
    assert np.linalg.norm(exact) > 0.0


def test_a_format_4_record_counts_the_payload_within_its_holder_and_still_verifies(held, tmp_path):
    """Format 5 records the payload apart; a format-4 file's record, made with the payload
    within its holder's body, is recomputed so by verify, and the other figure fails it."""
    plan, _, robot = held
    plan = with_robustness(plan, robot)  # as freefloat plan records it
    problem, beta = problem_from_plan(plan, robot)
    apart = spread(path_sensitivity(problem, beta), DEFAULT_UNCERTAINTY)
    within = spread(path_sensitivity(problem, beta, payload_apart=False), DEFAULT_UNCERTAINTY)
    assert plan.format == "freefloat.plan/5" and plan.robustness.rms_rad == apart.rms
    assert abs(apart.rms - within.rms) > 1e-3 * within.rms  # the two models differ
    data = plan.to_dict()
    data["format"] = "freefloat.plan/4"
    with pytest.raises(ff.InputError, match="states one uncertainty for every body"):
        with_robustness(plan, robot, Uncertainty(payload=Uncertainty(mass_fraction=0.2)))
    for figures, code in ((within, 0), (apart, 2)):
        data["robustness"]["rms_rad"] = figures.rms
        data["robustness"]["worst_rad"] = figures.worst
        old = tmp_path / "old.json"
        old.write_text(json.dumps(data))
        assert main(["verify", str(old)]) == code


def _table(out: str) -> dict[str, list[float]]:
    """The sensitivity table's rows: body -> mass, com, inertia, RMS (deg)."""
    rows = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 5 and all(
            p.replace(".", "").replace("e-", "").isdigit() for p in parts[1:]
        ):
            rows[parts[0]] = [float(p) for p in parts[1:]]
    return rows


def test_a_payload_may_have_its_own_uncertainty(held, worked, tmp_path, capsys):
    """A group's worst case scales with its size (first order, closed form): 20 % of the
    payload's mass is four times 5 %, 50 mm of its centre of mass five times 10 mm; every
    other body's row is unchanged."""
    plan, _, _ = held
    path = plan.save(tmp_path / "held.plan.json")
    assert main(["sensitivity", str(path)]) == 0
    plain = _table(capsys.readouterr().out)
    argv = ["sensitivity", str(path), "--payload-mass-pct", "20", "--payload-com-mm", "50"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "the captured payload mass 20 %, centre of mass 50 mm, inertia 10 %" in out
    mine = _table(out)
    assert mine["captured_payload"][0] == pytest.approx(4 * plain["captured_payload"][0], rel=1e-3)
    assert mine["captured_payload"][1] == pytest.approx(5 * plain["captured_payload"][1], rel=1e-3)
    assert mine["captured_payload"][2] == plain["captured_payload"][2]
    assert {k: v for k, v in mine.items() if k != "captured_payload"} == {
        k: v for k, v in plain.items() if k != "captured_payload"
    }
    _, without, _ = worked
    assert main(["sensitivity", str(without), "--payload-mass-pct", "20"]) == 2
    assert "holds a captured payload" in capsys.readouterr().err


def test_worst_case_equals_brute_force_vertex_enumeration():
    rng = np.random.default_rng(3)
    for n in (5, 15):
        s, u = rng.normal(size=(3, n)), rng.uniform(0.2, 1.0, n)
        brute = max(
            np.linalg.norm(s @ (np.array(v) * u)) for v in itertools.product((1, -1), repeat=n)
        )
        assert worst_case(s, u) == pytest.approx(brute, rel=1e-12)


def _draws(robot, link, count, fraction, seed):
    """Models with the link's three moments each off by a normal fraction (1-sigma)."""
    nominal = link_inertials(robot_text(robot))[link]
    rng = np.random.default_rng(seed)
    for _ in range(count):
        changes = {
            f"inertia.{k}": nominal.value(f"inertia.{k}") * (1 + fraction * rng.normal())
            for k in ("ixx", "iyy", "izz")
        }
        yield perturbed_robot(robot, {link: changes})


@pytest.mark.parametrize(("fixture", "link"), [("worked", "base"), ("panda", "spacecraft")])
def test_first_order_spread_agrees_with_monte_carlo_replays(request, fixture, link):
    plan, _, robot = request.getfixturevalue(fixture)
    sens = attitude_sensitivity(plan, robot)
    replayed, predicted = [], []
    for model in _draws(robot, link, 300, 0.01, seed=1):
        replayed.append(replay_attitude(plan, model).error_rotvec)
        predicted.append(sens.first_order(body_parameters(model) - sens.nominal))
    replayed, predicted = np.array(replayed), np.array(predicted)
    # the same draws: first order against the replays (linearity at a 1 % size)
    mean_mc = np.linalg.norm(replayed, axis=1).mean()
    assert np.linalg.norm(predicted, axis=1).mean() == pytest.approx(mean_mc, rel=0.05)
    # the analytic covariance of a 1 % uncertainty of those three moments, against the draws'
    only = Uncertainty(mass_fraction=0.0, com_m=0.0, inertia_fraction=0.01)
    sizes = only.sizes(sens.nominal)
    sizes[:, 7:] = 0.0
    sizes[1:] = 0.0
    scaled = (sens.jacobian * sizes[None]).reshape(3, -1)
    cov_mc = np.cov(replayed.T)
    assert np.linalg.norm(scaled @ scaled.T - cov_mc) <= 0.2 * np.linalg.norm(cov_mc)


def test_spread_figures_add_up(panda):
    plan, _, robot = panda
    result = spread(attitude_sensitivity(plan, robot), Uncertainty(0.05, 0.01, 0.1))
    assert result.rms == pytest.approx(math.sqrt(sum(b.rms**2 for b in result.bodies)))
    assert result.worst >= max(max(b.mass, b.com, b.inertia) for b in result.bodies)
    assert result.worst >= result.rms * 0.5


def test_correction_reaches_the_goal_and_shrinks_a_five_percent_error(worked):
    plan, _, robot = worked
    true = perturbed_robot(robot, {"base": {"inertia.izz": 66.67 * 1.05}})
    before = replay_attitude(plan, true)
    assert before.error_rad > 1e-3
    corr = correcting_plan(plan, robot, before.quaternion)
    assert corr.request.start_joints == corr.request.goal_joints == plan.request.goal_joints
    nominal = replay_attitude(corr, robot)  # RK5, not the planner's Magnus scheme
    assert nominal.error_rad <= 1e-9 + nominal.estimate_rad
    after = replay_attitude(corr, true, start_quaternion=before.quaternion)
    assert after.error_rad <= 0.1 * before.error_rad


def test_a_correction_no_motion_can_make_is_refused(worked):
    """The measured attitude, not a goal, is off-axis: the refusal says what to correct."""
    plan, _, robot = worked
    measured = quat_from_zyx(0.0, math.radians(2.0), 0.0)  # a planar base cannot pitch
    with pytest.raises(InfeasibleError) as info:
        correcting_plan(plan, robot, measured)
    assert info.value.off_axis
    assert str(info.value) == (
        "this robot is planar: a motion turns its base only about its z axis, and the measured "
        "attitude is 2 deg from the plan's goal about other axes; only the yaw can be "
        "corrected (give the measured yaw with the goal's pitch and roll)"
    )


def test_a_planar_correction_off_its_axis_says_so_before_the_cone(tmp_path):
    """A review: with a pointing cone on the worked example, a measured attitude pitched
    70 deg was refused by the cone (77.3 deg from its direction) before the planar robot's
    off-axis refusal, which is what the user must fix first."""
    path = tmp_path / "cone.toml"
    path.write_text(
        ff.default_scenario_path().read_text()
        + "\n[constraints.base_pointing]\naxis = [1.0, 0.0, 0.0]\nhalf_angle_deg = 60.0\n"
    )
    plan = ff.plan(Scenario.from_toml(path))
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    with pytest.raises(InfeasibleError) as info:
        correcting_plan(plan, robot, quat_from_zyx(0.0, math.radians(70.0), 0.0))
    assert str(info.value).startswith("this robot is planar: a motion turns its base only")


def test_a_correction_too_far_names_where_its_search_began(tmp_path):
    """The UR5 servicer turned 126 deg off its goal: the refusal said "back by 126 deg"
    beside "of the 119 deg asked" (the search's own figure, from the loop it began on) with
    nothing to tell them apart; now it names that loop's distance, which is the one asked."""
    import re

    plan = ff.plan(Scenario.from_toml(SCENARIOS / "ur5_servicer.toml"), samples=41)
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    measured = quat_from_zyx(*np.radians([120.0, 30.0, 10.0]))
    with pytest.raises(ff.SolverError) as info:
        correcting_plan(plan, robot, measured)
    message = str(info.value)
    wanted = math.degrees(ff.geodesic_angle(measured, plan.base.target_quaternion_xyzw))
    said = re.search(
        r"cannot turn the spacecraft back by ([\d.]+) deg .*search began on a loop ending "
        r"([\d.]+) deg from the goal: reachable up to [\d.]+ deg of the ([\d.]+) deg asked",
        message,
    )
    assert said, message
    assert float(said.group(1)) == pytest.approx(wanted, abs=0.5)
    assert float(said.group(2)) == pytest.approx(float(said.group(3)), abs=0.5)


def _cone_plan(tmp_path):
    """The worked example kept within 60 deg of the base direction at 70 deg (its tool's x
    axis, which points at q1 + q2 in the base plane)."""
    cone = (
        "\n[constraints.end_effector_cone]\naxis = [1.0, 0.0, 0.0]\n"
        "direction = [0.3420201433256687, 0.9396926207859083, 0.0]\nhalf_angle_deg = 60.0\n"
    )
    path = tmp_path / "s.toml"
    path.write_text(ff.default_scenario_path().read_text() + cone)
    plan = ff.plan(Scenario.from_toml(path))
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    goal_yaw = math.degrees(zyx_from_quat(plan.base.target_quaternion_xyzw)[0])
    return plan, robot, goal_yaw


def test_a_refused_correction_reports_no_residual_beyond_the_loop_it_began_on(tmp_path):
    """Turned back by 60 deg within the cone: the refusal said its search began on a loop
    ending near the goal beside a best residual of the whole turn (an attempt that started
    over). The loop keeps every constraint: no figure may be worse than it."""
    import re

    plan, robot, goal_yaw = _cone_plan(tmp_path)
    measured = quat_from_zyx(math.radians(goal_yaw + 60.0), 0.0, 0.0)
    with pytest.raises(ff.SolverError) as info:
        correcting_plan(plan, robot, measured)
    message = str(info.value)
    began = re.search(r"began on a loop ending ([\d.]+) deg from the goal", message)
    assert began and "within the plan's constraints" in message, message
    assert math.degrees(info.value.best_residual) <= float(began.group(1)) * (1 + 1e-3)


def test_a_root_polished_out_of_the_cone_is_dropped_not_returned(tmp_path):
    """Turned back by 45 deg: the search's one root within the cone (coefficients up to
    35 rad, found on a 64-step grid) moved, polished on the 2048-step grid that certifies it,
    onto a path 76.66 deg from the cone's direction (16.66 deg out: the closed-form gap of
    the test below, 0.269, on 400001 instants); the solver returned it, and only
    verification refused the plan. A correction now checks its root on the root's own grid
    (the planner's later stages bring such a root back inside instead)."""
    plan, robot, goal_yaw = _cone_plan(tmp_path)
    measured = quat_from_zyx(math.radians(goal_yaw + 45.0), 0.0, 0.0)
    with pytest.raises(ff.SolverError) as info:
        correcting_plan(plan, robot, measured)
    assert not isinstance(info.value, ff.VerificationError)
    said = "the root polished on a finer grid breaks end_effector_cone (ee's axis 76.66 deg"
    assert any(t.startswith(said) for t in info.value.tried), info.value.tried
    assert "end_effector_cone" in info.value.blocked_by


@pytest.mark.parametrize("back_deg", [2.0, 10.0, 15.0, -10.0])
def test_a_correction_near_the_cone_is_planned_not_refused_by_a_hair(tmp_path, back_deg):
    """Turned back by 2 deg: a root 0.01 deg outside the cone between the solver's instants
    was refused; the rows now ask for the axis a hair inside (SOLVER_SLACK). By 10 deg: it
    was refused until the loop it starts from kept the base near its start on the way. By
    15 deg: the search from that loop stops, and the one from the loop of the least joint
    motion (the earlier start, which planned it) is tried next. By -10 deg: both stop with
    two free coefficients per joint; with three, as plan's search goes on, it plans.
    Closed form: the cone's gap cos(60 deg) - cos(q1 + q2 - 70 deg) on 20001 instants of
    the plan."""
    plan, robot, goal_yaw = _cone_plan(tmp_path)
    measured = quat_from_zyx(math.radians(goal_yaw + back_deg), 0.0, 0.0)
    corrected = correcting_plan(plan, robot, measured)
    assert corrected.base.attitude_error_rad <= 1e-9
    q = corrected.joint_positions(np.linspace(0.0, corrected.duration, 20001))
    gap = math.cos(math.radians(60)) - np.cos(q[:, 0] + q[:, 1] - math.radians(70))
    assert gap.max() <= 1e-9


def test_unphysical_or_unknown_inertial_values_are_refused():
    text = (robots_dir() / "planar_2dof.urdf").read_text()
    with pytest.raises(InputError, match="mass must be a finite number > 0"):
        with_inertials(text, {"link1": {"mass": -1.0}})
    with pytest.raises(InputError, match="triangle inequality"):
        with_inertials(text, {"link1": {"inertia.izz": 10.0}})
    with pytest.raises(UnknownNameError, match="link2"):
        with_inertials(text, {"link9": {"mass": 1.0}})
    changed = link_inertials(with_inertials(text, {"link1": {"com.1": 0.25}}))
    assert changed["link1"].com[1] == 0.25
    assert changed["link2"] == link_inertials(text)["link2"]


def _replay_sweep(tmp_path: Path, plan_path: Path, body: str) -> Path:
    path = tmp_path / "mc.toml"
    path.write_text(f'plan = "{plan_path}"\n' + body)
    return path


def test_random_draws_are_physical_reproducible_and_drawn_together(tmp_path, worked):
    _, plan_path, _ = worked
    body = (
        '[[axis]]\nkey = "robot.links.link2.mass"\n'
        "values = { uniform = [-30.0, 60.0], samples = 40, seed = 4 }\n"
        '[[axis]]\nkey = "robot.links.base.inertia.izz"\n'
        "values = { normal = [66.67, 1.0], samples = 40, seed = 5 }\n"
    )
    spec = SweepSpec.from_toml(_replay_sweep(tmp_path, plan_path, body))
    again = SweepSpec.from_toml(_replay_sweep(tmp_path, plan_path, body))
    assert spec.size == 40 and spec.axes == again.axes
    masses = [job.changes["link2"]["mass"] for job in spec.jobs()]
    assert min(masses) > 0.0 and max(masses) <= 60.0  # negative masses drawn again
    bad = body.replace("samples = 40, seed = 5", "samples = 30, seed = 5")
    with pytest.raises(ScenarioError, match="same samples"):
        SweepSpec.from_toml(_replay_sweep(tmp_path, plan_path, bad))
    with pytest.raises(ScenarioError, match="inertial keys"):
        SweepSpec.from_toml(
            _replay_sweep(tmp_path, plan_path, '[[axis]]\nkey = "duration"\nvalues = [1.0]\n')
        )


def test_replay_sweep_rows_are_the_replays_locally_and_on_dask(tmp_path, worked):
    plan, plan_path, robot = worked
    body = (
        '[[axis]]\nkey = "robot.links.base.inertia.izz"\n'
        "values = { normal = [66.67, 3.0], samples = 6, seed = 1 }\n"
    )
    spec = SweepSpec.from_toml(_replay_sweep(tmp_path, plan_path, body))
    local = ff.sweep(spec, workers=2, output=tmp_path / "local.csv", progress=False)
    for row in local:
        direct = _replayed_error(plan, robot, "base", "inertia.izz", row.values[0])
        assert row.status == "replayed"
        assert [row.error_x_rad, row.error_y_rad, row.error_z_rad] == direct.tolist()
    resumed = ff.sweep(spec, workers=1, output=tmp_path / "local.csv", progress=False)
    assert resumed == local  # every row read back from the file, none run again
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            processes=True,
            n_workers=2,
            threads_per_worker=1,
            host="127.0.0.1",
            dashboard_address=None,
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = ff.sweep(spec, client=client, output=tmp_path / "dask.csv", progress=False)
    assert [r.without_timings() for r in remote] == [r.without_timings() for r in local]


def test_cli_sensitivity_and_correct(tmp_path, worked, capsys):
    plan, plan_path, robot = worked
    assert main(["sensitivity", str(plan_path), "--inertia-pct", "5"]) == 0
    out = capsys.readouterr().out
    assert "inertia 5 %" in out and "combined: RMS" in out and "link2" in out
    assert main(["sensitivity", str(plan_path), "--com-mm", "-3"]) == 2
    assert "--com-mm" in capsys.readouterr().err
    true = perturbed_robot(robot, {"base": {"inertia.izz": 66.67 * 1.05}})
    measured = np.degrees(zyx_from_quat(replay_attitude(plan, true).quaternion))
    output = tmp_path / "c.json"
    argv = ["correct", str(plan_path), "--base-zyx-deg", *map(str, measured), "-o", str(output)]
    capsys.readouterr()
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "freefloat plan:" not in printed  # the summary's header names its own command
    # its joints come back: beyond the bounds of simple motions, said as such
    assert "deg beyond (0.000, 0.000) deg of simple motions: this path goes back and forth" in (
        printed
    )
    assert any(
        line.startswith("freefloat correct: planar_2dof.urdf, T = ")
        for line in printed.splitlines()
    )
    assert ff.Plan.load(output).base.attitude_error_rad <= 1e-9
    # its joints end where they start: beyond the planar bounds of simple motions, (0, 0),
    # and judged on its own checks (verify once refused it for the bounds)
    capsys.readouterr()
    assert main(["verify", str(output)]) == 0, capsys.readouterr().err
    assert main(["correct", str(plan_path), "--base-zyx-deg", "0", "3", "0"]) == 2
    assert "this robot is planar" in capsys.readouterr().err


def test_correct_at_the_goal_writes_nothing(tmp_path, worked, capsys):
    """A measured attitude within the attitude tolerance (1e-9 rad) of the goal: nothing to do.

    Truth: the goal's yaw from the plan file, offset by hand (1e-8 deg = 1.7e-10 rad, within;
    1e-6 deg = 1.7e-8 rad, beyond, which plans a loop that turns back by that angle).
    """
    plan, plan_path, _ = worked
    yaw, pitch, roll = plan.base.target_zyx_deg
    output = tmp_path / "c.json"
    for offset in (0.0, 1e-8):
        argv = [str(yaw + offset), str(pitch), str(roll)]
        assert main(["correct", str(plan_path), "--base-zyx-deg", *argv, "-o", str(output)]) == 0
        printed = capsys.readouterr().out
        assert printed.startswith("freefloat correct: the measured attitude is ")
        tail = "within the attitude tolerance (5.73e-08 deg): nothing to correct, no plan written"
        assert tail in printed, printed
        assert not output.exists()
    argv = [str(yaw + 1e-6), str(pitch), str(roll)]
    assert main(["correct", str(plan_path), "--base-zyx-deg", *argv, "-o", str(output)]) == 0
    assert "turns the spacecraft back by 1e-06 deg" in capsys.readouterr().out
    assert ff.Plan.load(output).base.attitude_error_rad <= 1e-9


def test_a_correction_with_a_wild_second_root_verifies(tmp_path, worked, capsys):
    """Corrected from 179 deg, the worked example's search kept a second root whose path
    turned 617 rad: its residual was recorded from the solver's grid, and verify, which
    recomputes it on the plan's own, refused the written plan (3.9e-9 rad apart). Each
    root's residual is now recorded on the plan's grid. (Corrected from 150 deg, the
    search keeps three roots, of 27, 130 and 487 rad of joint travel.)"""
    _, plan_path, _ = worked
    output = tmp_path / "c.json"
    argv = ["correct", str(plan_path), "--base-zyx-deg", "150", "0", "0", "-o", str(output)]
    assert main([*argv, "-q"]) == 0
    corrected = ff.Plan.load(output)
    assert len(corrected.solver.solutions) > 1
    capsys.readouterr()
    assert main(["verify", str(output)]) == 0, capsys.readouterr().err


def test_the_robustness_record_is_recomputed_by_verify_and_old_plans_load(tmp_path, worked):
    plan, _, robot = worked
    recorded = with_robustness(plan, robot)
    found = plan_spread(plan, robot)
    assert recorded.robustness.rms_rad == found.rms and recorded.format == "freefloat.plan/5"
    path = recorded.save(tmp_path / "r.json")
    assert main(["verify", str(path)]) == 0
    data = json.loads(path.read_text())
    data["robustness"]["worst_rad"] *= 1.001
    tampered = tmp_path / "t.json"
    tampered.write_text(json.dumps(data))
    assert main(["verify", str(tampered)]) == 2
    older = recorded.to_dict()
    older = as_older_format(older)
    old = tmp_path / "old.json"
    old.write_text(json.dumps(older))
    loaded = ff.Plan.load(old)
    assert loaded.format == "freefloat.plan/3" and loaded.robustness is None
    assert json.loads(loaded.to_json())["format"] == "freefloat.plan/3"
    older["robustness"] = data["robustness"]  # a /3 file cannot hold the record
    old.write_text(json.dumps(older))
    assert main(["verify", str(old)]) == 2


def test_an_inertial_axis_of_a_scenario_sweep_plans_in_the_changed_model(tmp_path):
    from dataclasses import replace as with_field

    from freefloat.sweep import run_job

    path = tmp_path / "s.toml"
    path.write_text(
        'scenario = "worked_example"\nsamples = 21\n[[axis]]\n'
        'key = "robot.links.link2.mass"\nvalues = [30.0, 36.0]\n'
    )
    spec = SweepSpec.from_toml(path)
    nominal, heavier = (run_job(job) for job in spec.jobs())
    scenario = Scenario.from_toml(SCENARIOS / "worked_example.toml")
    base = ff.plan(scenario, samples=21)
    changed = with_field(scenario, robot=_reparsed(scenario.robot, {"link2": {"mass": 36.0}}))
    direct = ff.plan(changed, samples=21)
    assert nominal.path_length == pytest.approx(base.solver.solutions[0].path_length, rel=1e-12)
    assert heavier.path_length == pytest.approx(direct.solver.solutions[0].path_length, rel=1e-9)
    assert heavier.path_length != pytest.approx(nominal.path_length, rel=1e-3)


def test_cli_replay_sweep_prints_the_error_distribution(tmp_path, worked, capsys):
    from freefloat.robust import error_distribution

    _, plan_path, _ = worked
    body = (
        '[[axis]]\nkey = "robot.links.base.inertia.izz"\n'
        "values = { uniform = [60.0, 70.0], samples = 4, seed = 2 }\n"
    )
    path = _replay_sweep(tmp_path, plan_path, body)
    out = tmp_path / "mc.csv"
    assert main(["sweep", str(path), "-o", str(out), "--workers", "1"]) == 0
    printed = capsys.readouterr().out
    rows = list(csv.DictReader(out.open()))
    vectors = np.array([[float(r[f"error_{a}_rad"]) for a in "xyz"] for r in rows])
    found = error_distribution(vectors)
    assert found.count == 4 and found.largest == max(float(r["attitude_error_rad"]) for r in rows)
    assert f"mean {math.degrees(found.mean):.4g}" in printed and "replayed 4 of 4" in printed
    assert main(["sweep", str(path), "-o", str(out), "--plots", str(tmp_path / "p")]) == 2


def test_a_payload_axis_replays_the_plan_with_the_payload_changed(tmp_path):
    from freefloat.robot.payload import PAYLOAD_LINK
    from freefloat.sweep.replay import run_replay_job

    text = (SCENARIOS / "worked_example.toml").read_text().replace('robot = "planar_2dof"', "")
    urdf = robots_dir() / "planar_2dof.urdf"
    scenario_path = tmp_path / "held.toml"
    scenario_path.write_text(
        f'robot = "{urdf}"\n{text}\n[payload]\nmass = 20.0\ncom_xyz = [0.3, 0.0, 0.0]\n'
        "inertia = [0.5, 0.5, 0.5, 0.0, 0.0, 0.0]\n"
    )
    plan = ff.plan(Scenario.from_toml(scenario_path), samples=21)
    plan_path = plan.save(tmp_path / "held.plan.json")
    body = '[[axis]]\nkey = "payload.mass"\nvalues = [18.0, 22.0]\n'
    spec = SweepSpec.from_toml(_replay_sweep(tmp_path, plan_path, body))
    robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    for job in spec.jobs():
        row = run_replay_job(job)
        mass = job.changes["payload"]["mass"]
        direct = replay_attitude(plan, _reparsed(robot, {PAYLOAD_LINK: {"mass": mass}}))
        assert [row.error_x_rad, row.error_y_rad, row.error_z_rad] == pytest.approx(
            direct.error_rotvec.tolist(), abs=1e-12
        )
        assert row.attitude_error_rad > 1e-4  # 2 kg at the tip turns the base measurably
