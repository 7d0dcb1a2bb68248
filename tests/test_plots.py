"""Plots: files exist, are sensible images, and carry the plan's samples."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from freefloat.cli import main
from freefloat.viz.plots import TOPICS, figures


@pytest.fixture(scope="module")
def figs(worked_plan):
    return figures(worked_plan)


def _line(fig, label):
    ax = fig.axes[0]
    return next(line for line in ax.lines if line.get_label() == label)


def test_plotted_data_equals_the_samples(figs, worked_plan):
    s = worked_plan.samples
    t = np.array(s.t)
    q = np.degrees(np.array(s.q))
    qd = np.degrees(np.array(s.qd))
    for i, name in enumerate(worked_plan.robot.joints):
        np.testing.assert_array_equal(_line(figs["joint_positions"], name).get_xdata(), t)
        np.testing.assert_allclose(_line(figs["joint_positions"], name).get_ydata(), q[:, i])
        np.testing.assert_allclose(_line(figs["joint_rates"], name).get_ydata(), qd[:, i])
        np.testing.assert_allclose(
            _line(figs["joint_torques"], name).get_ydata(), np.array(s.tau)[:, i]
        )
    zyx = np.array(s.base_zyx_deg)
    for i, label in enumerate(("yaw", "pitch", "roll")):
        np.testing.assert_allclose(_line(figs["base_attitude"], label).get_ydata(), zyx[:, i])
    omega = np.degrees(np.array(s.base_angular_velocity))
    np.testing.assert_allclose(_line(figs["base_rate"], "$\\omega_z$").get_ydata(), omega[:, 2])
    ee = np.array(s.end_effector_position)
    np.testing.assert_allclose(_line(figs["end_effector"], "$x_E$").get_ydata(), ee[:, 0])
    np.testing.assert_allclose(_line(figs["end_effector"], "$y_E$").get_ydata(), ee[:, 1])
    path = _line(figs["end_effector_path"], "path")
    np.testing.assert_allclose(path.get_xdata(), ee[:, 0])
    np.testing.assert_allclose(path.get_ydata(), ee[:, 1])


def test_axis_labels_have_units(figs):
    for name in TOPICS:
        ax = figs[name].axes[0]
        assert "[" in ax.get_xlabel() and "[" in ax.get_ylabel(), name
    assert len(figs["overview"].axes) == 8


def test_plot_cli_writes_valid_images(tmp_path, worked_plan, capsys):
    plan_path = worked_plan.save(tmp_path / "p.json")
    out = tmp_path / "figs"
    assert main(["plot", str(plan_path), "-o", str(out), "--svg"]) == 0
    pngs = sorted(out.glob("*.png"))
    assert {p.stem for p in pngs} == {*TOPICS, "overview"}
    for png in pngs:
        with Image.open(png) as img:
            img.verify()
        with Image.open(png) as img:
            width, height = img.size
            assert 500 <= width <= 2000 and 300 <= height <= 2000
            assert np.asarray(img.convert("L")).std() > 5  # not blank
    svgs = sorted(out.glob("*.svg"))
    assert len(svgs) == len(pngs)
    assert all(p.read_text().lstrip().startswith("<?xml") for p in svgs)
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporaries left
    assert "16 files" in capsys.readouterr().out


def test_plot_into_a_folder_named_with_a_trailing_slash(tmp_path, worked_plan, capsys):
    """Figures go into a folder: `-o figs/` (not there yet) is that folder, not refused."""
    plan_path = worked_plan.save(tmp_path / "p.json")
    out = tmp_path / "figs"
    assert main(["plot", str(plan_path), "-o", f"{out}{os.sep}"]) == 0
    assert {p.stem for p in out.glob("*.png")} == {*TOPICS, "overview"}
    capsys.readouterr()


def test_broken_matplotlib_gives_a_clear_error(tmp_path, worked_plan):
    plan_path = worked_plan.save(tmp_path / "p.json")
    code = (
        "import sys; sys.modules['matplotlib'] = None\n"
        "from freefloat.cli import main\n"
        f"sys.exit(main(['plot', {str(plan_path)!r}, '-o', {str(tmp_path / 'f')!r}]))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False
    )
    assert result.returncode == 2
    assert "plots need matplotlib, which failed to import" in result.stderr


def test_legends_sit_outside_the_data(figs):
    for name in TOPICS:
        fig = figs[name]
        fig.canvas.draw()
        ax = fig.axes[0]
        legend = ax.get_legend().get_window_extent()
        assert legend.x0 >= ax.get_window_extent().x1, name


def test_goal_values_and_projection_are_marked(figs, worked_plan):
    ax = figs["joint_positions"].axes[0]
    goals = [line for line in ax.lines if line.get_label() == "_goal"]
    np.testing.assert_allclose(
        [line.get_ydata()[0] for line in goals], np.degrees(worked_plan.request.goal_joints)
    )
    assert all(line.get_xdata()[0] == worked_plan.duration for line in goals)
    ax = figs["base_attitude"].axes[0]
    targets = [line.get_ydata()[0] for line in ax.lines if line.get_label() == "_goal"]
    np.testing.assert_allclose(targets, worked_plan.base.target_zyx_deg)
    # Coinciding angles stay distinguishable: one line style each, goal markers drawn on top.
    data = [line for line in ax.lines if not line.get_label().startswith("_")][:3]
    assert len({line.get_linestyle() for line in data}) == 3
    at_t = [line for line in ax.lines if line.get_label() == "_goal_at_T"]
    assert [line.get_ydata()[0] for line in at_t] == list(worked_plan.base.target_zyx_deg)
    assert all(line.get_zorder() > max(d.get_zorder() for d in data) for line in at_t)
    assert "inertial x-y plane" in figs["end_effector_path"].axes[0].get_xlabel()


def test_joint_limits_are_drawn_from_the_urdf():
    import freefloat as ff

    from conftest import ROOT

    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    robot = ff.load_robot(plan.robot.urdf)
    figs = figures(plan, ("joint_positions", "joint_rates"))
    drawn = sorted(
        round(line.get_ydata()[0], 9)
        for line in figs["joint_positions"].axes[0].lines
        if line.get_label() == "_limit"
    )
    expected = sorted(
        round(float(np.degrees(v)), 9) for j in robot.joints for v in (j.lower, j.upper)
    )
    assert drawn == expected
    rates = [
        line.get_ydata()[0]
        for line in figs["joint_rates"].axes[0].lines
        if line.get_label() == "_limit"
    ]
    assert max(rates) == pytest.approx(np.degrees(max(j.velocity_limit for j in robot.joints)))


def test_names_the_font_lacks_give_one_warning_line(tmp_path, capfd):
    """Joints named in Chinese: matplotlib warned once per missing glyph, with its source
    paths, on stderr; now one freefloat line, and the figures are written."""
    import matplotlib.pyplot as plt

    from conftest import ROOT

    plt.close("all")  # what earlier tests left open (the last test here to use figures)
    names = {"q1": "关节一", "q2": "关节二"}
    urdf = (ROOT / "robots" / "planar_2dof.urdf").read_text(encoding="utf-8")
    scenario = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    for old, new in names.items():
        urdf = urdf.replace(f'"{old}"', f'"{new}"')
        scenario = scenario.replace(f"{old} =", f'"{new}" =')
    (tmp_path / "cjk.urdf").write_text(urdf, encoding="utf-8")
    lines = ['robot = "cjk.urdf"' if s.startswith("robot =") else s for s in scenario.splitlines()]
    (tmp_path / "cjk.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    plan = tmp_path / "cjk.json"
    assert main(["plan", str(tmp_path / "cjk.toml"), "-o", str(plan)]) == 0
    capfd.readouterr()
    assert main(["plot", str(plan), "-o", str(tmp_path / "figs")]) == 0
    err = capfd.readouterr().err.strip().splitlines()
    assert err == [
        "freefloat: warning: some names use characters the plots' font lacks (joint names in "
        "another script, say); they are drawn as boxes"
    ]
    assert len(list((tmp_path / "figs").glob("*.png"))) == len(TOPICS) + 1
