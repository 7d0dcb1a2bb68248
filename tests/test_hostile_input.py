"""Hostile input (issue 14): every expected failure is one line, exit code 2, nothing written,
no traceback, within seconds; the stated limits are named in the messages."""

from __future__ import annotations

import os
import stat
import time
from pathlib import Path

import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import excerpt
from freefloat.files import check_output, read_text_file
from freefloat.problem import limits

import urdfs
from conftest import ROOT
from test_errors import scenario_text

PLANAR = ROOT / "robots" / "planar_2dof.urdf"


def _refused(capsys, *argv, within=10.0):
    """Run the command in-process; it must refuse in one line, quickly. Return the line."""
    start = time.perf_counter()
    code = main([str(a) for a in argv])
    elapsed = time.perf_counter() - start
    _, err = capsys.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("freefloat: error: "), err[:500]
    assert "Traceback" not in err and len(err) < 400, err[:500]
    assert elapsed < within, f"{elapsed:.1f} s"
    return err.strip()


def _scenario(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# -- scenario numbers --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (
            {"duration": "1e-300"},
            "duration = 1e-300 s is outside the supported range [0.001, 1e+06] s",
        ),
        ({"duration": "1e300"}, "duration = 1e+300 s is above the supported maximum 1e+06 s"),
        ({"duration": "9" * 400}, "duration = 999999999999... (400 digits) s is above"),
        (
            {"goal": "q1 = 1e300, q2 = 0.0"},
            "[goal] joint 'q1' = 1e+300 deg is outside the supported range [-3600, 3600] deg",
        ),
        ({"yaw": "1e20"}, "[goal] base_zyx_deg[0] = 1e+20 deg is outside"),
        (
            {"path": "[path]\nextra = { q2 = 1000000 }"},
            "[path] extra for 'q2' = 1000000 is outside the supported range [0, 20]; "
            "polynomial degree at most 25",
        ),
        (
            {"path": "[path]\nmax_deviation_deg = 1e308"},
            "[path] max_deviation_deg = 1e+308 deg is outside",
        ),
    ],
)
def test_scenario_numbers_beyond_the_limits(tmp_path, capsys, change, needle):
    scenario = _scenario(tmp_path, scenario_text(**change))
    out = tmp_path / "p.json"
    line = _refused(capsys, "plan", scenario, "-o", out, within=5.0)
    assert needle in line
    assert not out.exists()


def test_a_deeply_nested_array_is_refused(tmp_path, capsys):
    scenario = _scenario(tmp_path, scenario_text() + "x = " + "[" * 20000 + "]" * 20000 + "\n")
    line = _refused(capsys, "plan", scenario, "-o", tmp_path / "p.json")
    assert "nested too deeply" in line


def test_a_huge_scenario_is_refused_by_size_without_echo(tmp_path, capsys):
    attitude = "[" + ", ".join(["1.0"] * 300_000) + "]"
    text = scenario_text().replace("base_zyx_deg = [0.0, 0.0, 0.0]", f"base_zyx_deg = {attitude}")
    line = _refused(capsys, "plan", _scenario(tmp_path, text), "-o", tmp_path / "p.json")
    assert "above the limit of 1000000 bytes for a scenario file" in line


def test_a_long_list_is_quoted_as_an_excerpt(tmp_path, capsys):
    attitude = "[" + ", ".join(["1.0"] * 10_000) + "]"
    text = scenario_text().replace("base_zyx_deg = [0.0, 0.0, 0.0]", f"base_zyx_deg = {attitude}")
    line = _refused(capsys, "plan", _scenario(tmp_path, text), "-o", tmp_path / "p.json")
    assert "must be a list of 3 numbers, got [1.0, 1.0," in line and "(10000 items)" in line


def test_excerpts_are_short():
    assert (
        excerpt([1.0] * 1_000_000)
        == "[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, ...] (1000000 items)"
    )
    assert excerpt(int("9" * 400)) == "999999999999... (400 digits)"
    assert len(excerpt("x" * 5000)) <= 60 and "(5002 characters)" in excerpt("x" * 5000)
    assert excerpt({"q2": 1}) == "{q2 = 1}"
    assert excerpt([[[[[[]]]]]]) == "[[[...]]]"


def test_limits_in_the_api(planar_robot):
    with pytest.raises(ff.InputLimitError) as info:
        ff.build_problem(planar_robot, [0, 0], [1, 1], [0, 0, 0, 1], [0, 0, 0, 1], 1e-300)
    assert (info.value.name, info.value.low, info.value.high) == ("duration", 1e-3, 1e6)
    with pytest.raises(ff.InputLimitError, match="free coefficients of 'q2' = 21"):
        ff.build_problem(planar_robot, [0, 0], [1, 1], [0, 0, 0, 1], [0, 0, 0, 1], 1.0, [0, 21])
    with pytest.raises(ff.InputLimitError, match=r"tolerance = 1e-30 rad is outside"):
        ff.SolveOptions(tolerance=1e-30)
    with pytest.raises(ff.InputLimitError, match=r"samples = 20000000 is outside"):
        ff.plan(ff.Scenario.from_toml(ff.default_scenario_path()), samples=20_000_000)


# -- command-line arguments --------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (
            ["--samples", "20000000"],
            "--samples = 20000000 is outside the supported range [2, 10001]",
        ),
        (
            ["--tolerance", "1e-30"],
            "--tolerance = 1e-30 rad is outside the supported range [1e-11, 1e-07] rad",
        ),
        (["--tolerance", "1e-3"], "--tolerance = 0.001 rad is outside"),
        (["--tolerance", "nan"], "--tolerance = nan rad is outside"),
        (["--samples", "many"], "argument --samples: invalid int value: 'many'"),
    ],
)
def test_plan_arguments_beyond_the_limits(tmp_path, capsys, argv, needle):
    out = tmp_path / "p.json"
    line = _refused(capsys, "plan", *argv, "-o", out, within=5.0)
    assert needle in line and not out.exists()


def test_other_arguments_beyond_the_limits(tmp_path, capsys):
    assert "--budget = 10000000 is outside" in _refused(capsys, "bounds", "--budget", "10000000")
    assert "--max-angle = 1e+30 deg" in _refused(capsys, "bounds", "--max-angle", "1e30")
    assert "--workers = 100000 is outside" in _refused(
        capsys, "sweep", tmp_path / "none.toml", "-o", tmp_path / "r.csv", "--workers", "100000"
    )
    line = _refused(
        capsys,
        "compose",
        "--arm",
        "ur5",
        "--base-mass",
        "nan",
        "--base-size",
        "1",
        "1",
        "1",
        "--mount",
        "0",
        "0",
        "0",
        "-o",
        tmp_path / "x.urdf",
    )
    assert "--base-mass must be finite, got nan" in line


# -- files -------------------------------------------------------------------------------


def test_non_regular_scenario_files(tmp_path, capsys):
    assert "/dev/zero is a device, not a regular file" in _refused(capsys, "plan", "/dev/zero")
    assert "is a directory, not a regular file" in _refused(capsys, "plan", tmp_path)
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    assert "is a FIFO (named pipe), not a regular file" in _refused(capsys, "plan", fifo)
    assert "scenario file not found" in _refused(capsys, "plan", tmp_path / "missing.toml")


def test_a_shipped_scenario_by_name_and_a_misspelt_one(tmp_path, capsys, monkeypatch):
    """A bare name that is no file here is the shipped scenario of that name (as in a sweep
    file); a misspelt one lists the shipped names; a file of that name here (even a dangling
    link) comes first, and a name with its suffix is always a file."""
    monkeypatch.chdir(tmp_path)
    assert main(["check", "ur5_servicer"]) == 0
    assert capsys.readouterr().out.startswith("freefloat check: ur5_servicer at start")
    line = _refused(capsys, "check", "ur5_servicr")
    assert line == (
        f"freefloat: error: scenario file not found: {tmp_path / 'ur5_servicr'}; or name a "
        "shipped scenario: dual_ur5_servicer, panda_servicer, ur5_servicer, worked_example, "
        "worked_example_sweep"
    )
    # with its suffix a name is a file, never the shipped one; so is a dangling link
    assert "scenario file not found" in _refused(capsys, "check", "ur5_servicer.toml")
    (tmp_path / "ur5_servicer").symlink_to(tmp_path / "gone.toml")
    assert "scenario file not found" in _refused(capsys, "check", "ur5_servicer")
    (tmp_path / "ur5_servicer").unlink()
    (tmp_path / "ur5_servicer").write_text("robot = 1\n")  # a file here: read, and refused
    assert "ur5_servicer" in _refused(capsys, "check", "ur5_servicer")


def test_symlink_loops(tmp_path, capsys):
    loop = tmp_path / "loop.toml"
    loop.symlink_to(loop)
    assert "a symbolic-link loop" in _refused(capsys, "plan", loop)
    urdf = tmp_path / "loop.urdf"
    urdf.symlink_to(urdf)
    line = _refused(capsys, "plan", _scenario(tmp_path, scenario_text(robot=str(urdf))))
    assert "URDF path" in line and "a symbolic-link loop" in line


def test_an_output_link_into_a_missing_folder_makes_no_folder(tmp_path, capsys):
    """A dangling link to ``missing/deeper/x.json``: the output would have made those folders
    at the link's end. Refused; nothing made."""
    link = tmp_path / "out.json"
    link.symlink_to(tmp_path / "missing" / "deeper" / "x.json")
    line = _refused(capsys, "plan", "-o", str(link))
    assert "goes through a symbolic link to nothing" in line
    assert not (tmp_path / "missing").exists()
    folder = tmp_path / "linked"  # a folder of the path, not its last part
    folder.symlink_to(tmp_path / "missing" / "deeper")
    line = _refused(capsys, "plan", "-o", str(folder / "out.json"))
    assert "goes through a symbolic link to nothing" in line
    assert not (tmp_path / "missing").exists()


def test_nul_bytes_in_paths(tmp_path, capsys):
    assert "contains a NUL byte" in _refused(capsys, "plan", "wo\0rk.toml")
    text = scenario_text(robot=str(PLANAR)).replace("planar_2dof.urdf", "planar\\u0000.urdf")
    assert "URDF path" in _refused(capsys, "plan", _scenario(tmp_path, text))
    assert "contains a NUL byte" in _refused(capsys, "plan", "-o", "p\0.json")


def test_size_limits(tmp_path, monkeypatch):
    big = tmp_path / "big.txt"
    big.write_text("x" * 101)
    with pytest.raises(ff.FileError, match="is 101 bytes, above the limit of 100 bytes"):
        read_text_file(big, "test", 100)
    monkeypatch.setattr("freefloat.robot.model.MAX_URDF_BYTES", 1000)
    with pytest.raises(ff.ModelError, match="above the limit of 1000 bytes for a URDF file"):
        ff.load_robot(PLANAR)
    assert limits.MAX_SCENARIO_BYTES == 1_000_000


def test_non_utf8_scenario(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_bytes(b"robot = '\xff'\n")
    assert "is not UTF-8 text (byte 0xff at offset 9)" in _refused(capsys, "plan", path)


@pytest.fixture
def plan_file(tmp_path, worked_plan):
    return worked_plan.save(tmp_path / "plan.json")


def _outputs(plan_file: Path, target: Path) -> dict[str, list[str]]:
    sweep = plan_file.parent / "sweep.toml"
    sweep.write_text(
        'scenario = "worked_example"\n[[axis]]\nkey = "goal.joints.q2"\nvalues = [90.0]\n'
    )
    return {
        "plan": ["plan", "-o", str(target)],
        "plot": ["plot", str(plan_file), "-o", str(target)],
        "show": ["show", str(plan_file), "--html", str(target)],
        "export": ["export", str(plan_file), "--format", "csv", "-o", str(target)],
        "compose": [
            "compose",
            "--arm",
            "ur5",
            "--base-mass",
            "100",
            "--base-size",
            "1",
            "1",
            "1",
            "--mount",
            "0.5",
            "0",
            "0",
            "-o",
            str(target),
        ],
        "sweep": ["sweep", str(sweep), "-o", str(target)],
    }


@pytest.mark.parametrize("command", ["plan", "plot", "show", "export", "compose", "sweep"])
def test_outputs_under_a_file_are_refused(tmp_path, capsys, plan_file, command):
    blocker = tmp_path / "file"
    blocker.write_text("keep")
    argv = _outputs(plan_file, blocker / "out")[command]
    line = _refused(capsys, *argv, within=5.0)
    assert f"{blocker} is a file, not a folder" in line
    assert blocker.read_text() == "keep"


@pytest.mark.parametrize("command", ["plan", "show", "export", "compose", "sweep"])
def test_outputs_onto_a_directory_are_refused(tmp_path, capsys, plan_file, command):
    folder = tmp_path / "folder"
    folder.mkdir()
    line = _refused(capsys, *_outputs(plan_file, folder)[command], within=5.0)
    assert "is a directory; give a file name" in line
    assert list(folder.iterdir()) == []


@pytest.mark.parametrize("command", ["plan", "show", "export", "compose", "sweep"])
def test_outputs_named_as_a_folder_not_there_yet_are_refused(tmp_path, capsys, plan_file, command):
    """``-o out/`` with no ``out`` yet: a folder was meant, not a file called ``out``."""
    folder = tmp_path / "out"
    line = _refused(capsys, *_outputs(plan_file, f"{folder}{os.sep}")[command], within=5.0)
    assert "names a folder; give a file name" in line
    assert not folder.exists()


@pytest.mark.parametrize("command", ["plan", "plot", "show", "export", "compose", "sweep"])
def test_outputs_into_a_read_only_folder_are_refused(tmp_path, capsys, plan_file, command):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    real_access = os.access
    if os.geteuid() == 0:  # root writes anywhere: make the check see what a user would
        os.access = lambda path, mode: False if Path(path) == folder else real_access(path, mode)
    try:
        line = _refused(capsys, *_outputs(plan_file, folder / "x" / "out")[command], within=5.0)
    finally:
        os.access = real_access
        folder.chmod(0o755)
    assert f"folder {folder} is not writable" in line
    assert list(folder.iterdir()) == []


def test_a_write_that_fails_late_is_one_error_and_leaves_nothing(tmp_path, monkeypatch):
    def refuse(src, dst):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(ff.FileError, match=r"cannot write .*x.json: Permission denied"):
        ff.files.atomic_write_text(tmp_path / "x.json", "{}")
    assert list(tmp_path.iterdir()) == []


def test_check_output_accepts_new_folders(tmp_path):
    assert check_output(tmp_path / "a" / "b" / "c.json") == tmp_path / "a" / "b" / "c.json"
    assert check_output(tmp_path, folder=True) == tmp_path


# -- URDFs ------------------------------------------------------------------------------


def _planar_variant(tmp_path, old, new, name="r.urdf"):
    text = PLANAR.read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def test_mimic_joint_is_refused_by_name(tmp_path, capsys):
    urdf = _planar_variant(
        tmp_path,
        '<joint name="q2" type="continuous">',
        '<joint name="q2" type="continuous"><mimic joint="q1"/>',
    )
    with pytest.raises(
        ff.ModelError, match="joint 'q2' mimics 'q1': mimic joints are not supported"
    ):
        ff.load_robot(urdf)
    out = tmp_path / "p.json"
    _refused(capsys, "plan", _scenario(tmp_path, scenario_text(robot=str(urdf))), "-o", out)
    assert not out.exists()


def test_revolute_joint_without_limit_is_one_clean_line(tmp_path, capfd):
    urdf = _planar_variant(
        tmp_path, '<joint name="q1" type="continuous">', '<joint name="q1" type="revolute">'
    )
    code = main(["plan", str(_scenario(tmp_path, scenario_text(robot=str(urdf))))])
    _, err = capfd.readouterr()  # file descriptor 2 too: no urdfdom noise
    assert code == 2 and err.count("\n") == 1
    assert "joint 'q1' (revolute) has no <limit>; it needs <limit lower=... upper=..." in err


@pytest.mark.parametrize("attr", ["effort", "velocity"])
def test_a_negative_limit_is_refused_by_name(tmp_path, capfd, attr):
    """Pinocchio's parser said only that it could not read the file."""
    limit = f'<limit lower="-3" upper="3" effort="10" velocity="2" {attr}="-1"/>'.replace(
        f'{attr}="{"10" if attr == "effort" else "2"}" ', ""
    )
    urdf = _planar_variant(
        tmp_path,
        '<joint name="q1" type="continuous">',
        '<joint name="q1" type="revolute">' + limit,
    )
    code = main(["plan", str(_scenario(tmp_path, scenario_text(robot=str(urdf))))])
    _, err = capfd.readouterr()
    assert code == 2 and err.count("\n") == 1
    assert f"joint 'q1' <limit> {attr}='-1' is negative; a limit is a magnitude (>= 0" in err


def test_zero_axis_is_refused_by_name_without_warnings(tmp_path):
    import subprocess
    import sys

    urdf = _planar_variant(tmp_path, '<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>')
    scenario = _scenario(tmp_path, scenario_text(robot=str(urdf)))
    result = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", "plan", str(scenario)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1, result.stderr  # no RuntimeWarning before it
    assert "joint 'q1' has a zero axis (xyz='0 0 0')" in result.stderr


def test_parser_noise_is_captured_into_the_message(tmp_path, capfd):
    urdf = _planar_variant(  # <dynamics> is not read by freefloat's own checks
        tmp_path, '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><dynamics damping="zero"/>'
    )
    with pytest.raises(ff.ModelError) as info:
        ff.load_robot(urdf)
    assert "urdfdom: damping value (zero) is not a valid float" in str(info.value)
    assert "\n" not in str(info.value)
    assert capfd.readouterr().err == ""


# -- large robots -----------------------------------------------------------------------


@pytest.mark.parametrize("spatial", [False, True])
def test_a_30_joint_chain_is_refused_up_front(tmp_path, capsys, spatial):
    urdf = tmp_path / "chain.urdf"
    urdf.write_text(urdfs.chain(30, spatial))
    joints = ", ".join(f"j{i} = 10.0" for i in range(1, 31))
    goal = ", ".join(f"j{i} = 20.0" for i in range(1, 31))
    scenario = _scenario(
        tmp_path,
        f'robot = "chain.urdf"\nduration = 10.0\n[start]\njoints = {{ {joints} }}\n'
        f"[goal]\njoints = {{ {goal} }}\nbase_zyx_deg = [1.0, 0.0, 0.0]\n",
    )
    line = _refused(capsys, "plan", scenario, "-o", tmp_path / "p.json", within=5.0)
    assert (
        f"movable joints of 'chain30' = 30 is above the supported maximum {limits.MAX_JOINTS}"
        in line
    )
    assert ff.load_robot(urdf).n == 30  # loading it for other uses is fine


def test_a_scenario_name_too_long_for_the_file_system_is_no_write(tmp_path, capsys, monkeypatch):
    """A 300-character scenario name was "cannot write .../robots/scenarios/aaa...: File name
    too long": the wrong verb, and the install's folder. It names the path asked for."""
    monkeypatch.chdir(tmp_path)
    assert main(["check", "a" * 300]) == 2
    err = capsys.readouterr().err
    shown = f"{tmp_path}/{'a' * 300}"
    assert err.startswith(f"freefloat: error: '{shown[:40]}") and "cannot write" not in err
    assert err.endswith(f"({len(shown)} characters): File name too long\n")
