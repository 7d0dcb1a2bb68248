"""Sweeps: the worked example's feasibility map, validation before any job, resume, Dask."""

from __future__ import annotations

import csv
import os
import shutil
import sys
from dataclasses import replace
from pathlib import Path

import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.sweep import TIMING_COLUMNS, SweepSpec

import reference as ref

DATA = Path(__file__).parent / "data"


#: A 9-job subset of the yaw sweep (plans and infeasible refusals) for the quicker tests.
SUBSET = [-55.0, -50.0, -40.0, -30.0, -20.0, 0.0, 22.0, 23.0, 25.0]


def _sweep_file(tmp_path: Path, body: str, name: str = "sweep.toml") -> Path:
    shutil.copy(DATA / "worked_example_auto.toml", tmp_path / "worked_example_auto.toml")
    path = tmp_path / name
    path.write_text('scenario = "worked_example_auto.toml"\nsamples = 21\n' + body)
    return path


def _subset_file(tmp_path: Path) -> Path:
    values = ", ".join(repr(v) for v in SUBSET)
    return _sweep_file(tmp_path, f'[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [{values}]\n')


def _without_timings(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    return [{k: v for k, v in row.items() if k not in TIMING_COLUMNS} for row in rows]


@pytest.fixture(scope="module")
def yaw_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "yaw.csv"
    rows = ff.sweep(DATA / "yaw_sweep.toml", workers=2, output=out, progress=False)
    return rows, out


def test_worked_example_yaw_sweep_planned_inside_infeasible_outside(yaw_sweep):
    rows, out = yaw_sweep
    assert len(rows) == 81
    assert [r.index for r in rows] == list(range(81))
    lo, hi = rows[0].yaw_change_min_deg, rows[0].yaw_change_max_deg
    assert (lo, hi) == pytest.approx(ref.worked_bounds_deg(), abs=1e-6)  # closed form, grid
    for row in rows:
        change = round(row.values[0] + 50.0, 9)
        if lo < change < hi:
            assert row.status == "planned", (change, row.message)
            assert row.attitude_error_rad < 1e-9
            assert row.peak_torque > 0 and row.path_length > 0
            assert row.message == ""
        else:
            assert row.status == "infeasible", (change, row.message)
            assert "outside the reachable interval" in row.message
        assert "\n" not in row.message
    with open(out, newline="") as handle:
        lines = list(csv.reader(handle))
    assert lines[0][:3] == ["index", "goal.base_zyx_deg.0", "status"]
    assert len(lines) == 82
    assert [float(line[1]) for line in lines[1:]] == [float(v) for v in range(-55, 26)]


def test_unknown_key_is_refused_naming_the_valid_keys(tmp_path):
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_ypr.0"\nvalues = [1.0]\n')
    with pytest.raises(ff.UnknownNameError) as info:
        SweepSpec.from_toml(path)
    message = str(info.value)
    assert "goal.base_ypr.0" in message and "goal.joints" in message
    assert "goal.base_zyx_deg" in message and "\n" not in message
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.joints.q7"\nvalues = [1.0]\n')
    with pytest.raises(ff.UnknownNameError, match=r"goal\.joints\.q1, goal\.joints\.q2"):
        SweepSpec.from_toml(path)
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.3"\nvalues = [1.0]\n')
    with pytest.raises(ff.UnknownNameError, match=r"goal\.base_zyx_deg\.2"):
        SweepSpec.from_toml(path)


@pytest.mark.parametrize(
    ("axis", "match"),
    [
        ('key = "duration"\nvalues = [10.0, -1.0]', r"'duration' = -1\.0: duration must be > 0"),
        ('key = "goal.joints.q1"\nvalues = ["ninety"]', r"goal\.joints\.q1.*must be of the"),
        ('key = "duration"\nvalues = { start = 1.0, stop = 2.0 }', r"needs start, stop and num"),
        ('key = "duration"\nvalues = { start = 1.0, stop = 2.0, num = 0 }', r"num must be"),
        ('key = "duration"\nvalues = []', r"non-empty list"),
        ('key = "goal"\nvalues = [1.0]', r"names a table or list.*goal\.joints"),
        # integers beyond the floats, and a range whose step overflows: tracebacks before
        (f'key = "goal.joints.q2"\nvalues = [{10**400}]', r"must be finite, got 1000.*\(401 d"),
        (
            f'key = "goal.joints.q2"\nvalues = {{ start = {10**400}, stop = 2.0, num = 3 }}',
            r"range start must be finite",
        ),
        (
            f'key = "goal.joints.q2"\nvalues = {{ normal = [{10**400}, 1.0], samples = 3 }}',
            r"normal must be two finite numbers",
        ),
        (
            'key = "goal.joints.q2"\nvalues = { start = -1.7e308, stop = 1.7e308, num = 3 }',
            r"range from -1\.7e\+308 to 1\.7e\+308 overflows the floats",
        ),
        # numpy's uniform draw overflowed: OverflowError, a traceback
        (
            'key = "goal.joints.q2"\nvalues = { uniform = [-1e308, 1e308], samples = 2 }',
            r"uniform must be two finite numbers of magnitude at most 1e\+09",
        ),
    ],
)
def test_bad_values_are_refused_before_any_job(tmp_path, monkeypatch, axis, match):
    path = _sweep_file(tmp_path, f"[[axis]]\n{axis}\n")

    def no_job(job):  # pragma: no cover - must not be reached
        raise AssertionError("a job ran")

    # ff.sweep is the function; the package's modules are reached through sys.modules
    monkeypatch.setattr(sys.modules["freefloat.sweep.runner"], "run_job_collecting", no_job)
    with pytest.raises(ff.FreeFloatError, match=match):
        ff.sweep(path, workers=1, progress=False)


def test_a_grid_of_1e15_jobs_is_refused_at_once(tmp_path):
    """Each axis within its limit, their product counted: it was listed first, 1e15 tuples
    (a hang, memory growing without end)."""
    axes = "".join(
        f'[[axis]]\nkey = "{key}"\nvalues = {{ start = 1.0, stop = 2.0, num = 100000 }}\n'
        for key in ("goal.joints.q1", "goal.joints.q2", "goal.base_zyx_deg.0")
    )
    with pytest.raises(
        ff.InputLimitError, match=r"jobs of the sweep = 1000000000000000 is outside"
    ):
        SweepSpec.from_toml(_sweep_file(tmp_path, axes))


def test_cli_exit_codes_and_no_file_on_bad_input(tmp_path, capsys):
    out = tmp_path / "out.csv"
    bad = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.nope"\nvalues = [1.0]\n', "bad.toml")
    assert main(["sweep", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("freefloat: error: ") and err.count("\n") == 1
    assert "goal.nope" in err and "Traceback" not in err
    assert not out.exists()
    three = _sweep_file(
        tmp_path,
        "".join(
            f'[[axis]]\nkey = "{k}"\nvalues = [1.0]\n'
            for k in ("goal.joints.q1", "goal.joints.q2", "duration")
        ),
        "three.toml",
    )
    assert main(["sweep", str(three), "-o", str(out), "--plots", str(tmp_path / "p")]) == 2
    assert "1 or 2 axes" in capsys.readouterr().err
    assert not out.exists() and not (tmp_path / "p").exists()
    assert main(["sweep", str(three), "-o", str(out), "--workers", "0"]) == 2
    assert not out.exists()
    assert main(["sweep", str(DATA / "nope.toml"), "-o", str(out)]) == 2
    capsys.readouterr()
    two = _sweep_file(
        tmp_path,
        '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [-20.0, 30.0]\n'
        '[[axis]]\nkey = "duration"\nvalues = [10.0, 20.0]\n',
        "two.toml",
    )
    plots = tmp_path / "plots"
    (plots / "sweep_heatmap.png").mkdir(parents=True)  # the figure's name taken by a folder
    assert main(["sweep", str(two), "-o", str(out), "--workers", "1", "--plots", str(plots)]) == 2
    assert "sweep_heatmap.png' is a directory" in capsys.readouterr().err
    assert not out.exists()  # refused before any job ran
    (plots / "sweep_heatmap.png").rmdir()
    assert main(["sweep", str(two), "-o", str(out), "--workers", "1", "--plots", str(plots)]) == 0
    printed = capsys.readouterr().out
    assert "4 jobs" in printed and "2 planned, 2 infeasible, 0 failed" in printed
    assert (plots / "sweep_heatmap.png").stat().st_size > 0
    assert len(_without_timings(out)) == 4


def test_resume_after_an_interrupted_run_gives_the_same_file(tmp_path):
    path = _subset_file(tmp_path)
    out = tmp_path / "subset.csv"
    ff.sweep(path, workers=1, output=out, progress=False)
    whole = out.read_text()
    lines = whole.splitlines(keepends=True)
    # interrupted after 4 rows, in completion order (not index order), with a torn 5th line
    out.write_text(lines[0] + lines[3] + lines[1] + lines[5] + lines[2] + lines[6][:17])
    ran = []
    rows = ff.sweep(path, workers=1, output=out, progress=False, on_row=ran.append)
    assert sorted(r.index for r in ran) == [3, 5, 6, 7, 8]
    assert [r.index for r in rows] == list(range(len(SUBSET)))
    assert _without_timings(out) == [
        {k: v for k, v in row.items() if k not in TIMING_COLUMNS}
        for row in csv.DictReader(whole.splitlines())
    ]
    # timings of kept rows are kept (total_time_s: before message and inputs)
    kept = [line.split(",")[-3] for line in lines[1:3]]
    assert [line.split(",")[-3] for line in out.read_text().splitlines()[1:3]] == kept
    # a finished file is left as it is
    again = out.read_text()
    assert ff.sweep(path, workers=1, output=out, progress=False, on_row=ran.append)
    assert out.read_text() == again and len(ran) == 5


def test_an_edited_results_file_is_refused_on_resume(tmp_path):
    """A planned row given a 5 rad attitude error, a NaN or a word in a number's place, or a
    status the rows never have, was kept as it was on resume (the summary then read "9
    planned" for 10 jobs). Each is refused, naming the line, the file left as it was."""
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [0.0, 10.0]\n')
    out = tmp_path / "two.csv"
    ff.sweep(path, workers=1, output=out, progress=False)
    whole = out.read_text()
    one, two = csv.DictReader(whole.splitlines())
    assert one["status"] == two["status"] == "planned"
    edits = {
        "attitude_error_rad": ("5.0", "a planned row whose attitude error 5.0 rad exceeds"),
        "path_length": ("nan", "path_length 'nan' is not a finite number"),
        "peak_torque": ("lots", "peak_torque 'lots' is not a finite number"),
        "status": ("bogus", "status 'bogus' is none of planned, infeasible, failed"),
    }
    for column, (value, message) in edits.items():
        rows = list(csv.DictReader(whole.splitlines()))
        rows[1][column] = value
        with open(out, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]), lineterminator="\n")
            writer.writeheader()
            writer.writerows(rows)
        edited = out.read_text()
        with pytest.raises(ff.ScenarioError) as info:
            ff.sweep(path, workers=1, output=out, progress=False)
        assert f"{out} line 3: {message}" in str(info.value)
        assert out.read_text() == edited


def test_rows_of_an_edited_base_scenario_or_robot_are_not_resumed(tmp_path):
    """Rows planned with a 10 s duration were kept on resume after the base scenario was
    changed to 20 s, and mixed with the new rows: the file records a digest of the base
    scenario and robot (``inputs``), and a row of other inputs is refused, naming the line,
    the file left as it was. A file of an older freefloat (no such column) is refused too."""
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [0.0, 10.0]\n')
    out = tmp_path / "two.csv"
    ff.sweep(path, workers=1, output=out, progress=False)
    lines = out.read_text().splitlines(keepends=True)
    assert (
        lines[0].rstrip().endswith(",inputs")
        and len({line.split(",")[-1] for line in lines[1:]}) == 1
    )
    out.write_text(lines[0] + lines[1])  # interrupted after one row
    scenario = tmp_path / "worked_example_auto.toml"
    original = scenario.read_text()
    assert "duration = 10.0" in original
    scenario.write_text(original.replace("duration = 10.0", "duration = 20.0"))
    with pytest.raises(ff.ScenarioError) as info:
        ff.sweep(path, workers=1, output=out, progress=False)
    assert str(info.value).startswith(f"{out} line 2 came from another base scenario or robot")
    assert out.read_text() == lines[0] + lines[1]
    scenario.write_text(original)  # the same inputs again: resumed
    assert len(ff.sweep(path, workers=1, output=out, progress=False)) == 2
    older = "".join(line[: line.rindex(",")] + "\n" for line in out.read_text().splitlines())
    out.write_text(older)
    with pytest.raises(ff.ScenarioError, match="written by an older freefloat"):
        ff.sweep(path, workers=1, output=out, progress=False)
    assert out.read_text() == older


def test_the_inputs_digest_follows_the_robot_file(tmp_path):
    """An edited URDF (a link's mass) changes the digest: its rows are not this sweep's."""
    from freefloat.robot.model import robots_dir
    from freefloat.sweep.results import inputs_digest

    shutil.copy(robots_dir() / "planar_2dof.urdf", tmp_path / "arm.urdf")
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [0.0]\n')
    scenario = tmp_path / "worked_example_auto.toml"
    text = scenario.read_text()
    assert 'robot = "planar_2dof"' in text
    scenario.write_text(text.replace('robot = "planar_2dof"', 'robot = "arm.urdf"'))
    before = inputs_digest(SweepSpec.from_toml(path))
    urdf = (tmp_path / "arm.urdf").read_text()
    assert urdf.count('<mass value="40.0"/>') == 1
    (tmp_path / "arm.urdf").write_text(urdf.replace('<mass value="40.0"/>', '<mass value="41.0"/>'))
    edited = inputs_digest(SweepSpec.from_toml(path))
    assert edited != before
    # an SRDF beside the URDF (the pairs never checked) is read too, and so is an edit of it
    srdf = tmp_path / "arm.srdf"
    srdf.write_text('<robot name="planar_2dof">\n</robot>\n')
    beside = inputs_digest(SweepSpec.from_toml(path))
    srdf.write_text(
        '<robot name="planar_2dof">\n<disable_collisions link1="base" link2="link2" '
        'reason="Never"/>\n</robot>\n'
    )
    assert len({edited, beside, inputs_digest(SweepSpec.from_toml(path))}) == 3


def test_a_results_file_saved_with_a_byte_order_mark_resumes(tmp_path):
    """A spreadsheet saved the file with a BOM: its header read as another sweep's."""
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [0.0, 10.0]\n')
    out = tmp_path / "two.csv"
    ff.sweep(path, workers=1, output=out, progress=False)
    whole = out.read_text()
    out.write_text("\ufeff" + whole, encoding="utf-8")
    ran = []
    ff.sweep(path, workers=1, output=out, progress=False, on_row=ran.append)
    assert ran == [] and out.read_text() == whole  # nothing run again; written without it


def test_output_of_another_sweep_is_refused(tmp_path):
    out = tmp_path / "other.csv"
    out.write_text("index,duration,status\n")
    with pytest.raises(ff.ScenarioError, match="holds another sweep"):
        ff.sweep(_subset_file(tmp_path), workers=1, output=out, progress=False)
    assert out.read_text() == "index,duration,status\n"


def _loopback_cluster(distributed, workers: int, threads: int):  # type: ignore[no-untyped-def]
    """A Dask LocalCluster of worker processes on loopback, no dashboard."""
    return distributed.LocalCluster(
        processes=True,
        n_workers=workers,
        threads_per_worker=threads,
        host="127.0.0.1",
        dashboard_address=None,
    )


def test_dask_local_cluster_gives_the_local_rows(tmp_path, yaw_sweep):
    distributed = pytest.importorskip("distributed")
    path = _subset_file(tmp_path)
    with (
        _loopback_cluster(distributed, workers=2, threads=1) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = ff.sweep(path, client=client, output=tmp_path / "dask.csv", progress=False)
    by_value = {row.values: row for row in yaw_sweep[0]}  # the local run, 2 processes
    local = [replace(by_value[r.values], index=r.index).without_timings() for r in remote]
    assert [r.without_timings() for r in remote] == local
    assert [r.status for r in remote] == ["infeasible"] * 2 + ["planned"] * 5 + ["infeasible"] * 2
    ff.sweep(path, workers=1, output=tmp_path / "local.csv", progress=False)
    assert _without_timings(tmp_path / "dask.csv") == _without_timings(tmp_path / "local.csv")


def test_a_payload_mass_axis_plans_each_mass_on_its_own_robot(tmp_path, monkeypatch):
    """Each payload mass is a different robot: a worker must not reuse the first one's."""
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    base = (DATA / "worked_example_auto.toml").read_text()
    base += "\n[payload]\nmass = 5.0\ninertia = [0.01, 0.01, 0.01, 0.0, 0.0, 0.0]\n"
    (tmp_path / "held.toml").write_text(base)
    sweep = tmp_path / "mass.toml"
    sweep.write_text(
        'scenario = "held.toml"\nsamples = 21\n[[axis]]\nkey = "payload.mass"\n'
        "values = [5.0, 40.0]\n"
    )
    rows = ff.sweep(SweepSpec.from_toml(sweep), workers=1, progress=False)
    assert [r.status for r in rows] == ["planned", "planned"], [r.message for r in rows]
    # Independent: each mass planned on its own, in this process.
    for row, mass in zip(rows, (5.0, 40.0), strict=True):
        (tmp_path / "one.toml").write_text(base.replace("mass = 5.0", f"mass = {mass}"))
        alone = ff.plan(ff.Scenario.from_toml(tmp_path / "one.toml"), samples=21)
        peak = max(abs(x) for sample in alone.samples.tau for x in sample)
        assert row.peak_torque == pytest.approx(peak, rel=1e-9)
    assert rows[0].peak_torque != pytest.approx(rows[1].peak_torque, rel=1e-3)


def test_an_objective_axis_records_each_objective_and_its_value(tmp_path):
    shutil.copy(DATA / "worked_example_auto.toml", tmp_path / "base.toml")
    base = (tmp_path / "base.toml").read_text()
    assert "\n[path]" not in base  # automatic freedom: no [path] table of its own
    (tmp_path / "worked_example_auto.toml").write_text(base + '\n[path]\nobjective = "min_norm"\n')
    path = tmp_path / "objectives.toml"
    path.write_text(
        'scenario = "worked_example_auto.toml"\nsamples = 21\n[[axis]]\nkey = "path.objective"\n'
        'values = ["min_norm", "min_effort"]\n'
    )
    out = tmp_path / "objectives.csv"
    rows = ff.sweep(path, workers=1, output=out, progress=False)
    assert [(r.status, r.objective) for r in rows] == [
        ("planned", "min_norm"),
        ("planned", "min_effort"),
    ]
    effort = ff.plan(
        ff.Scenario.from_toml(tmp_path / "worked_example_auto.toml"), objective="min_effort"
    )
    assert rows[1].objective_value == pytest.approx(effort.objective.value, rel=1e-12)
    # the file reads back (resume) to the same rows
    again = ff.sweep(path, workers=1, output=out, progress=False)
    assert [r.without_timings() for r in again] == [r.without_timings() for r in rows]


def test_a_warning_of_every_job_is_said_once_with_the_prefix(tmp_path, capfd):
    """The planar arm has no collision geometry: each job's plan notes it, the sweep says it
    once, as a ``freefloat: warning:`` line (workers print nothing themselves)."""
    path = _sweep_file(tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [-30.0, 0.0]\n')
    assert main(["sweep", str(path), "-o", str(tmp_path / "out.csv"), "--workers", "2"]) == 0
    err = capfd.readouterr().err.splitlines()
    assert [line for line in err if "clearance" in line] == [
        "freefloat: warning: clearance: not checked for link1, link2 (no collision geometry)"
    ]
    rows = ff.sweep(path, workers=1, progress=False)
    assert [row.status for row in rows] == ["planned", "planned"]


def test_a_dask_worker_with_several_threads_is_refused_before_any_job(tmp_path, yaw_sweep):
    distributed = pytest.importorskip("distributed")
    path = _subset_file(tmp_path)
    with (
        _loopback_cluster(distributed, workers=1, threads=2) as cluster,
        distributed.Client(cluster) as client,
        pytest.raises(ff.InputError, match=r"runs 2 threads; freefloat needs one thread"),
    ):
        ff.sweep(path, client=client, output=tmp_path / "dask.csv", progress=False)
    assert not (tmp_path / "dask.csv").exists()


def test_a_job_that_spins_a_joint_is_flagged_in_its_row_and_said_once(tmp_path, capfd):
    """Goal yaws -48 and -47 deg turn the elbow more than a full turn beyond its span: each
    row carries the excursion (against the plan of that goal, its joint values sampled
    densely here), and the sweep says it once for both jobs, not once per job."""
    import dataclasses
    import math

    import numpy as np

    path = _sweep_file(
        tmp_path, '[[axis]]\nkey = "goal.base_zyx_deg.0"\nvalues = [-48.0, -47.0, -30.0]\n'
    )
    out = tmp_path / "out.csv"
    assert main(["sweep", str(path), "-o", str(out), "--workers", "2"]) == 0
    said = [line for line in capfd.readouterr().err.splitlines() if "full turn" in line]
    assert len(said) == 1
    assert said[0].startswith(
        "freefloat: warning: 2 planned job(s) turn a joint a full turn or more beyond its "
        "start-goal span (jobs 0, 1; at most "
    )
    with open(out, newline="") as handle:
        rows = {float(r["goal.base_zyx_deg.0"]): r for r in csv.DictReader(handle)}
    scenario = ff.Scenario.from_toml(tmp_path / "worked_example_auto.toml")
    goal = ff.quat_from_zyx(math.radians(-47.0), 0.0, 0.0)
    plan = ff.plan(dataclasses.replace(scenario, goal_attitude=goal), samples=21)
    t = np.linspace(0.0, plan.duration, 400001)
    q = np.degrees(plan.joint_positions(t))
    ends = np.degrees(np.array([plan.request.start_joints, plan.request.goal_joints]))
    beyond = np.maximum(q.max(axis=0) - ends.max(axis=0), ends.min(axis=0) - q.min(axis=0))
    assert float(rows[-47.0]["largest_excursion_deg"]) == pytest.approx(beyond.max(), abs=1e-4)
    assert float(rows[-47.0]["largest_excursion_deg"]) >= 360.0
    assert float(rows[-30.0]["largest_excursion_deg"]) < 360.0
    # The spacecraft's largest turn on the way: the planar closed form's yaw rate
    # (tests/reference.py) along the same plans, by the trapezoid rule on the dense grid
    # (the spinning one passes 180 deg, where a sample can fall short of the peak).
    import reference

    def largest_turn(plan: ff.Plan) -> tuple[float, float]:
        """The largest sampled turn (deg), and how much more it can be between samples."""
        samples = plan.path().evaluate(t)
        g1, g2 = reference._gain_arrays(samples.q[:, 0], samples.q[:, 1])
        rate = g1 * samples.qd[:, 0] + g2 * samples.qd[:, 1]
        yaw = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])
        sampled = float(np.degrees(np.abs(np.angle(np.exp(1j * yaw)))).max())
        return sampled, float(np.degrees(np.abs(rate).max() * (t[1] - t[0])))

    spun = float(rows[-47.0]["largest_turn_deg"])
    sampled, between = largest_turn(plan)
    assert sampled - 1e-9 <= spun <= min(180.0, sampled + between)
    goal = ff.quat_from_zyx(math.radians(-30.0), 0.0, 0.0)
    calm = ff.plan(dataclasses.replace(scenario, goal_attitude=goal), samples=21)
    assert float(rows[-30.0]["largest_turn_deg"]) == pytest.approx(largest_turn(calm)[0], abs=1e-6)


@pytest.mark.parametrize("reply", [b"", b"\xff" * 64])
def test_a_server_that_is_no_scheduler_is_named_not_waited_on(monkeypatch, reply):
    """A loopback server that accepts and then says nothing (a web server waiting for its
    request held the sweep for ever), or answers garbage (read as a 3 EiB message length:
    MemoryError's traceback). Both refused in a bounded time, naming the address."""
    pytest.importorskip("distributed")
    import socket
    import threading

    from freefloat.sweep import runner

    monkeypatch.setattr(runner, "HANDSHAKE_GRACE", 1.0)
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held = []

    def serve() -> None:
        conn, _ = server.accept()
        held.append(conn)
        if reply:
            conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    with pytest.raises(ff.InputError, match=f"cannot connect to the Dask scheduler '{address}'"):
        runner.connect(address, timeout=1.0)
    for conn in held:
        conn.close()
    server.close()


def test_a_sweep_whose_scenario_is_itself_says_so(tmp_path):
    """It read "unknown sweep key 'duration'", the sweep file parsed as its own scenario."""
    path = tmp_path / "self.toml"
    path.write_text('scenario = "self.toml"\n[[axis]]\nkey = "duration"\nvalues = [1.0]\n')
    with pytest.raises(ff.ScenarioError, match=r"the sweep's scenario 'self\.toml' is the sweep"):
        SweepSpec.from_toml(path)


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_workers_leave_when_the_sweep_is_killed_outright(tmp_path):
    """SIGKILL, which nothing can catch, left the fork server, its two workers and the
    resource tracker running for ever; they now leave within seconds, even while the killed
    sweep waits to be reaped (a zombie, as here until the end)."""
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "killed.csv"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "freefloat.cli",
            "sweep",
            str(DATA / "yaw_sweep.toml"),
            "-o",
            str(out),
            "--workers",
            "2",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline and (not out.exists() or out.read_text().count("\n") < 4):
        time.sleep(0.05)
    helpers = _children(proc.pid)
    workers = [w for h in helpers for w in _children(h)]
    assert len(helpers) >= 2 and len(workers) >= 1, (helpers, workers)  # mid-sweep
    proc.send_signal(signal.SIGKILL)  # not reaped until the end: a zombie meanwhile
    left = [p for p in helpers + workers if Path(f"/proc/{p}").exists()]
    deadline = time.monotonic() + 15.0
    while left and time.monotonic() < deadline:
        time.sleep(0.1)
        left = [p for p in left if Path(f"/proc/{p}").exists()]
    for pid in left:  # not to leave them to the next test either
        os.kill(pid, signal.SIGKILL)
    proc.wait()
    assert left == []


def test_a_resumed_sweep_says_how_many_jobs_it_kept(tmp_path, capsys):
    from freefloat.cli import main

    path = _subset_file(tmp_path)
    out = tmp_path / "subset.csv"
    assert main(["sweep", str(path), "-o", str(out), "--workers", "1"]) == 0
    assert "(resumed:" not in capsys.readouterr().out  # a whole run
    lines = out.read_text().splitlines(keepends=True)
    out.write_text("".join(lines[:4]))  # the header and three rows
    assert main(["sweep", str(path), "-o", str(out), "--workers", "1"]) == 0
    assert f"(resumed: 3 of {len(SUBSET)} jobs were in it, {len(SUBSET) - 3} run now)" in (
        capsys.readouterr().out
    )
