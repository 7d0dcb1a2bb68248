"""Values in messages and tables as the user wrote them: a value a hair outside a limit never
printed as the limit, TOML dates as dates, check's columns apart."""

from __future__ import annotations

import datetime

import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.excerpts import apart, excerpt

import urdfs


def open_text(path: str) -> str:
    with open(path, encoding="utf-8") as file:
        return file.read()


def _slider_scenario(tmp_path, start: str) -> str:
    urdf = tmp_path / "slider.urdf"
    urdf.write_text(urdfs.slider_arm())
    path = tmp_path / "s.toml"
    path.write_text(
        f'robot = "{urdf}"\nduration = 10.0\n[start]\njoints = {{ slide = {start}, turn = 0.0 }}\n'
        "[goal]\njoints = { slide = 0.1, turn = 10.0 }\nbase_zyx_deg = [0.0, 0.0, 0.0]\n"
        "[safety]\ncheck = false\n"
    )
    return str(path)


def test_a_value_a_hair_past_its_limit_is_not_printed_as_the_limit(tmp_path):
    """0.40000001 m against the URDF's upper limit 0.4 m (tests/urdfs.py: slider_arm)."""
    with pytest.raises(ff.JointLimitError) as info:
        ff.plan(_slider_scenario(tmp_path, "0.40000001"))  # a path: read as a scenario
    assert "joint 'slide' = 0.40000001 m is outside its limits [-0.2, 0.4] m" in str(info.value)
    assert info.value.value > info.value.upper == 0.4


@pytest.mark.parametrize(
    ("value", "bounds", "shown"),
    [
        (0.50000001, (-0.5, 0.5), "0.50000001"),
        (0.5, (-0.5, 0.5), "0.5"),
        (-0.0, (), "0"),
        (123.4567891, (0.0, 100.0), "123.457"),
        (0.5000000000000001, (0.5,), "0.5000000000000001"),
    ],
)
def test_apart_tells_a_value_from_its_bounds(value, bounds, shown):
    assert apart(value, *bounds) == shown
    assert float(shown) == pytest.approx(value, rel=1e-5) and float(shown) not in [
        b for b in bounds if b != value
    ]


def test_a_toml_date_is_quoted_as_written(tmp_path):
    assert excerpt(datetime.date(1979, 5, 27)) == "1979-05-27 (a date)"
    assert excerpt(datetime.time(7, 32)) == "07:32:00 (a time)"
    path = tmp_path / "dated.toml"
    text = open_text(_slider_scenario(tmp_path, "0.0"))
    path.write_text(text.replace("duration = 10.0", "duration = 1979-05-27"))
    with pytest.raises(ff.FreeFloatError) as info:
        ff.Scenario.from_toml(path)
    assert "got 1979-05-27 (a date)" in str(info.value)
    assert "datetime" not in str(info.value)


def test_check_keeps_its_columns_apart_at_many_decimals(tmp_path, capsys):
    """A room of 1e-10 m needs 10 decimals: every cell still has a space before it."""
    scenario = _slider_scenario(tmp_path, "0.0")
    assert main(["check", scenario, "--at", "0.4000000001,0"]) == 1
    row = next(line for line in capsys.readouterr().out.splitlines() if "slide" in line)
    value, lower, upper, room = row.split()[1:5]
    assert (float(value), float(lower), float(upper)) == (0.4000000001, -0.2, 0.4)
    assert float(room) == pytest.approx(-1e-10) and row.rstrip().endswith("OUTSIDE")


def test_plan_and_reach_take_a_scenario_path_and_name_anything_else(tmp_path):
    path = str(ff.default_scenario_path())
    assert ff.plan(path).free_parameters == ff.plan(ff.Scenario.from_toml(path)).free_parameters
    with pytest.raises(ff.InputError, match=r"path of a scenario TOML file, got dict$"):
        ff.plan({"duration": 10.0})
    with pytest.raises(ff.InputError, match=r"freefloat\.Scenario or the path"):
        ff.reachable(3.0)


@pytest.mark.parametrize(
    ("given", "valid", "said"),
    [
        ("qe\u0301", ["q\u00e9", "q2"], r"'qe\u0301', 'q\xe9'"),  # NFD against the URDF's NFC
        ("j\u0430", ["ja", "jb"], r"'j\u0430', 'ja'"),  # a Cyrillic a
    ],
)
def test_a_look_alike_name_shows_its_code_points(given, valid, said):
    message = str(ff.UnknownNameError("joint", given, valid))
    assert f"but its code points differ: {said})" in message
    for other, valid in (("\u00e9\u00e9", ["ja"]), ("\u5173\u8282\u4e00", ["\u5173\u8282\u4e8c"])):
        assert "code points" not in str(ff.UnknownNameError("joint", other, valid))
    cyrillic = "\u043f\u043b\u0435\u0447\u043e"  # two Russian words a letter apart
    assert "code points" not in str(
        ff.UnknownNameError("joint", cyrillic, [cyrillic[:-1] + "\u0438"])
    )


def test_a_long_path_is_quoted_with_both_its_ends():
    from freefloat.excerpts import path_excerpt

    path = "/tmp/" + "deep/" * 40 + "sweep_heatmap.png"
    quoted = path_excerpt(path)
    assert quoted.startswith("'/tmp/deep/") and quoted.endswith(
        f"sweep_heatmap.png' ({len(path)} characters)"
    )
    assert len(quoted) < 150
    assert path_excerpt("/tmp/a.json") == "'/tmp/a.json'"


def test_a_scenario_through_a_pipe_without_a_name_is_named_a_pipe():
    """``plan <(cat s.toml)`` said "file not found: /proc/PID/fd/pipe:[...]"."""
    import os

    read, write = os.pipe()
    try:
        with pytest.raises(ff.ScenarioError) as info:
            ff.Scenario.from_toml(f"/proc/self/fd/{read}")
    finally:
        os.close(read)
        os.close(write)
    assert str(info.value) == (
        f"scenario '/proc/self/fd/{read}' is a pipe or socket with no file name (as <(...) "
        "gives), not a file; give a file (a piped input written to one first)"
    )


def test_an_output_in_a_folder_no_one_can_write_is_refused_before_any_work(tmp_path, capsys):
    """/proc refuses new files even to root, whose permission bits say yes: the folder is
    tried, not its bits read (as root the plot was drawn, then refused without a path)."""
    from freefloat.files import check_output

    with pytest.raises(ff.FileError, match=r"^cannot write --plot '/proc/r\.png': folder /proc is"):
        check_output("/proc/r.png", "--plot")
    plan = ff.plan(ff.default_scenario_path()).save(tmp_path / "p.json")
    assert main(["plot", str(plan), "-o", "/proc/plots"]) == 2
    assert "folder /proc is not writable (it takes no new files)" in capsys.readouterr().err


def test_reach_draws_into_folders_it_makes(tmp_path, capsys):
    figure = tmp_path / "new" / "sub" / "reach.png"
    assert main(["reach", str(ff.default_scenario_path()), "-q", "--plot", str(figure)]) == 0
    assert figure.read_bytes().startswith(b"\x89PNG")
    assert not [p for p in figure.parent.iterdir() if p.name.startswith(".")]  # no leftovers


def test_a_payload_key_on_a_plan_without_a_payload_says_so(tmp_path, capsys):
    """A replay sweep's payload.mass named "unknown link ... 'payload'"."""
    plan = ff.plan(ff.default_scenario_path()).save(tmp_path / "p.json")
    sweep = tmp_path / "s.toml"
    sweep.write_text(f'plan = "{plan.name}"\n[[axis]]\nkey = "payload.mass"\nvalues = [1.0]\n')
    assert main(["sweep", str(sweep), "-o", str(tmp_path / "r.csv")]) == 2
    assert (
        capsys.readouterr()
        .err.rstrip()
        .endswith(
            "axis 'payload.mass' = 1.0: payload keys need a robot that holds a captured payload "
            "([payload] in the scenario, or freefloat compose --payload-mass); this one holds none"
        )
    )


def test_planarity_of_a_robot_whose_limits_keep_away_from_zero(tmp_path):
    """Limits 2 to 3 rad: the planarity test drew from [max(2, -1), min(3, 1)], empty, and
    plan crashed. Planarity is the axes' property: the answer is the unlimited robot's."""
    text = urdfs.chain(3)  # every axis along z: planar
    far = text.replace('lower="-3.0" upper="3.0"', 'lower="2.0" upper="3.0"')
    assert far != text
    answers = []
    for name, body in (("near.urdf", text), ("far.urdf", far)):
        path = tmp_path / name
        path.write_text(body)
        answers.append(ff.is_planar(ff.load_robot(path)))
    assert answers == [True, True]
