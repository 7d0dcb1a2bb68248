"""Packaging: public names, version, shipped data in the wheel, CI runs the README's command."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
import sys
import zipfile

import pytest

import freefloat as ff

from conftest import ROOT


def test_every_public_name_imports():
    for name in ff.__all__:
        assert getattr(ff, name) is not None, name


def test_version_has_one_source():
    assert importlib.metadata.version("freefloat") == ff.__version__
    assert "version =" not in (ROOT / "pyproject.toml").read_text().split("[tool")[0]


def test_core_never_imports_viewers():
    code = (
        "import sys, freefloat, freefloat.cli; "
        "print(sorted(m for m in ('meshcat', 'matplotlib') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _readme_commands():
    return re.findall(r"```bash\n(.+?)\n```", (ROOT / "README.md").read_text())


def test_ci_runs_the_readme_test_command():
    commands = _readme_commands()
    assert len(commands) >= 2
    install_and_run, install_and_test = commands[0], commands[1]
    assert "freefloat plan" in install_and_run and "pytest" in install_and_test
    ci = (ROOT / ".ci" / "run").read_text()
    assert install_and_test in ci
    assert '"$status" -eq 5' in ci  # no tests collected is a failure


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(ROOT)],
        check=True,
        capture_output=True,
    )
    (path,) = out.glob("freefloat-*.whl")
    return path


def test_wheel_ships_robots_scenarios_and_types(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert "freefloat/robots/planar_2dof.urdf" in names
    assert "freefloat/robots/scenarios/worked_example.toml" in names
    assert "freefloat/py.typed" in names
    assert "freefloat/schemas/plan.schema.json" in names
    assert "freefloat/schemas/scenario.schema.json" in names


def test_installed_copy_plans_the_shipped_example(wheel, tmp_path):
    """Unpacked wheel on the path, no checkout: the shipped robot resolves from package data."""
    zipfile.ZipFile(wheel).extractall(tmp_path / "site")
    code = (
        "import freefloat as ff; p = ff.default_scenario_path(); "
        "print(p); s = ff.Scenario.from_toml(p); print(s.robot.urdf)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
        env={"PYTHONPATH": str(tmp_path / "site")},
    )
    lines = out.stdout.split()
    assert all(line.startswith(str(tmp_path / "site")) for line in lines)


def test_plan_format_module_is_strictly_typed():
    """The plan file format passes ``mypy --strict`` (typed records, no bare dicts of Any)."""
    mypy = pytest.importorskip("mypy.api")
    out, err, status = mypy.run(
        ["--strict", str(ROOT / "src" / "freefloat" / "plans" / "format.py")]
    )
    assert status == 0, out + err
