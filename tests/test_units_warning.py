"""Scenario joint values that look like radians (files are in degrees) give a UnitsWarning."""

from __future__ import annotations

import sys
import warnings

import pytest

import freefloat as ff
from freefloat.cli import main

from conftest import ROOT

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

UR5 = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
#: A UR5 start pasted from a ROS joint state (rad), and the shipped scenario's goal (deg).
ROS_START = (0.0, -1.57, 1.57, 0.0, 1.2, 0.0)
SHIPPED_GOAL = (57.3, -57.3, 68.8, -68.8, -57.3, 28.6)
#: What the warning says about ROS_START: -1.57 rad = -1.57 * 180 / pi deg.
ROS_START_MESSAGE = (
    "[start] joints look like radians (every value within +-6.28, shoulder_lift_joint = "
    "-1.57); scenario joints are in degrees (-1.57 rad is -89.95 deg)"
)


def _ur5_scenario(tmp_path, start, goal=SHIPPED_GOAL):
    def table(values):
        return ", ".join(f"{name} = {value!r}" for name, value in zip(UR5, values, strict=True))

    path = tmp_path / "ur5.toml"
    path.write_text(
        'robot = "ur5_servicer"\nduration = 20.0\n\n'
        f"[start]\njoints = {{ {table(start)} }}\n\n"
        f"[goal]\njoints = {{ {table(goal)} }}\nbase_zyx_deg = [-7.6, -1.8, -8.3]\n"
    )
    return path


def _units_warnings(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ff.Scenario.from_toml(path)
    return [str(w.message) for w in caught if issubclass(w.category, ff.UnitsWarning)]


def test_a_ros_start_in_radians_is_warned_of(tmp_path):
    assert _units_warnings(_ur5_scenario(tmp_path, ROS_START)) == [ROS_START_MESSAGE]


def test_the_warning_names_the_goal_table(tmp_path):
    goal = (0.5, -1.0, 1.0, -0.8, 0.3, 0.0)
    (message,) = _units_warnings(_ur5_scenario(tmp_path, (0, -90, 90, -90, -90, 0), goal))
    # the largest fractional value is named: -0.8 rad = -0.8 * 180 / pi deg
    assert message == (
        "[goal] joints look like radians (every value within +-6.28, wrist_1_joint = -0.8); "
        "scenario joints are in degrees (-0.8 rad is -45.84 deg)"
    )


@pytest.mark.parametrize(
    "start",
    [
        (0, -90, 90, -90, -90, 0),  # the shipped start
        (0, -2, 2, 0, 1, 0),  # small whole numbers: no telling their unit
        (0, 0, 0, 0, 0, 0),
        (0.0, -90.0, 90.0, -90.0, -1.5, 0.0),  # a value beyond 2 pi: degrees
        (0.0, -7.5, 1.57, 0.0, 1.2, 0.0),
    ],
)
def test_degree_tables_are_not_warned_of(tmp_path, start):
    assert _units_warnings(_ur5_scenario(tmp_path, start)) == []


def _shipped_scenarios():
    files = sorted((ROOT / "robots" / "scenarios").glob("*.toml"))
    files += sorted((ROOT / "examples").glob("*.toml"))
    return [f for f in files if "start" in tomllib.loads(f.read_text())]


def test_shipped_scenarios_are_found():
    names = {f.name for f in _shipped_scenarios()}
    assert {"ur5_servicer.toml", "panda_servicer.toml", "worked_example.toml"} <= names


@pytest.mark.parametrize("path", _shipped_scenarios(), ids=lambda p: p.name)
def test_no_shipped_scenario_is_warned_of(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ff.UnitsWarning)
        ff.Scenario.from_toml(path)


def test_the_command_line_prints_it_as_one_warning_line(tmp_path, capsys):
    path = _ur5_scenario(tmp_path, ROS_START)
    assert main(["check", str(path)]) == 0
    err = capsys.readouterr().err
    assert err == f"freefloat: warning: {ROS_START_MESSAGE}\n"
    assert main(["check", "-q", str(path)]) == 0
    assert capsys.readouterr().err == ""


def test_a_sweep_says_it_once_and_its_workers_stay_quiet(tmp_path, capfd):
    shipped = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    assert shipped.count("q1 = 80.0, q2 = 30.0") == 1
    (tmp_path / "s.toml").write_text(shipped.replace("q1 = 80.0, q2 = 30.0", "q1 = 1.4, q2 = 0.5"))
    (tmp_path / "sweep.toml").write_text(
        'scenario = "s.toml"\nsamples = 51\n\n[[axis]]\nkey = "goal.base_zyx_deg.0"\n'
        "values = [-10.0, -5.0, 0.0]\n"
    )
    argv = ["sweep", str(tmp_path / "sweep.toml"), "-o", str(tmp_path / "r.csv")]
    assert main([*argv, "--workers", "1"]) == 0
    # 1.4 rad = 1.4 * 180 / pi deg; the worker processes' stderr is captured too
    assert capfd.readouterr().err == (
        "freefloat: warning: [start] joints look like radians (every value within +-6.28, "
        "q1 = 1.4); scenario joints are in degrees (1.4 rad is 80.21 deg)\n"
    )


@pytest.mark.parametrize(
    ("written", "said"),
    [
        ("[1, 0, 0, 0]", "is a half turn about x (the order is x, y, z, w)"),
        ("[-1.0, 0, 0, 0]", "is a half turn about x (the order is x, y, z, w)"),
        ("[0, 0, 0, 2]", "has norm 2, not 1; it is used divided by it"),
        ("[0.1, 0.2, 0.3, 0.5]", "has norm 0.6245, not 1"),
        ("[0, 0, 0, 1]", None),
        ("[0.0012, -0.0104, 0.6523, 0.7579]", None),  # 4 decimals of a unit quaternion
        ("[0, 1, 0, 0]", None),  # a half turn about y: w first would be [0, 0, 1, 0] here
        # 1 deg about z written w first: 2 acos(0.00872654) = 179 deg as written,
        # 2 acos(0.99996192) = 1 deg read w first
        (
            "[0.99996192, 0.0, 0.0, 0.00872654]",
            "is a 179 deg turn; read w first it would be a 1 deg turn: the order is x, y, z, w",
        ),
        ("[0.7071, 0, 0, 0.7072]", None),  # a quarter turn about x, either way
        ("[0.7072, 0, 0, 0.7071]", None),
        ("[0.3, 0, 0, 0.954]", None),  # 35 deg about x
    ],
)
def test_a_written_quaternion_in_another_convention_is_warned_of(tmp_path, written, said):
    """w first (the identity [1, 0, 0, 0] of Eigen and many papers), or a norm far from 1
    (by hand: |[0.1, 0.2, 0.3, 0.5]| = sqrt(0.39) = 0.6245); plain ones say nothing."""
    path = _ur5_scenario(tmp_path, (0, -90, 90, -90, -90, 0))
    text = path.read_text().replace("base_zyx_deg = [-7.6, -1.8, -8.3]", "")
    path.write_text(text + f"base_quaternion_xyzw = {written}\n")
    messages = _units_warnings(path)
    if said is None:
        assert messages == []
    else:
        assert len(messages) == 1 and said in messages[0]
        assert messages[0].startswith("[goal] base_quaternion_xyzw = [")
