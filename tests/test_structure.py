"""The structure: constraints through the public interface, typed plans, pure scenarios, layers."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff

SRC = Path(__file__).resolve().parents[1] / "src" / "freefloat"


class BelowOnJoint(ff.Constraint):
    """A toy constraint written only against the public interface: q_j(t) <= ceiling (rad)."""

    name = "toy_ceiling"
    unit = "rad"
    tolerance = 1e-9
    affine = True

    def __init__(self, joint: int, ceiling: float) -> None:
        self.joint, self.ceiling = joint, ceiling

    def rows(self, problem, beta, instants=ff.problem.constraints.DEFAULT_INSTANTS):
        base, dq, _ = problem.family.linear_map(np.asarray(instants, dtype=float))
        q = base.q[:, self.joint] + dq[:, self.joint, :] @ beta
        return ff.ConstraintRows(q - self.ceiling, dq[:, self.joint, :])

    def excess(self, robot, path):
        (_, _), (high, when) = path.extremes(self.joint, 0)
        return ff.Excess(high - self.ceiling, 0.0, f"t = {when:.3g} s")


def test_a_toy_constraint_through_the_public_interface_is_honoured():
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    free = ff.plan(scenario)
    assert max(np.array(free.samples.q)[:, 1]) > 1.9  # the minimum-norm root overshoots q2
    constraints = [*ff.default_constraints(), BelowOnJoint(1, 1.6)]
    held = ff.plan(scenario, constraints=constraints)
    path = ff.JointPolynomials.from_lists(
        [held.coefficients[n] for n in held.robot.joints], held.duration
    )
    assert path.extremes(1, 0)[1][0] <= 1.6 + 1e-9  # exact maximum of the polynomial
    assert held.verification["toy_ceiling"].passed
    assert held.base.attitude_error_rad < 1e-9
    # Another root of the same equation was chosen, not the minimum-norm one.
    assert held.free_parameters["q2"] != free.free_parameters["q2"]


def test_a_constraint_no_root_can_meet_is_a_clear_refusal():
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    with pytest.raises(ff.SolverError) as info:
        ff.plan(scenario, constraints=[BelowOnJoint(1, 1.0)])
    assert "toy_ceiling" in str(info.value)
    assert "\n" not in str(info.value)


def test_typed_round_trip(tmp_path, worked_plan):
    again = ff.Plan.load(worked_plan.save(tmp_path / "p.json"))
    assert again == worked_plan
    assert isinstance(again.verification, ff.Verification)
    assert all(isinstance(c, ff.Check) for c in again.verification.checks)
    assert again.request.start_joints == worked_plan.request.start_joints


def test_a_plan_file_of_format_1_still_loads_and_verify_recomputes(tmp_path, worked_plan):
    data = worked_plan.to_dict()
    data["format"] = "freefloat.plan/1"
    data["verification"] = {"passed": True, "momentum_max": 0.0}  # the old untyped section
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    old = ff.Plan.load(path)
    assert old.verification.checks == () and not old.verification.passed
    assert ff.verify_plan(old).passed


def test_solve_does_not_change_the_problem(planar_robot):
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    problem = ff.problem_from_scenario(scenario)
    before = (problem.steps, problem.family, problem.yaw_change)
    solution = ff.solve(problem)
    assert (problem.steps, problem.family, problem.yaw_change) == before
    assert solution.strategy is ff.Strategy.SCAN


def test_problem_from_scenario_equals_build_problem():
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    a = ff.problem_from_scenario(scenario)
    b = ff.build_problem(
        scenario.robot,
        scenario.start,
        scenario.goal,
        scenario.start_attitude,
        scenario.goal_attitude,
        scenario.duration,
        extra=scenario.extra,
    )
    beta = np.array([1e-4])
    np.testing.assert_array_equal(a.residual(beta), b.residual(beta))


def test_reading_an_inline_servicer_writes_nothing(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("FREEFLOAT_CACHE", str(cache))
    path = tmp_path / "s.toml"
    path.write_text(
        """
duration = 10.0
[robot]
arm = "ur5"
base_mass = 100.0
base_size = [0.6, 0.6, 0.6]
mount = [0.3, 0.0, 0.0]
mount_rpy_deg = [0.0, 90.0, 0.0]
[start]
joints = { shoulder_pan_joint = 0.0, shoulder_lift_joint = -60.0, elbow_joint = 90.0, \
wrist_1_joint = -30.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0 }
[goal]
end_effector_xyz = [0.9, 0.2, 0.3]
"""
    )
    scenario = ff.Scenario.from_toml(path)
    assert not cache.exists() or not any(cache.iterdir())  # nothing composed to disk yet
    assert scenario.goal_pose is not None and scenario.robot_text is not None
    resolved = scenario.resolved()  # inverse kinematics, explicitly
    assert resolved.goal_pose is None and len(resolved.goal) == 6
    written = scenario.write_robot()
    assert written.is_file() and ff.load_robot(written).n == 6


def _imports(path: Path) -> set[str]:
    """Modules of freefloat that ``path`` imports (absolute dotted names)."""
    package = ".".join(("freefloat", *path.relative_to(SRC).with_suffix("").parts))
    if path.name == "__init__.py":
        package = package.rsplit(".", 1)[0] + "._"
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package.split(".")[: -node.level]
            target = ".".join([*base, node.module] if node.module else base)
            out.add(target)
    return out


def test_layers_flow_one_way_and_no_circle():
    """robot -> physics -> problem -> solvers -> plans -> verify -> pipeline -> viz, export,
    sweep -> cli."""
    order = [
        "errors",
        "files",
        "progress",
        "robot",
        "physics",
        "problem",
        "solvers",
        "plans",
        "verify",
        "pipeline",
        "configuration",
        "reachable",
        "viz",
        "export",
        "sweep",
        "cli",
    ]
    for path in SRC.rglob("*.py"):
        if path.name == "__init__.py" and path.parent == SRC:
            continue
        layer = path.relative_to(SRC).parts[0].removesuffix(".py")
        for target in _imports(path):
            parts = target.split(".")
            if len(parts) < 2 or parts[1] not in order:
                continue
            assert order.index(parts[1]) <= order.index(layer), (
                f"{path.relative_to(SRC)} imports {target}: an arrow against the flow"
            )


def test_no_module_is_too_long_without_a_reason():
    for path in SRC.rglob("*.py"):
        lines = path.read_text().count("\n")
        doc = ast.get_docstring(ast.parse(path.read_text())) or ""
        assert lines <= 400 or "long because" in doc, f"{path.name}: {lines} lines"


def test_method_document_exists_and_is_cited():
    doc = SRC.parents[1] / "docs" / "method.md"
    text = doc.read_text()
    for section in range(1, 9):
        assert f"## {section}." in text
    cited = [p for p in SRC.rglob("*.py") if "docs/method.md" in p.read_text()]
    assert len(cited) >= 5
