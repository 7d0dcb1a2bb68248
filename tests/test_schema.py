"""The shipped JSON Schemas: shipped scenarios and fresh plans validate; bad fields are named."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import jsonschema
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.plans.schema import SCHEMAS, check_plan_file, schema, schema_errors

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((ROOT / "robots" / "scenarios").glob("*.toml"))


@pytest.mark.parametrize("name", SCHEMAS)
def test_schemas_are_valid_draft_2020_12(name):
    jsonschema.Draft202012Validator.check_schema(schema(name))


def test_schemas_ship_inside_the_package():
    folder = Path(ff.__file__).parent / "schemas"
    assert sorted(p.name for p in folder.glob("*.json")) == [
        "plan.schema.json",
        "scenario.schema.json",
    ]
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["tool"]["hatch"]["build"]["targets"]["wheel"]["packages"] == ["src/freefloat"]


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_shipped_scenarios_validate(path):
    assert SCENARIOS
    data = tomllib.loads(path.read_text())
    assert schema_errors(data, "scenario") == []
    jsonschema.validate(data, schema("scenario"))


def test_inline_servicer_and_cartesian_scenario_validate():
    data = {
        "robot": {"arm": "panda", "base_mass": 100.0, "base_size": [0.6, 0.6, 0.6]},
        "duration": 20.0,
        "start": {"joints": {"panda_joint1": 0.0}},
        "goal": {"end_effector_xyz": [0.5, 0.1, 0.3]},
    }
    assert schema_errors(data, "scenario") == []
    data["goal"] = {"base_zyx_deg": [0, 0, 0]}
    assert schema_errors(data, "scenario")
    data["goal"] = {"joints": {"a": 1.0}}
    data["robot"]["base_mass"] = "heavy"
    assert schema_errors(data, "scenario") == ["robot.base_mass: expected a number, got 'heavy'"]


def test_fresh_plan_validates(worked_plan, tmp_path):
    assert schema_errors(json.loads(worked_plan.to_json()), "plan") == []
    check_plan_file(worked_plan.save(tmp_path / "plan.json"))


def _broken(worked_plan, tmp_path, change):
    data = json.loads(worked_plan.to_json())
    change(data)
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda d: d["samples"]["tau"][3].__setitem__(1, "x"),
            "samples.tau[3][1]: expected a number",
        ),
        (lambda d: d["base"].pop("attitude_error_rad"), "base.attitude_error_rad: missing"),
        (lambda d: d.__setitem__("duration", -1.0), "duration: "),
        (lambda d: d["robot"].__setitem__("joints", "q1"), "robot.joints: expected a list"),
        (
            lambda d: d["samples"]["base_position"][0].pop(),
            "samples.base_position[0]: expected at least 3 entries",
        ),
        (lambda d: d["robot"].__setitem__("colour", "red"), "robot: unknown key 'colour'"),
    ],
)
def test_verify_names_the_bad_field(worked_plan, tmp_path, capsys, change, message):
    path = _broken(worked_plan, tmp_path, change)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("freefloat: error: ")
    assert "does not match the plan schema" in err[0] and message in err[0], err[0]


@pytest.mark.parametrize(
    "argv",
    [
        ["verify"],
        ["sensitivity"],
        ["correct", "--base-zyx-deg", "1", "0", "0"],
        ["export", "--format", "csv", "-o", "out.csv"],
    ],
)
def test_a_negative_margin_is_named_by_every_command_that_reads_a_plan(
    worked_plan, tmp_path, capsys, monkeypatch, argv
):
    """A clearance margin below 0 m raised a traceback from verify, correct, sensitivity and
    export (the last three read the file without its schema)."""
    monkeypatch.chdir(tmp_path)
    path = _broken(worked_plan, tmp_path, lambda d: d["safety"].__setitem__("margin_m", -1.0))
    assert main([argv[0], str(path), *argv[1:]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "safety.margin_m: -1.0 is less than the minimum of 0" in err[0]
    assert not (tmp_path / "out.csv").exists() and not path.with_suffix(".correct.json").exists()


def test_a_payload_given_as_a_box_validates_as_the_loader_reads_it(tmp_path):
    """The loader takes a payload's inertia or a box (a uniform box's inertia); the schema
    asked for inertia alone, so a scenario ``plan`` reads was invalid by the schema."""
    text = (ROOT / "robots" / "scenarios" / "panda_servicer.toml").read_text()
    text = text.replace(
        'robot = "panda_servicer"', f'robot = "{ROOT / "robots"}/panda_servicer.urdf"'
    )
    tables = {
        "mass = 5.0\nbox = [0.2, 0.2, 0.2]\n": [],
        "mass = 5.0\ninertia = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]\n": [],
        "mass = 5.0\n": ["payload: give 'inertia' or 'box'"],
    }
    for table, errors in tables.items():
        path = tmp_path / "held.toml"
        path.write_text(text + "\n[payload]\n" + table)
        assert schema_errors(tomllib.loads(path.read_text()), "scenario") == errors
        if errors:
            with pytest.raises(ff.ScenarioError, match=r"\[payload\] needs inertia"):
                ff.Scenario.from_toml(path)
        else:
            assert ff.Scenario.from_toml(path).payload is not None
