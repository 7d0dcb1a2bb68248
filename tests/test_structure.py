"""The structure: constraints through the public interface, typed plans, pure scenarios, layers."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff

from legacy import as_format_3

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


@pytest.fixture
def registered(monkeypatch):
    """BelowOnJoint registered (one line), as a plan's constraint must be."""
    monkeypatch.setitem(ff.problem.constraints.CONSTRAINTS, BelowOnJoint.name, BelowOnJoint)


def test_a_toy_constraint_through_the_public_interface_is_honoured(registered):
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    free = ff.plan(scenario)
    assert max(np.array(free.samples.q)[:, 1]) > 1.9  # the minimum-norm root overshoots q2
    constraints = [*ff.default_constraints(), BelowOnJoint(1, 1.6)]
    held = ff.plan(scenario, constraints=constraints)
    path = held.path()
    assert path.extremes(1, 0)[1][0] <= 1.6 + 1e-9  # exact maximum of the polynomial
    assert "toy_ceiling" in held.verification
    assert held.base.attitude_error_rad < 1e-9
    # Another root of the same equation was chosen, not the minimum-norm one.
    assert held.free_parameters["q2"] != free.free_parameters["q2"]


def test_a_constraint_no_root_can_meet_is_a_clear_refusal(registered):
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    with pytest.raises(ff.SolverError) as info:
        ff.plan(scenario, constraints=[BelowOnJoint(1, 1.0)])
    assert "toy_ceiling" in str(info.value)
    assert "\n" not in str(info.value)


def test_an_unregistered_constraint_is_refused_before_any_work():
    scenario = ff.Scenario.from_toml(ff.default_scenario_path())
    with pytest.raises(
        ff.InputError, match=r"'toy_ceiling' \(BelowOnJoint\) is not in the registry"
    ):
        ff.plan(scenario, constraints=[BelowOnJoint(1, 1.6)])


def test_typed_round_trip(tmp_path, worked_plan):
    again = ff.Plan.load(worked_plan.save(tmp_path / "p.json"))
    assert again == worked_plan
    assert isinstance(again.verification, ff.Verification)
    assert all(isinstance(c, ff.Check) for c in again.verification.checks)
    assert again.request.start_joints == worked_plan.request.start_joints


def test_a_plan_file_of_format_1_still_loads_and_verify_recomputes(tmp_path, worked_plan):
    data = as_format_3(worked_plan.to_dict())
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
    assert solution.strategy == ff.Strategy.SCAN


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
    """robot -> physics -> problem -> solvers -> plans -> verify -> pipeline -> robust -> viz,
    export, sweep -> cli."""
    order = [
        "errors",
        "plugins",
        "files",
        "staged",
        "_exits",
        "progress",
        "parallel",
        "robot",
        "physics",
        "problem",
        "solvers",
        "plans",
        "verify",
        "pipeline",
        "robust",
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


#: No module beyond 400 lines and no function beyond 80 lines of code (docstring aside): no
#: exceptions.
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 80


def _code_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines from the first statement after the docstring to the last."""
    body = node.body
    first = body[0]
    if (
        isinstance(first, ast.Expr)
        and isinstance(first.value, ast.Constant)
        and isinstance(first.value.value, str)
        and len(body) > 1
    ):
        body = body[1:]
    return int(body[-1].end_lineno or body[-1].lineno) - body[0].lineno + 1


def test_no_module_is_too_long():
    too_long = {}
    for path in SRC.rglob("*.py"):
        name = path.relative_to(SRC).as_posix()
        lines = path.read_text().count("\n")
        if lines > MAX_MODULE_LINES:
            too_long[name] = lines
    assert not too_long, f"modules over {MAX_MODULE_LINES} lines: {too_long}"


def test_no_function_is_too_long():
    too_long = {}
    for path in SRC.rglob("*.py"):
        name = path.relative_to(SRC).as_posix()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = _code_lines(node)
                if lines > MAX_FUNCTION_LINES:
                    too_long[f"{name}:{node.name}"] = lines
    assert not too_long, f"functions over {MAX_FUNCTION_LINES} lines of code: {too_long}"


def test_no_module_claims_to_be_long_for_a_reason():
    """The old escape hatch is gone: a docstring no longer excuses a long module."""
    for path in SRC.rglob("*.py"):
        assert "is long because" not in (ast.get_docstring(ast.parse(path.read_text())) or "")


def test_method_document_exists_and_is_cited():
    doc = SRC.parents[1] / "docs" / "method.md"
    text = doc.read_text()
    for section in range(1, 9):
        assert f"## {section}." in text
    cited = [p for p in SRC.rglob("*.py") if "docs/method.md" in p.read_text()]
    assert len(cited) >= 5


# -- one list per plug-in kind: schemas and CLI agree with the registries ---------------------


def test_shipped_schemas_list_the_registries_plugins():
    """The shipped files hold the built-in registries' names (scripts/write_schemas.py)."""
    from freefloat.plans.schema import SCHEMAS, schema_text

    for name in SCHEMAS:
        shipped = (SRC / "schemas" / f"{name}.schema.json").read_text()
        assert shipped == schema_text(name), f"{name}: run scripts/write_schemas.py"


def test_schema_enums_follow_the_live_registries(monkeypatch):
    from freefloat.plans.schema import schema

    monkeypatch.setitem(ff.OBJECTIVES, "toy", ff.Objective)
    objective = schema("plan")["properties"]["objective"]["properties"]["name"]
    assert objective["enum"] == list(ff.OBJECTIVES)
    path = schema("scenario")["properties"]["path"]["properties"]["objective"]
    assert "toy" in path["enum"]


def test_cli_choices_are_the_registries():
    from freefloat.cli import build_parser
    from freefloat.export import EXPORTS

    parser = build_parser()
    commands = next(a for a in parser._actions if a.choices and "plan" in a.choices).choices
    objective = next(a for a in commands["plan"]._actions if "--objective" in a.option_strings)
    assert list(objective.choices) == list(ff.OBJECTIVES)
    export = next(a for a in commands["export"]._actions if "--format" in a.option_strings)
    assert export.help == " | ".join(EXPORTS)


def test_strategies_are_named_by_their_registry():
    from freefloat.solvers import STRATEGIES

    assert {s.value for s in ff.Strategy} - {"none"} == set(STRATEGIES)


# -- one description per file format: the dataclasses and the schema agree ----------------------


def _properties(schema: dict, path: tuple[str, ...]) -> tuple[set[str], set[str]]:
    node = schema
    for key in path:
        node = node[key]
    return set(node["properties"]), set(node.get("required", ()))


def _fields(cls) -> tuple[set[str], set[str]]:
    import dataclasses

    fields = dataclasses.fields(cls)
    required = {
        f.name
        for f in fields
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }
    return {f.name for f in fields}, required


def test_plan_records_and_the_plan_schema_name_the_same_fields():
    from freefloat import plans as fmt
    from freefloat.plans.schema import schema
    from freefloat.robot.collision import Obstacle

    plan = schema("plan")
    records = {
        ("properties", "robot"): fmt.RobotRef,
        ("properties", "base"): fmt.BaseReport,
        ("properties", "feasibility"): fmt.Feasibility,
        ("properties", "samples"): fmt.Samples,
        ("properties", "request"): fmt.Request,
        ("properties", "solver", "properties", "solutions", "items"): fmt.SolutionRecord,
        ("properties", "verification", "properties", "checks", "items"): fmt.Check,
        ("properties", "safety", "properties", "obstacles", "items"): Obstacle,
        ("properties", "objective", "properties", "levels", "items"): ff.problem.objectives.Level,
        ("properties", "constraints", "items"): fmt.ConstraintRecord,
    }
    for path, cls in records.items():
        names, required = _fields(cls)
        in_schema, schema_required = _properties(plan, path)
        in_schema.discard("passed")  # a check's verdict, written from its figures
        assert names == in_schema, (cls.__name__, names ^ in_schema)
        assert required == schema_required, (cls.__name__, required ^ schema_required)
    # records whose every field has a default: the schema requires what the file must state
    for path, cls in {
        ("properties", "solver"): fmt.SolverReport,
        ("properties", "safety"): fmt.SafetyReport,
        ("properties", "objective"): fmt.ObjectiveReport,
    }.items():
        names, _ = _fields(cls)
        in_schema, _ = _properties(plan, path)
        assert names == in_schema, (cls.__name__, names ^ in_schema)
    # the plan itself: its coefficients are the file's path, its verification the checks
    names, _ = _fields(fmt.Plan)
    top, _ = _properties(plan, ())
    # (the path's basis is path.basis, its quality record path_quality)
    assert (names - {"coefficients", "basis", "quality"}) | {"path", "path_quality"} == top, (
        names ^ top
    )


def test_plan_limits_are_the_schema_limits():
    from freefloat.plans import limits
    from freefloat.plans.schema import schema

    p = schema("plan")["properties"]
    assert p["robot"]["properties"]["joints"]["maxItems"] == limits.MAX_JOINTS
    assert p["duration"]["minimum"] == limits.MIN_DURATION
    assert p["duration"]["maximum"] == limits.MAX_DURATION
    # per format: basis coefficients (format 4 on), monomials before
    by_format = next(b for b in schema("plan")["allOf"] if "else" in b)
    basis = by_format["then"]["properties"]["path"]["properties"]["coefficients"]
    monomials = by_format["else"]["properties"]["path"]["properties"]["coefficients"]
    assert basis["additionalProperties"]["maxItems"] == limits.MAX_DEGREE - 5
    assert monomials["additionalProperties"]["maxItems"] == limits.MAX_DEGREE + 1
    assert p["samples"]["properties"]["t"]["maxItems"] == limits.MAX_SAMPLES
    assert p["solver"]["properties"]["solutions"]["maxItems"] == limits.MAX_SOLUTIONS
    steps = p["solver"]["properties"]["integration_steps"]["maximum"]
    assert steps == limits.MAX_INTEGRATION_STEPS
    note = p["objective"]["properties"]["levels"]["items"]["properties"]["note"]["maxLength"]
    assert note == ff.problem.objectives.base.MAX_NOTE


def test_scenario_keys_and_the_scenario_schema_name_the_same_keys():
    from freefloat.plans.schema import schema
    from freefloat.problem import payload_table
    from freefloat.problem import robot_table as rt
    from freefloat.problem import scenario_safety as ss
    from freefloat.problem import scenario_tables as sc

    s = schema("scenario")
    for path, keys in {
        (): sc.TOP_KEYS,
        ("properties", "path"): sc.PATH_KEYS,
        ("properties", "safety"): ss.SAFETY_KEYS,
        ("properties", "payload"): payload_table.PAYLOAD_KEYS,
        ("properties", "start"): sc.STATE_KEYS,
        ("properties", "goal"): sc.GOAL_KEYS,
        ("properties", "obstacles", "items"): ss.OBSTACLE_KEYS,
        ("properties", "robot", "oneOf", 1): rt._SERVICER_KEYS,
        ("properties", "robot", "oneOf", 2): rt._URDF_KEYS,
    }.items():
        node = s
        for key in path:
            node = node[key]
        assert set(node["properties"]) == set(keys), (path, set(node["properties"]) ^ set(keys))


def test_no_record_is_a_field_for_field_copy_of_another():
    """Every dataclass of the package (three fields or more) has its own set of field names."""
    import dataclasses
    import importlib
    import itertools
    import pkgutil

    records: dict[str, frozenset[str]] = {}
    for info in pkgutil.walk_packages(ff.__path__, "freefloat."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if isinstance(value, type) and dataclasses.is_dataclass(value):
                if value.__module__ != module.__name__:
                    continue
                fields = frozenset(f.name for f in dataclasses.fields(value))
                records[f"{value.__module__}.{value.__qualname__}"] = fields
    assert len(records) > 50  # the walk saw the package's records
    copies = [
        (a, b)
        for (a, fa), (b, fb) in itertools.combinations(records.items(), 2)
        if fa == fb and len(fa) >= 3
    ]
    assert not copies, copies
