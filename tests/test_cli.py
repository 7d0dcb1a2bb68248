"""The command line: summaries, exit codes, one-line errors, nothing half-written."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

import freefloat as ff
from freefloat.cli import main

import reference as ref
from test_errors import scenario_text


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_without_arguments_plans_the_worked_example(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, err = _run(capsys, "plan")
    assert code == 0, err
    plan_path = tmp_path / "freefloat-out" / "plan.json"
    data = json.loads(plan_path.read_text())
    assert data["format"] == "freefloat.plan/5"
    assert data["robustness"]["inertia_fraction"] == 0.1 and data["robustness"]["rms_rad"] > 0
    # the paper's b26 = -0.552e-4 rad/s^6 is -sqrt(12012) beta / T^6 (docs/method.md section 4)
    b26 = -math.sqrt(12012.0) * data["free_parameters"]["q2"][0] / 10.0**6
    assert b26 == pytest.approx(-0.552e-4, rel=0.01)
    assert "achieved" in out and "attitude error" in out and "t^6 -5.518" in out
    assert "deviation from the quintic 28.8 deg RMS" in out and "path quality" in out
    assert str(plan_path) in out
    html = tmp_path / "freefloat-out" / "plan.html"
    assert html.stat().st_size > 100_000 and str(html) in out
    plots = sorted(p.name for p in (tmp_path / "freefloat-out" / "plots").glob("*.png"))
    assert "overview.png" in plots and len(plots) == 8


def test_plan_file_has_the_documented_keys(tmp_path, capsys):
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text())
    code, _, err = _run(capsys, "plan", str(scenario), "-o", str(tmp_path / "out.json"))
    assert code == 0, err
    data = json.loads((tmp_path / "out.json").read_text())
    assert {
        "format",
        "robot",
        "duration",
        "path",
        "free_parameters",
        "base",
        "feasibility",
        "samples",
        "solver",
    } <= set(data)
    assert set(data["robot"]) >= {"urdf", "joints", "end_effector"}
    assert data["path"]["family"] == "polynomial"
    assert set(data["base"]) >= {
        "start_quaternion_xyzw",
        "target_quaternion_xyzw",
        "achieved_quaternion_xyzw",
        "start_zyx_deg",
        "target_zyx_deg",
        "achieved_zyx_deg",
        "attitude_error_rad",
    }
    assert set(data["feasibility"]) == {
        "planar",
        "yaw_change_bounds_deg",
        "requested_yaw_change_deg",
    }
    assert set(data["samples"]) >= {
        "t",
        "q",
        "qd",
        "qdd",
        "base_position",
        "base_quaternion_xyzw",
        "base_zyx_deg",
        "end_effector_position",
    }
    assert set(data["solver"]) >= {
        "method",
        "iterations",
        "evaluations",
        "residual_rad",
        "wall_time_s",
        "solutions",
    }
    assert len(data["samples"]["t"]) == 201


def test_default_output_name_next_to_cwd(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mission.toml").write_text(scenario_text())
    code, _, _ = _run(capsys, "plan", "mission.toml")
    assert code == 0
    assert (tmp_path / "mission.plan.json").is_file()


def test_infeasible_request_exits_2_and_writes_nothing(tmp_path, capsys):
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text(yaw="40.0"))  # a 90 deg yaw change
    out_file = tmp_path / "never.json"
    code, _, err = _run(capsys, "plan", str(scenario), "-o", str(out_file))
    assert code == 2
    assert err.count("\n") == 1
    assert err.startswith(
        "freefloat: error: requested yaw change 90.000 deg is outside the "
        f"reachable interval {ref.worked_bounds_text()} deg"
    )
    assert not out_file.exists() and list(tmp_path.iterdir()) == [scenario]


def test_solver_failure_exits_2(tmp_path, capsys):
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text(path="[path]\nextra = { q2 = 1 }\nmax_deviation_deg = 1.0"))
    code, _, err = _run(capsys, "plan", str(scenario), "-o", str(tmp_path / "p.json"))
    assert code == 2
    assert "reaches the goal attitude (best residual" in err
    assert not (tmp_path / "p.json").exists()


def test_bad_scenario_exits_2(tmp_path, capsys):
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text(goal="q1 = 1.0, wrist = 2.0"))
    code, _, err = _run(capsys, "plan", str(scenario))
    assert code == 2
    assert "unknown joint 'wrist'; valid: q1, q2" in err and err.count("\n") == 1


def test_bounds_command(capsys):
    code, out, _ = _run(capsys, "bounds")
    assert code == 0
    # the interval from the closed form on a dense grid (tests/reference.py), as printed
    assert f"reachable yaw change: {ref.worked_bounds_text()} deg" in out
    assert "requested yaw change: 50.000 deg -> feasible" in out


def test_bounds_plot_of_a_planar_robot_is_refused_not_dropped(tmp_path, capsys):
    """A planar robot has no estimate to draw: --plot is refused in one line (exit 2, nothing
    printed, nothing written) rather than silently ignored."""
    figure = tmp_path / "bounds.png"
    assert main(["bounds", "--plot", str(figure)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "freefloat reach --plot" in err
    assert not figure.exists()


@pytest.mark.parametrize("command", ["reach", "bounds"])
@pytest.mark.parametrize("name", ["figure.txt", "figure"])
def test_a_figure_not_named_for_its_format_is_refused_before_any_work(
    tmp_path, capsys, command, name
):
    """``--plot x.txt`` raised matplotlib's traceback after the work; ``--plot x`` wrote
    ``x.png``. Both are refused first, in one line, nothing printed or written."""
    figure = tmp_path / name
    assert main([command, "--plot", str(figure)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "a figure is written as PNG, SVG or PDF" in err
    assert list(tmp_path.iterdir()) == []


def test_bounds_of_an_infeasible_request_reports_it(tmp_path, capsys):
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text(yaw="40.0"))
    code, out, _ = _run(capsys, "bounds", str(scenario))
    assert code == 0
    assert "requested yaw change: 90.000 deg -> outside the bounds" in out


@pytest.mark.parametrize("command", [[], ["plan"], ["bounds"]])
def test_help(command):
    result = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", *command, "--help"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0
    assert "usage: freefloat" in result.stdout


def test_plan_help_states_the_default_tolerance_in_both_units(capsys):
    """The default attitude tolerance is 1e-9 rad (docs/reference.md); its degrees in the help
    are that value's conversion (180/pi), to the three digits printed."""
    assert main(["plan", "--help"]) == 0
    said = " ".join(capsys.readouterr().out.split())
    found = re.search(
        r"--tolerance-deg DEG attitude tolerance in deg \(default (\S+) deg, that is (\S+) rad\)",
        said,
    )
    assert found is not None, said
    assert float(found[2]) == 1e-9
    assert found[1] == "5.73e-08" and abs(float(found[1]) - 1e-9 * 180 / math.pi) < 5e-11


def test_console_script_exit_code(tmp_path):
    """The installed entry point: a real process, a real exit code, no traceback."""
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text(duration="-1"))
    exe = Path(sys.executable).parent / "freefloat"
    assert exe.is_file(), "the console script is installed next to the interpreter"
    cmd = [str(exe)]
    result = subprocess.run(
        [*cmd, "plan", str(scenario)], capture_output=True, text=True, check=False
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().endswith("duration must be > 0 s, got -1")


def test_api_round_trip_matches_cli(tmp_path, worked_plan):
    path = worked_plan.save(tmp_path / "x.json")
    assert ff.Plan.load(path).free_parameters == worked_plan.free_parameters


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["show", "{plan}", "--html", ""], "--html needs a file name, got an empty one"),
        (["plan", "-o", ""], "-o needs a file name, got an empty one"),
        (["show", "{plan}", "--html", "{plan}"], "is the file this command reads"),
        (["export", "{plan}", "--format", "csv", "-o", "{plan}"], "is the file this command reads"),
        (["correct", "{plan}", "--base-zyx-deg", "1", "0", "0", "-o", "{plan}"], "reads"),
        (["plan", "{scenario}", "-o", "{scenario}"], "is the file this command reads"),
        (["plan", "{missing}", "-o", "{plan}"], "scenario file not found"),  # not the output
    ],
)
def test_an_empty_output_name_or_one_that_is_the_input_is_refused(
    tmp_path, capsys, worked_plan, argv, option
):
    """``show --html ""`` started the server (and hung); ``--html plan.json`` overwrote the
    plan it shows. Each is refused in one line, and the input stays as it was."""
    plan = worked_plan.save(tmp_path / "plan.json")
    scenario = tmp_path / "s.toml"
    scenario.write_text(scenario_text())
    kept = {p: p.read_bytes() for p in (plan, scenario)}
    filled = [a.format(plan=plan, scenario=scenario, missing=tmp_path / "no.toml") for a in argv]
    assert main(filled) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option in err
    assert {p: p.read_bytes() for p in kept} == kept
