"""A scenario given where a plan is read, or a plan where a scenario is read: a hint."""

from __future__ import annotations

import json

import pytest

import freefloat as ff
from freefloat.cli import main


@pytest.fixture
def scenario_text() -> str:
    return ff.default_scenario_path().read_text()


@pytest.mark.parametrize("name", ["scenario.toml", "scenario.txt"])
def test_verify_of_a_scenario_suggests_plan(tmp_path, capsys, scenario_text, name):
    path = tmp_path / name
    path.write_text(scenario_text)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err
    assert "not a plan file, corrupt JSON" in err
    assert err.rstrip().endswith(
        f"; it looks like a scenario file (TOML): freefloat plan {path} plans it"
    )
    assert len(err.splitlines()) == 1


@pytest.mark.parametrize("name", ["plan.json", "plan.txt"])
def test_plan_of_a_plan_file_suggests_verify(tmp_path, capsys, name):
    path = tmp_path / name
    path.write_text(json.dumps({"format": "freefloat.plan/4", "duration": 10.0}, indent=1))
    assert main(["plan", str(path), "-o", str(tmp_path / "out.json")]) == 2
    err = capsys.readouterr().err
    assert "invalid TOML" in err
    assert f"; it looks like a plan file (JSON): freefloat verify {path} checks it" in err
    assert len(err.splitlines()) == 1 and not (tmp_path / "out.json").exists()


def test_no_hint_for_a_file_of_neither_kind(tmp_path, capsys):
    path = tmp_path / "notes.txt"
    path.write_text("= not json and not toml\n")
    assert main(["verify", str(path)]) == 2
    assert main(["plan", str(path)]) == 2
    assert "looks like" not in capsys.readouterr().err


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("README.md", "# freefloat\n\nPlans motions.\n"),
        ("pyproject.toml", '[project]\nname = "demo"\nversion = "0.1"\n'),
    ],
)
def test_verify_of_markdown_or_other_toml_suggests_no_scenario(tmp_path, capsys, name, text):
    """Only TOML with a ``robot`` key is called a scenario: a README or a project file that
    ``freefloat plan`` could not read gets no hint to plan it."""
    path = tmp_path / name
    path.write_text(text)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err
    assert "not a plan file, corrupt JSON" in err and "looks like" not in err


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("deep.toml", "a = " + "[" * 100_000 + "]" * 100_000 + "\n"),  # nested past recursion
        ("big.toml", 'robot = "planar_2dof"\n' + "# padding\n" * 110_000),  # > 1 MB
    ],
)
def test_a_hostile_would_be_scenario_gets_one_line_and_no_hint(tmp_path, capsys, name, text):
    """A file nested too deeply for the TOML parser, or larger than any scenario may be: the
    hint is left out (nothing parsed), and the refusal is one line with exit code 2."""
    path = tmp_path / name
    path.write_text(text)
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "not a plan file" in err and "looks like" not in err
