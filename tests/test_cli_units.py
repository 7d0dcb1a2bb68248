"""Degrees at the command line's edge: ``plan --tolerance-deg`` and the deprecated rad option."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

import freefloat.cli.plan as plan_command
from freefloat.cli import main

SRC = Path(__file__).resolve().parents[1] / "src"


class _StopError(Exception):
    """Raised by the stand-in planner once it has seen its options."""


@pytest.fixture
def seen(monkeypatch):
    """The SolveOptions ``freefloat plan`` hands the planner (which then stops the run)."""
    options = []

    def fake_plan(scenario, solve_options, **kwargs):
        options.append(solve_options)
        raise _StopError

    monkeypatch.setattr(plan_command, "plan", fake_plan)
    return options


def _planned_tolerance(seen, capsys, *argv):
    with pytest.raises(_StopError):
        main(["plan", *argv])
    (options,) = seen
    return options.tolerance, capsys.readouterr().err


@pytest.mark.parametrize("degrees", [5.72958e-10, 1e-8, 5.72958e-8, 1e-6, 5.72958e-6])
def test_tolerance_deg_is_converted_to_rad(seen, capsys, degrees):
    tolerance, err = _planned_tolerance(seen, capsys, "--tolerance-deg", str(degrees))
    # the printed ends of the range (six digits) are held to the range's ends
    truth = min(max(degrees * math.pi / 180.0, 1e-11), 1e-7)
    assert tolerance == pytest.approx(truth, rel=1e-15) and err == ""


def test_degree_and_rad_options_give_the_same_tolerance(seen, capsys):
    by_degrees, _ = _planned_tolerance(seen, capsys, "--tolerance-deg", "2e-7")
    seen.clear()
    by_radians, _ = _planned_tolerance(seen, capsys, "--tolerance", str(math.radians(2e-7)))
    assert by_degrees == pytest.approx(by_radians, rel=1e-15)


def test_default_tolerance_is_unchanged(seen, capsys):
    tolerance, err = _planned_tolerance(seen, capsys)
    assert tolerance == 1e-9 and err == ""


def test_rad_option_still_works_and_says_it_is_deprecated(seen, capsys):
    tolerance, err = _planned_tolerance(seen, capsys, "--tolerance", "3e-9")
    assert tolerance == 3e-9  # what an old call computed, exactly
    assert err == (
        f"freefloat: warning: --tolerance is in rad and deprecated; give --tolerance-deg "
        f"{3e-9 * 180 / math.pi:g} instead\n"
    )


def test_rad_option_deprecation_is_quiet_with_q(seen, capsys):
    tolerance, err = _planned_tolerance(seen, capsys, "-q", "--tolerance", "3e-9")
    assert tolerance == 3e-9 and err == ""


def _refusal(capsys, *argv):
    code = main(["plan", *argv])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("freefloat: error: "), err
    return err.strip()


def test_both_tolerance_options_are_refused(seen, capsys):
    line = _refusal(capsys, "--tolerance-deg", "1e-7", "--tolerance", "1e-9")
    assert line == (
        "freefloat: error: give the attitude tolerance once: --tolerance-deg DEG (or the "
        "deprecated --tolerance RAD), not both"
    )
    assert seen == []


def test_both_tolerance_options_exit_2_without_traceback_from_the_console(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    argv = ["plan", "--tolerance", "1e-9", "--tolerance-deg", "1e-7"]
    done = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", *argv],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr and not any(tmp_path.iterdir())
    assert done.stderr.startswith("freefloat: error: give the attitude tolerance once")


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (
            ["--tolerance-deg", "1e-3"],
            "--tolerance-deg = 0.001 deg is outside the supported range "
            f"[{1e-11 * 180 / math.pi:g}, {1e-7 * 180 / math.pi:g}] deg",
        ),
        (["--tolerance-deg", "nan"], "--tolerance-deg = nan deg is outside"),
        (["--tolerance-deg", "5.8e-6"], "--tolerance-deg = 5.8e-06 deg is outside"),
        (
            ["--tolerance", "1e-3"],
            "--tolerance = 0.001 rad is outside the supported range [1e-11, 1e-07] rad",
        ),
    ],
)
def test_range_errors_are_in_the_unit_typed(seen, capsys, argv, needle):
    assert needle in _refusal(capsys, *argv)
    assert seen == []


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["plan", "--tolerance-deg", "-1e-3"], "--tolerance-deg = -0.001 deg is outside"),
        (
            ["correct", "absent.json", "--base-zyx-deg", "-1e9", "0", "0"],
            "--base-zyx-deg = -1e+09 deg is outside the supported range [-3600, 3600] deg",
        ),
        (
            ["correct", "absent.json", "--base-zyx-deg", "0", "-2.5E+4", "0"],
            "--base-zyx-deg = -25000 deg is outside",
        ),
    ],
)
def test_negative_numbers_in_exponent_notation_are_values(
    tmp_path, monkeypatch, capsys, argv, needle
):
    """Not options: argparse's own pattern reads ``-1e9`` as one ("expected 3 arguments")."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and needle in err, err
    assert not any(tmp_path.iterdir())


def test_names_an_ascii_terminal_cannot_show_are_escaped_not_a_traceback(tmp_path):
    """Joints named in Chinese, printed with an ASCII encoding (``LC_ALL=C``): ``check``,
    ``plan`` and others raised UnicodeEncodeError (exit 1), ``plan`` after writing its file."""
    root = SRC.parent
    urdf = (root / "robots" / "planar_2dof.urdf").read_text(encoding="utf-8")
    scenario = (root / "robots" / "scenarios" / "worked_example.toml").read_text()
    for old, new in {"q1": "关节一", "q2": "关节二"}.items():
        urdf = urdf.replace(f'"{old}"', f'"{new}"')
        scenario = scenario.replace(f"{old} =", f'"{new}" =')
    (tmp_path / "cjk.urdf").write_text(urdf, encoding="utf-8")
    lines = ['robot = "cjk.urdf"' if s.startswith("robot =") else s for s in scenario.splitlines()]
    (tmp_path / "cjk.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(SRC), "PYTHONIOENCODING": "ascii"}
    done = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", "check", "cjk.toml"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        encoding="ascii",
    )
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert "\\u5173\\u8282\\u4e00" in done.stdout  # the name, escaped


def test_an_output_is_never_the_robot_a_scenario_or_plan_reads(tmp_path, monkeypatch, capsys):
    """``plan -o r.urdf`` replaced the scenario's own robot with the plan; export, show and
    correct did the same through a plan's URDF, compose an arm's SRDF through its own."""
    import json
    import shutil

    root = SRC.parent
    monkeypatch.chdir(tmp_path)
    shutil.copy(root / "robots" / "planar_2dof.urdf", "r.urdf")
    text = (root / "robots" / "scenarios" / "worked_example.toml").read_text()
    Path("s.toml").write_text(text.replace('robot = "planar_2dof"', 'robot = "r.urdf"'))
    original = Path("r.urdf").read_bytes()
    assert main(["plan", "s.toml", "-o", "p.json", "-q"]) == 0
    capsys.readouterr()
    for argv in (
        ["plan", "s.toml", "-o", "r.urdf"],
        ["export", "p.json", "--format", "csv", "-o", "r.urdf"],
        ["show", "p.json", "--html", "r.urdf"],
        ["correct", "p.json", "--base-zyx-deg", "1", "0", "0", "-o", "r.urdf"],
    ):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert (
            err.count("\n") == 1 and "r.urdf is a file this command reads (the robot's URDF)" in err
        )
    assert Path("r.urdf").read_bytes() == original
    # a scenario with a [payload] loads a decorated copy: the file it names is still read
    held = Path("s.toml").read_text() + "[payload]\nmass = 1.0\nbox = [0.1, 0.1, 0.1]\n"
    Path("held.toml").write_text(held)
    assert main(["plan", "held.toml", "-o", "r.urdf"]) == 2
    assert "r.urdf is a file this command reads" in capsys.readouterr().err
    # a plan whose URDF path is relative, read from another folder
    Path("sub").mkdir()
    shutil.copy("r.urdf", "sub/r.urdf")
    doc = json.loads(Path("p.json").read_text())
    doc["robot"]["urdf"] = "r.urdf"
    Path("sub/p.json").write_text(json.dumps(doc))
    assert main(["export", "sub/p.json", "--format", "csv", "-o", "sub/r.urdf"]) == 2
    assert "sub/r.urdf is a file this command reads" in capsys.readouterr().err
    assert Path("r.urdf").read_bytes() == Path("sub/r.urdf").read_bytes() == original
    Path("a.urdf").write_bytes(original)
    Path("a.srdf").write_text(
        '<robot name="a"><disable_collisions link1="link1" link2="link2"/></robot>'
    )
    kept = Path("a.srdf").read_bytes()
    argv = ["compose", "--arm", "a.urdf", "--mount", "0.5", "0", "0", "--arm", "ur5", "--mount"]
    argv += ["-0.5", "0", "0", "--base-mass", "100", "--base-size", "1", "1", "1", "-o", "a.xml"]
    assert main(argv) == 2
    assert "-o a.xml (and a.srdf beside it) is a file this command reads (an arm's SRDF)" in (
        capsys.readouterr().err
    )
    assert Path("a.srdf").read_bytes() == kept and not Path("a.xml").exists()


@pytest.mark.parametrize(
    ("edit", "said"),
    [
        (
            lambda s, u: s.replace(f'robot = "{u}"', 'robot = "https://example.com/x.urdf"'),
            "robot 'https://example.com/x.urdf' is a URL; give a shipped robot name or the path",
        ),
        (
            lambda s, u: s + '\n[safety]\nsrdf = "/tmp"\n',
            "srdf /tmp is not a regular file (a folder",
        ),
        (
            lambda s, u: s.replace(
                "base_zyx_deg = [0.0, 0.0, 0.0]", "base_zyx_deg = [310.0, 0.0, 0.0]"
            ),
            "requested yaw change 0.000 deg is outside",
        ),  # a whole turn from the start: not -0.000
        (
            lambda s, u: (
                s.replace(f'robot = "{u}"', "") + f'[robot]\nurdf = "{u}"\nlock = ["q1", "q2"]\n'
            ),
            "[robot] lock locks every movable joint (q1, q2); leave at least one to move",
        ),
        (  # locked at 30 then 45 deg: the last won, silently
            lambda s, u: (
                s.replace(f'robot = "{u}"', "")
                + f'[robot]\nurdf = "{u}"\nlock = [{{ joint = "q2", value = 30.0 }}, '
                '{ joint = "q2", value = 45.0 }]\n'
            ),
            "[robot] lock names joint 'q2' twice; lock each joint once",
        ),
        (
            lambda s, u: (
                s.replace(f'robot = "{u}"', "")
                + f'[robot]\nurdf = "{u}"\nlock = ["q2", {{ joint = "q2", value = 45.0 }}]\n'
            ),
            "[robot] lock names joint 'q2' twice; lock each joint once",
        ),
    ],
)
def test_messages_from_the_hostile_trial_say_what_is_wrong(tmp_path, capsys, edit, said):
    root = SRC.parent
    urdf = str(root / "robots" / "planar_2dof.urdf")
    text = (root / "robots" / "scenarios" / "worked_example.toml").read_text()
    text = text.replace('robot = "planar_2dof"', f'robot = "{urdf}"')
    text = text.replace("[safety]\ncheck = false", "")  # some edits add their own table
    (tmp_path / "s.toml").write_text(edit(text, urdf))
    assert main(["plan", str(tmp_path / "s.toml"), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err, err


def test_equal_joint_limits_suggest_a_fixed_joint(tmp_path, capsys):
    urdf = (SRC.parent / "robots" / "planar_2dof.urdf").read_text()
    joint = '<joint name="q2" type="continuous">'
    assert joint in urdf
    urdf = urdf.replace(joint, joint.replace("continuous", "revolute"))
    axis = '<axis xyz="0 0 1"/>'
    start = urdf.index(axis, urdf.index('name="q2"')) + len(axis)
    limit = '<limit lower="0.5" upper="0.5" effort="10" velocity="1"/>'
    (tmp_path / "r.urdf").write_text(urdf[:start] + limit + urdf[start:])
    text = (SRC.parent / "robots" / "scenarios" / "worked_example.toml").read_text()
    (tmp_path / "s.toml").write_text(text.replace('robot = "planar_2dof"', 'robot = "r.urdf"'))
    assert main(["check", str(tmp_path / "s.toml")]) == 2
    err = capsys.readouterr().err
    assert "has limits [0.5, 0.5]; lower must be below upper; a joint that cannot move is" in err


def test_a_script_calling_main_keeps_its_own_stream_settings(capsys):
    """main() escapes what the streams cannot encode while it runs, and puts their error
    handling back: a caller's later prints behave as before."""
    import sys

    before = (sys.stdout.errors, sys.stderr.errors)
    assert "backslashreplace" not in before
    assert main(["--version"]) == 0
    assert (sys.stdout.errors, sys.stderr.errors) == before
