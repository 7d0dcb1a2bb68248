"""Messages of hostile input (issue 26): limits before collisions, byte-order marks, C++
loader failures and parser noise as one line naming the file, empty option values."""

from __future__ import annotations

import time

import pytest

import freefloat as ff
from freefloat._exits import error_line
from freefloat.cli import main

from conftest import ROOT
from test_errors import scenario_text

PLANAR = ROOT / "robots" / "planar_2dof.urdf"


def _refused(capfd, *argv):
    """Run in-process; one line on descriptor 2 (C++ noise included), exit 2. The line."""
    start = time.perf_counter()
    code = main([str(a) for a in argv])
    _, err = capfd.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("freefloat: error: "), err[:600]
    assert time.perf_counter() - start < 30.0
    return err.strip()


def test_a_goal_outside_its_limit_is_reported_as_a_limit_not_an_overlap(
    tmp_path, capfd, monkeypatch
):
    """xArm7 joint2 at 150 deg (limit 120 deg) also folds link4 into the spacecraft."""
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    joints = "joint1 = 0.0, joint3 = 0.0, joint4 = 30.0, joint5 = 0.0, joint6 = 0.0, joint7 = 0.0"
    scenario = tmp_path / "x.toml"
    scenario.write_text(
        'duration = 10.0\n[robot]\narm = "xarm7"\nbase_mass = 100.0\n'
        "base_size = [0.6, 0.6, 0.6]\nmount = [0.3, 0.0, 0.0]\nmount_rpy_deg = [0.0, 90.0, 0.0]\n"
        f"[start]\njoints = {{ joint2 = 0.0, {joints} }}\n"
        f"[goal]\njoints = {{ joint2 = 150.0, {joints} }}\nbase_zyx_deg = [1.0, 0.0, 0.0]\n"
    )
    line = _refused(capfd, "plan", scenario, "-o", tmp_path / "p.json")
    assert "goal: joint 'joint2' = 150 deg is outside its limits [-117.972, 120] deg" in line
    assert line.startswith(f"freefloat: error: {scenario}: goal: ")  # the file, named first
    # the same pose within its limits is an overlap, named as such
    scenario.write_text(scenario.read_text().replace("joint2 = 150.0", "joint2 = 119.0"))
    overlap = _refused(capfd, "plan", scenario, "-o", tmp_path / "p.json")
    assert "overlap" in overlap and overlap.startswith(f"freefloat: error: {scenario}: goal")


def test_a_scenario_with_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "s.toml"
    path.write_bytes(b"\xef\xbb\xbf" + scenario_text().encode())
    assert ff.Scenario.from_toml(path).robot.n == 2


def test_an_arm_that_is_no_urdf_is_one_line_without_parser_noise(tmp_path, capfd):
    text = "root:x:0:0:root:/root:/bin/bash\n"
    arm = tmp_path / "passwd"
    arm.write_text(text)
    argv = ["--base-mass", "100", "--base-size", "1", "1", "1", "--mount", "0.5", "0", "0"]
    line = _refused(capfd, "compose", "--arm", arm, *argv, "-o", tmp_path / "c.urdf")
    assert f"cannot read arm URDF {arm}: malformed URDF XML" in line
    assert not (tmp_path / "c.urdf").exists()


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        (b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "an ASCII STL cut short"),
        (b"<COLLADA><bad", "neither a binary STL"),
    ],
)
def test_a_broken_mesh_is_one_line_naming_the_file(tmp_path, capfd, content, reason):
    mesh = tmp_path / "broken.stl"
    mesh.write_bytes(content)
    urdf = tmp_path / "m.urdf"
    cylinder = '<geometry><cylinder radius="0.05" length="1.0"/></geometry>'
    urdf.write_text(
        PLANAR.read_text().replace(cylinder, f'<geometry><mesh filename="{mesh}"/></geometry>')
    )
    plan = ff.plan(ff.Scenario.from_toml(_write(tmp_path, scenario_text(robot=str(urdf)))))
    path = plan.save(tmp_path / "p.json")
    capfd.readouterr()  # planning's own warning (this robot has no collision geometry)
    line = _refused(capfd, "show", path, "--html", tmp_path / "p.html")
    assert f"cannot draw the mesh {mesh}: {reason}" in line
    assert "From file" not in line and "in function" not in line
    assert not (tmp_path / "p.html").exists()


def _write(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


def test_cpp_exception_context_is_left_out_of_the_line(capsys):
    error_line(
        "error: cannot read it (From file: /x/a.cpp\nin function: void f()\nat line: 91\n"
        "message: Could not load resource /m.stl\nSTL: bad\nHint: check the path.)"
    )
    assert capsys.readouterr().err == (
        "freefloat: error: cannot read it (Could not load resource /m.stl; STL: bad)\n"
    )


def test_an_empty_scheduler_address_is_refused_by_name(tmp_path, capfd):
    line = _refused(
        capfd, "sweep", tmp_path / "s.toml", "-o", tmp_path / "r.csv", "--scheduler", " "
    )
    assert "--scheduler is empty; give the Dask scheduler's address" in line


def test_a_visual_colour_of_three_numbers_is_one_line_naming_it(tmp_path, capfd):
    """The page refuses a material colour of the wrong count (urdfdom wants r g b a), in one
    line on the command line, exit 2, no page left behind."""
    urdf = tmp_path / "m.urdf"
    text = PLANAR.read_text()
    assert '<color rgba="0.9 0.55 0.1 1"/>' in text
    urdf.write_text(text.replace('<color rgba="0.9 0.55 0.1 1"/>', '<color rgba="0.9 0.55 0.1"/>'))
    plan = ff.plan(ff.Scenario.from_toml(_write(tmp_path, scenario_text(robot=str(urdf)))))
    path = plan.save(tmp_path / "p.json")
    capfd.readouterr()
    line = _refused(capfd, "show", path, "--html", tmp_path / "p.html")
    assert "m.urdf: material 'arm' gives '0.9 0.55 0.1'; expected 4 finite numbers" in line
    assert not (tmp_path / "p.html").exists()


def test_a_value_just_beyond_its_limit_is_shown_as_given(capfd):
    """``--max-angle 180.0001`` read "180 deg is outside [-180, 180]": the value as given, and
    the range of a positive option from 0."""
    line = _refused(capfd, "bounds", "--max-angle", "180.0001")
    assert "--max-angle = 180.0001 deg is outside the supported range [0, 180] deg" in line
