"""Plots: files exist, are sensible images, and carry the plan's samples."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.colors import to_rgba
from PIL import Image

from freefloat.cli import main
from freefloat.viz.plots import TOPICS, figures


@pytest.fixture(scope="module")
def figs(worked_plan):
    return figures(worked_plan)


def _close(*figures):
    """Close figures a test made (pyplot keeps every figure until closed)."""
    import matplotlib.pyplot as plt

    for fig in figures:
        plt.close(fig)


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


def _limits_in_view(values, marks):
    """The marks within two data spans of the data (the figure's rule, restated)."""
    low, high = float(np.min(values)), float(np.max(values))
    reach = 2.0 * max(high - low, 1e-9 + 1e-3 * max(abs(low), abs(high)))
    return [m for m in marks if low - reach <= m <= high + reach]


def test_joint_limits_are_drawn_from_the_urdf():
    """Limits near the data are drawn; those far beyond it (they would flatten every line)
    are named in the legend instead: together, every finite URDF limit."""
    import freefloat as ff

    from conftest import ROOT

    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    robot = ff.load_robot(plan.robot.urdf)
    figs = figures(plan, ("joint_positions", "joint_rates"))
    for topic, key in (("joint_positions", "q"), ("joint_rates", "qd")):
        ax = figs[topic].axes[0]
        data = np.degrees(np.asarray(getattr(plan.samples, key)))
        drawn = sorted(
            round(line.get_ydata()[0], 9) for line in ax.lines if line.get_label() == "_limit"
        )
        marks = {
            j.name: [
                float(np.degrees(v))
                for v in (
                    (j.lower, j.upper) if key == "q" else (-j.velocity_limit, j.velocity_limit)
                )
            ]
            for j in robot.joints
        }
        shown = {name: _limits_in_view(data, m) for name, m in marks.items()}
        assert drawn == sorted(round(v, 9) for m in shown.values() for v in m), topic
        far = [name for name, m in marks.items() if len(shown[name]) < len(m)]
        labels = [line.get_label() for line in ax.get_legend().get_lines()]
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        which = "\n".join(far) if len(far) <= 3 else f"{len(far)} joints"
        said = f"limits beyond the axes\n(not drawn): {which}"
        assert labels and (said in texts) == bool(far), texts
        assert not far or all(abs(v) > 2 * np.ptp(data) for name in far for v in marks[name])
    # the UR5's rate limits (180 deg/s) lie far beyond its motion: named, not drawn
    assert "limits beyond the axes" in " ".join(
        t.get_text() for t in figs["joint_rates"].axes[0].get_legend().get_texts()
    )
    _close(*figs.values())


def test_prismatic_joints_get_their_own_axis_in_metres(worked_plan):
    """A robot with revolute and prismatic joints: metres never share an axis with degrees."""
    from dataclasses import replace

    robot = replace(worked_plan.robot, joint_kinds=["revolute", "prismatic"])
    figs = figures(replace(worked_plan, robot=robot), ("joint_positions", "joint_rates"))
    q = np.asarray(worked_plan.samples.q)
    for topic, unit in (("joint_positions", "m"), ("joint_rates", "m/s")):
        left, right = figs[topic].axes
        assert left.get_ylabel().endswith("[deg]" if unit == "m" else "[deg/s]")
        assert right.get_ylabel() == f"prismatic joint {topic.split('_')[1][:-1]} [{unit}]"
        on_left = [line.get_label() for line in left.lines]
        assert "q1" in on_left and "q2" not in on_left
        assert "q2" in [line.get_label() for line in right.lines]
        assert "q2" in [t.get_text() for t in left.get_legend().get_texts()]  # one legend
    right = figs["joint_positions"].axes[1]
    q2 = next(line for line in right.lines if line.get_label() == "q2")
    np.testing.assert_array_equal(q2.get_ydata(), q[:, 1])  # metres: not scaled to degrees
    _close(*figs.values())


def test_twelve_joints_have_twelve_distinct_styles(worked_plan):
    """Matplotlib's cycle has ten colours: the eleventh joint took the first's."""
    from dataclasses import replace

    names = [f"j{k}" for k in range(12)]
    samples = worked_plan.samples
    wide = {
        key: np.tile(np.asarray(getattr(samples, key)), 6).tolist() for key in ("q", "qd", "tau")
    }
    plan = replace(
        worked_plan,
        robot=replace(worked_plan.robot, joints=names, joint_kinds=["revolute"] * 12),
        samples=replace(samples, **wide),
        request=replace(worked_plan.request, goal_joints=[0.0] * 12, start_joints=[0.0] * 12),
    )
    ax = figures(plan, ("joint_positions",))["joint_positions"].axes[0]
    lines = [line for line in ax.lines if line.get_label() in names]
    assert len(lines) == 12
    styles = {
        (tuple(np.round(to_rgba(line.get_color()), 6)), line.get_linestyle()) for line in lines
    }
    assert len(styles) == 12
    _close(ax.figure)


def test_long_joint_names_are_cut_in_legends_and_leave_the_axes_their_room(worked_plan):
    """Joints named with 20,000 characters squeezed the axes to nothing (matplotlib warned
    that its layout collapsed); legends now show each name's two ends, 40 characters."""
    import warnings
    from dataclasses import replace

    long = ["a" * 10_000 + "q1" + "b" * 10_000, "c" * 10_000 + "q2" + "d" * 10_000]
    plan = replace(worked_plan, robot=replace(worked_plan.robot, joints=long))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the layout warning would fail the test
        fig = figures(plan, ("joint_positions",))["joint_positions"]
        fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "a" * 18 + "..." + "b" * 19 in labels and "c" * 18 + "..." + "d" * 19 in labels
    width = fig.axes[0].get_position().width
    assert width > 0.3, width  # the data keeps a third of the figure at least
    _close(fig)


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


def test_a_figure_that_cannot_be_written_leaves_none_behind(tmp_path, worked_plan, capsys):
    """The last figure's name was a folder: seven of eight figures were written first."""
    plan_path = worked_plan.save(tmp_path / "p.json")
    out = tmp_path / "figs"
    (out / "overview.png").mkdir(parents=True)
    assert main(["plot", str(plan_path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("freefloat: error: a figure ") and "is a directory" in err
    assert err.count("\n") == 1
    assert [p.name for p in out.iterdir()] == ["overview.png"]


def test_the_main_jobs_outputs_are_checked_before_any_work(tmp_path, monkeypatch, capsys):
    """`freefloat plan` with no arguments writes a plan, a page and plots: with the page's
    name taken by a folder it refused only after writing the plan."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "freefloat-out" / "plan.html").mkdir(parents=True)
    assert main(["plan"]) == 2
    assert "the playback page 'freefloat-out/plan.html' is a directory" in capsys.readouterr().err
    assert [p.name for p in (tmp_path / "freefloat-out").iterdir()] == ["plan.html"]
