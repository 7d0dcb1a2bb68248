"""Exports read back with the libraries that read them elsewhere, compared with the plan."""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import stat
import subprocess
import sys

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.export import from_samples, resample


@pytest.fixture(scope="module")
def plan_file(worked_plan, tmp_path_factory):
    return worked_plan.save(tmp_path_factory.mktemp("plan") / "plan.json")


def _plan_arrays(plan):
    s = plan.samples
    return {
        k: np.asarray(getattr(s, k), dtype=float)
        for k in (
            "t",
            "q",
            "qd",
            "qdd",
            "tau",
            "base_quaternion_xyzw",
            "base_position",
            "end_effector_position",
        )
    }


def test_csv_round_trip(worked_plan, plan_file, tmp_path):
    out = tmp_path / "plan.csv"
    assert main(["export", str(plan_file), "--format", "csv", "-o", str(out)]) == 0
    with open(out, newline="") as handle:
        rows = list(csv.reader(handle))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    assert header[0] == "t [s]"
    assert "q_q1 [rad]" in header and "tau_q2 [N m]" in header and "qdd_q1 [rad/s^2]" in header
    assert "base_qw [1]" in header and "ee_y [m]" in header and "base_x [m]" in header
    col = {name: values[:, i] for i, name in enumerate(header)}
    a = _plan_arrays(worked_plan)
    np.testing.assert_array_equal(col["t [s]"], a["t"])
    for j, joint in enumerate(worked_plan.robot.joints):
        np.testing.assert_array_equal(col[f"q_{joint} [rad]"], a["q"][:, j])
        np.testing.assert_array_equal(col[f"qd_{joint} [rad/s]"], a["qd"][:, j])
        np.testing.assert_array_equal(col[f"qdd_{joint} [rad/s^2]"], a["qdd"][:, j])
        np.testing.assert_array_equal(col[f"tau_{joint} [N m]"], a["tau"][:, j])
    for k, c in enumerate("xyzw"):
        np.testing.assert_array_equal(col[f"base_q{c} [1]"], a["base_quaternion_xyzw"][:, k])
    for k, c in enumerate("xyz"):
        np.testing.assert_array_equal(col[f"base_{c} [m]"], a["base_position"][:, k])
        np.testing.assert_array_equal(col[f"ee_{c} [m]"], a["end_effector_position"][:, k])
    assert stat.S_IMODE(os.stat(out).st_mode) == 0o666 & ~_umask()


def _umask():
    current = os.umask(0)
    os.umask(current)
    return current


def test_resampling_reproduces_the_samples_at_their_instants(worked_plan):
    """Recomputed from the polynomials and the robot, the samples come back to ~1e-12."""
    own = from_samples(worked_plan)
    again = resample(worked_plan, 20.0, times=own.t)
    for name in (
        "q",
        "qd",
        "qdd",
        "tau",
        "base_quaternion_xyzw",
        "base_position",
        "end_effector_position",
    ):
        np.testing.assert_allclose(getattr(again, name), getattr(own, name), atol=1e-10)


def test_resampling_in_small_chunks_reproduces_the_samples(worked_plan, monkeypatch):
    """The attitude is integrated a chunk of steps at a time (the base rates of millions of
    nodes at once exhausted the memory at the largest rate): chunks of 7 steps give the
    plan's own samples as well."""
    import importlib

    trajectory = importlib.import_module("freefloat.export.trajectory")
    monkeypatch.setattr(trajectory, "_CHUNK", 7)
    own = from_samples(worked_plan)
    again = resample(worked_plan, 20.0, times=own.t)
    np.testing.assert_allclose(again.base_quaternion_xyzw, own.base_quaternion_xyzw, atol=1e-10)
    np.testing.assert_allclose(again.base_position, own.base_position, atol=1e-10)


@pytest.mark.parametrize("times", [[5.0, 10.0, 2.0], [0.0, 5.0, 25.0], [-1.0, 5.0]])
def test_resampling_instants_must_ascend_within_the_motion(worked_plan, times):
    """Unsorted instants gave wrong attitudes; ones past T were extrapolated."""
    with pytest.raises(ff.InputError, match="resampling instants must ascend within"):
        resample(worked_plan, 20.0, times=np.array(times))


def test_resampled_grid(worked_plan):
    traj = resample(worked_plan, 7.0)
    T = worked_plan.duration
    assert traj.t[0] == 0.0 and traj.t[-1] == T
    np.testing.assert_allclose(np.diff(traj.t[:-1]), 1 / 7.0, rtol=1e-9)
    assert len(traj.t) == int(np.floor(T * 7.0)) + 2 - (1 if (T * 7.0).is_integer() else 0)
    np.testing.assert_allclose(traj.q, worked_plan.joint_positions(traj.t), atol=1e-14)


def test_mcap_round_trip(worked_plan, plan_file, tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = tmp_path / "plan.mcap"
    assert main(["export", str(plan_file), "--format", "mcap", "-o", str(out)]) == 0
    a = _plan_arrays(worked_plan)
    by_topic: dict[str, list] = {}
    with open(out, "rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            assert channel.message_encoding == "cdr" and schema.encoding == "ros2msg"
            by_topic.setdefault(channel.topic, []).append((schema.name, message, decoded))
    assert set(by_topic) == {"/joint_trajectory", "/joint_states", "/tf", "/end_effector"}
    ((name, _, traj),) = by_topic["/joint_trajectory"]
    assert name == "trajectory_msgs/msg/JointTrajectory"
    assert list(traj.joint_names) == worked_plan.robot.joints
    assert len(traj.points) == len(a["t"])
    for k in (0, 57, len(a["t"]) - 1):
        p = traj.points[k]
        np.testing.assert_array_equal(p.positions, a["q"][k])
        np.testing.assert_array_equal(p.velocities, a["qd"][k])
        np.testing.assert_array_equal(p.accelerations, a["qdd"][k])
        np.testing.assert_array_equal(p.effort, a["tau"][k])
        assert p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 == pytest.approx(
            a["t"][k], abs=1e-9
        )
    states = by_topic["/joint_states"]
    assert len(states) == len(a["t"])
    for k, (name, message, js) in enumerate(states):
        assert name == "sensor_msgs/msg/JointState"
        assert message.log_time == round(a["t"][k] * 1e9)
        np.testing.assert_array_equal(js.position, a["q"][k])
        np.testing.assert_array_equal(js.velocity, a["qd"][k])
        np.testing.assert_array_equal(js.effort, a["tau"][k])
    for k, (name, _, tf) in enumerate(by_topic["/tf"]):
        assert name == "tf2_msgs/msg/TFMessage"
        (tr,) = tf.transforms
        assert tr.header.frame_id == "world" and tr.child_frame_id == "base"
        r, p = tr.transform.rotation, tr.transform.translation
        np.testing.assert_array_equal([r.x, r.y, r.z, r.w], a["base_quaternion_xyzw"][k])
        np.testing.assert_array_equal([p.x, p.y, p.z], a["base_position"][k])
    for k, (_, _, ee) in enumerate(by_topic["/end_effector"]):
        np.testing.assert_array_equal(
            [ee.point.x, ee.point.y, ee.point.z], a["end_effector_position"][k]
        )


def test_ros2_bag_round_trip_resampled(worked_plan, plan_file, tmp_path):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    out = tmp_path / "bag"
    args = ["export", str(plan_file), "--format", "ros2-bag", "--rate", "4", "-o", str(out)]
    assert main(args) == 0
    assert main(args) == 0  # an existing bag is replaced
    assert "version: 8" in (out / "metadata.yaml").read_text()  # rosbag2 metadata format
    slashed = tmp_path / "bag2"  # a bag is a folder: named with a trailing slash, it is one
    assert main([*args[:-1], f"{slashed}{os.sep}"]) == 0
    assert "version: 8" in (slashed / "metadata.yaml").read_text()
    # Truth evaluated here from the plan's coefficients (NumPy) and Pinocchio's inverse
    # dynamics, not by the exporter's resample(): instants every 1/4 s, and T.
    poly = np.polynomial.polynomial
    t = np.arange(0.0, worked_plan.duration, 0.25)
    t = np.append(t, worked_plan.duration) if t[-1] < worked_plan.duration else t
    from legacy import as_format_3  # the file's basis as monomials in t, rebuilt by NumPy

    monomials = as_format_3(json.loads(worked_plan.to_json()))["path"]["coefficients"]
    coefficients = [np.asarray(monomials[n]) for n in worked_plan.robot.joints]
    q, qd, qdd = (
        np.stack([poly.polyval(t, poly.polyder(c, k)) for c in coefficients], axis=1)
        for k in range(3)
    )
    mmap = ff.MomentumMap(ff.load_robot(worked_plan.robot.urdf))
    tau = ff.physics.dynamics.inverse_dynamics_batch(mmap, q, qd, qdd).tau
    ts = get_typestore(Stores.ROS2_HUMBLE)
    got: dict[str, list] = {}
    with Reader(out) as reader:
        for connection, timestamp, raw in reader.messages():
            got.setdefault(connection.topic, []).append(
                (connection.msgtype, timestamp, ts.deserialize_cdr(raw, connection.msgtype))
            )
    ((msgtype, _, traj),) = got["/joint_trajectory"]
    assert msgtype == "trajectory_msgs/msg/JointTrajectory"
    np.testing.assert_allclose([p.positions for p in traj.points], q, rtol=0, atol=1e-12)
    assert [m[0] for m in got["/tf"]] == ["tf2_msgs/msg/TFMessage"] * len(t)
    states = got["/joint_states"]
    assert [m[1] for m in states] == [round(x * 1e9) for x in t]
    np.testing.assert_allclose([m[2].position for m in states], q, rtol=0, atol=1e-12)
    scale = np.abs(tau).max()
    np.testing.assert_allclose([m[2].effort for m in states], tau, rtol=0, atol=1e-10 * scale)
    quats = np.array(
        [[r.x, r.y, r.z, r.w] for r in (m[2].transforms[0].transform.rotation for m in got["/tf"])]
    )
    # The base attitude starts at the plan's start and ends at its goal, on unit quaternions.
    np.testing.assert_allclose(np.linalg.norm(quats, axis=1), 1.0, atol=1e-12)
    start, end = worked_plan.base.start_quaternion_xyzw, worked_plan.base.target_quaternion_xyzw
    assert ff.geodesic_angle(quats[0], np.array(start)) < 1e-12
    assert ff.geodesic_angle(quats[-1], np.array(end)) < 1e-9


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--format", "xml"], "unknown --format 'xml'; valid: csv, mcap, ros2-bag"),
        (["--format", "csv", "--rate", "0"], "--rate must be a positive number of Hz"),
        (["--format", "csv", "--rate", "fast"], "--rate must be a positive number of Hz"),
        (["--format", "mcap", "--rate", "nan"], "--rate must be a positive number of Hz"),
        (["--format", "csv", "--rate", "1e12"], "samples an export may hold"),
        (["--format", "csv", "--rate", "1e308"], "samples an export may hold"),
    ],
)
def test_bad_format_or_rate_is_one_line_and_writes_nothing(plan_file, tmp_path, extra, needle):
    out = tmp_path / "out.file"
    proc = subprocess.run(
        [sys.executable, "-m", "freefloat.cli", "export", str(plan_file), *extra, "-o", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("freefloat: error: ") and needle in lines[0]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("duration", [10.0, 7.3, 0.25])
def test_the_rate_a_refusal_suggests_is_accepted(duration):
    """``--rate 200000`` over 10 s was told to use "a rate up to 2e+05 Hz": the same rate.
    The suggestion is now one the export takes, just below the refused one's limit."""
    import importlib
    import re

    trajectory = importlib.import_module("freefloat.export.trajectory")

    refused = 2.0 * trajectory.MAX_SAMPLES / duration
    with pytest.raises(ff.InputError) as info:
        trajectory.check_rate(refused, duration)
    suggested = float(re.search(r"use a rate up to ([\d.e+]+) Hz", str(info.value)).group(1))
    assert trajectory.check_rate(suggested, duration) <= trajectory.MAX_SAMPLES
    with pytest.raises(ff.InputError):
        trajectory.check_rate(suggested * 1.001, duration)


def test_export_verifies_the_plan_first(plan_file, tmp_path, capsys):
    """A plan whose end effector was moved 0.5 m at one sample exported without a word, for ROS
    tools to trust; it is refused as show and plot refuse it, and --no-verify writes it."""
    import json

    data = json.loads(plan_file.read_text())
    data["samples"]["end_effector_position"][10][0] += 0.5
    tampered = tmp_path / "tampered.json"
    tampered.write_text(json.dumps(data))
    out = tmp_path / "t.csv"
    from freefloat.cli import main

    assert main(["export", str(tampered), "--format", "csv", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "end_effector_position" in err and "--no-verify exports it anyway" in err
    assert not out.exists()
    assert main(["export", str(tampered), "--format", "csv", "-o", str(out), "--no-verify"]) == 0
    assert out.is_file()


def test_a_rate_beyond_the_limit_is_refused_before_the_plan_is_verified(
    plan_file, tmp_path, capsys, monkeypatch
):
    """The rate is checked against the plan's duration first: its refusal costs no
    verification (it came after one)."""
    from freefloat.cli import common, main

    verified = []
    monkeypatch.setattr(common, "require_verified", lambda plan, *_: verified.append(plan))
    out = tmp_path / "r.csv"
    assert main(["export", str(plan_file), "--format", "csv", "--rate", "1e9", "-o", str(out)]) == 2
    assert "samples an export may hold" in capsys.readouterr().err
    assert verified == [] and not out.exists()


def test_a_robot_whose_root_link_is_world_gets_an_inertial_frame_of_another_name(tmp_path):
    """A URDF rooted at a link named ``world`` (ROS-industrial files are): /tf from ``world`` to
    ``world`` would be a frame that is its own parent, which tf2 refuses. The MCAP, read back
    with the mcap library, names the inertial frame ``freefloat_world`` in every header."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from freefloat.robot.model import robots_dir

    urdf = tmp_path / "rooted.urdf"
    text = (robots_dir() / "planar_2dof.urdf").read_text()
    urdf.write_text(
        text.replace('link name="base"', 'link name="world"').replace(
            'parent link="base"', 'parent link="world"'
        )
    )
    scenario = ff.Scenario.from_toml(robots_dir() / "scenarios" / "worked_example.toml")
    robot = ff.load_robot(urdf, "ee")
    plan = ff.plan(dataclasses.replace(scenario, robot=robot), samples=11)
    out = tmp_path / "plan.mcap"
    assert (
        main(["export", str(plan.save(tmp_path / "p.json")), "--format", "mcap", "-o", str(out)])
        == 0
    )
    frames = set()
    with open(out, "rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        for _, channel, _, decoded in reader.iter_decoded_messages():
            if channel.topic == "/tf":
                ((stamped,),) = [decoded.transforms]
                assert (stamped.header.frame_id, stamped.child_frame_id) == (
                    "freefloat_world",
                    "world",
                )
            elif channel.topic in ("/end_effector", "/joint_trajectory"):
                frames.add(decoded.header.frame_id)
    assert frames == {"freefloat_world"}


def test_a_bag_through_a_dangling_link_is_refused_and_nothing_is_made(plan_file, tmp_path, capsys):
    """A bag (a folder) through a link to nothing was made at the link's end (at the root of
    the file system for a link to /nonexistent)."""
    link = tmp_path / "bag"
    link.symlink_to(tmp_path / "elsewhere")
    argv = ["export", str(plan_file), "--format", "ros2-bag", "-o", str(link)]
    assert main(argv) == 2
    assert "goes through a symbolic link to nothing" in capsys.readouterr().err
    assert not (tmp_path / "elsewhere").exists()


def test_a_bag_the_disk_cannot_hold_is_one_line_and_leaves_nothing(
    plan_file, tmp_path, capsys, monkeypatch
):
    """SQLite's "database or disk is full" (a 64 kB file system) was a traceback."""
    import sqlite3

    import rosbags.rosbag2

    class Full(rosbags.rosbag2.Writer):
        def write(self, *args, **kwargs):
            raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(rosbags.rosbag2, "Writer", Full)
    target = tmp_path / "out" / "bag"
    target.parent.mkdir()
    assert main(["export", str(plan_file), "--format", "ros2-bag", "-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert err == f"freefloat: error: cannot write the bag {target}: database or disk is full\n"
    assert list(target.parent.iterdir()) == []
