"""Progress on a terminal, silence (no control characters) when piped; -v and -q."""

from __future__ import annotations

import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import freefloat as ff

CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")  # anything but tab and newline


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(ff.__file__).resolve().parents[1])
    env["TERM"] = "xterm-256color"
    env.pop("NO_COLOR", None)
    return env


def _command(tmp_path, *flags):
    return [
        sys.executable,
        "-m",
        "freefloat.cli",
        *flags,
        "plan",
        str(ff.default_scenario_path()),
        "-o",
        str(tmp_path / "plan.json"),
    ]


def test_progress_shows_in_a_pseudo_terminal(tmp_path):
    master, slave = pty.openpty()
    proc = subprocess.Popen(
        _command(tmp_path), stdin=slave, stdout=slave, stderr=slave, env=_env(), close_fds=True
    )
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 4096)
        except OSError:  # EIO once the child has closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    assert proc.wait(timeout=120) == 0
    text = b"".join(chunks).decode("utf-8", "replace")
    plain = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", text)
    assert "solve ..." in plain  # the live spinner line
    assert re.search(r"done solve \(\d+\.\d\d s\)", plain)
    assert "done sample and verify" in plain
    assert "\x1b[" in text  # drawn live (ANSI control sequences)
    assert "freefloat plan:" in text


def test_piped_output_has_no_control_characters(tmp_path):
    proc = subprocess.run(
        _command(tmp_path), capture_output=True, text=True, env=_env(), check=True, timeout=120
    )
    assert proc.stderr == ""
    assert "freefloat plan:" in proc.stdout
    assert not CONTROL.search(proc.stdout + proc.stderr)


def test_verbose_logs_stage_timings_and_quiet_silences(tmp_path):
    proc = subprocess.run(
        _command(tmp_path, "-v"), capture_output=True, text=True, env=_env(), check=True
    )
    assert re.search(r"^freefloat: info: solve: \d+\.\d+ s$", proc.stderr, re.M)
    assert re.search(r"^freefloat: info: sample and verify: \d+\.\d+ s$", proc.stderr, re.M)
    assert not CONTROL.search(proc.stderr)
    quiet = [*_command(tmp_path)[:3], "plan", "-q", *_command(tmp_path)[4:]]
    proc = subprocess.run(quiet, capture_output=True, text=True, env=_env(), check=True)
    assert proc.stderr == "" and "freefloat plan:" in proc.stdout


def test_heartbeat_speaks_at_least_every_period_with_v(monkeypatch):
    """-v: a long loop's heartbeat prints once each period has passed (display only)."""
    import io

    from freefloat import progress

    clock = [100.0]
    monkeypatch.setattr(progress.time, "perf_counter", lambda: clock[0])
    log = io.StringIO()
    progress.configure(1, stream=log)
    try:
        for now in (100.0, 104.0, 105.5, 106.0, 110.6, 111.0):
            clock[0] = now
            progress.heartbeat(lambda now=now: f"at {now}")
        quiet = io.StringIO()
        progress.configure(0, stream=quiet)  # without -v: nothing
        clock[0] = 200.0
        progress.heartbeat(lambda: "never")
        clock[0] = 300.0
        progress.heartbeat(lambda: "never")
    finally:
        progress.configure(0)
    assert log.getvalue().splitlines() == ["freefloat: info: at 105.5", "freefloat: info: at 110.6"]
    assert quiet.getvalue() == ""
