"""Ctrl-C and SIGTERM: one line, exit 130 or 143, no partial file, the previous output intact.

Deterministic: the writer pauses (``FREEFLOAT_TEST_WRITE_PAUSE``) after its temporary file is
complete, the test waits until that file exists and only then sends the signal; start-up is
interrupted from an import hook while the package is being imported.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT

SRC = ROOT / "src"


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC), env.get("PYTHONPATH", "")])
    env.update(extra)
    return env


def _python(code: str, folder: Path) -> subprocess.CompletedProcess[str]:
    """``python -c code`` in ``folder`` with this checkout's package, its output captured."""
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=_env(),
        cwd=folder,
        check=False,
        timeout=60,
    )


def _wait_for(predicate, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


@pytest.mark.parametrize(
    ("signum", "code", "line"),
    [
        (signal.SIGTERM, 143, "freefloat: terminated"),
        (signal.SIGINT, 130, "freefloat: interrupted"),
        (signal.SIGHUP, 129, "freefloat: hung up"),
    ],
)
def test_a_signal_while_writing_leaves_the_previous_plan(tmp_path, signum, code, line):
    target = tmp_path / "x.json"
    target.write_text("previous plan")
    proc = subprocess.Popen(
        [sys.executable, "-m", "freefloat.cli", "plan", "-o", str(target)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(FREEFLOAT_TEST_WRITE_PAUSE="30"),
    )
    try:
        _wait_for(lambda: any(p.name.startswith(".x.json.") for p in tmp_path.iterdir()))
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == code
    assert err == f"{line}\n"
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]  # no hidden temporary file
    assert target.read_text() == "previous plan"


def test_ctrl_c_during_start_up_is_one_line(tmp_path):
    """SIGINT while the package is imported by the command (here: when Pinocchio is)."""
    code = f"""
import os, signal, sys
class Interrupt:
    def find_spec(self, name, path=None, target=None):
        if name == "pinocchio":
            os.kill(os.getpid(), signal.SIGINT)
        return None
sys.meta_path.insert(0, Interrupt())
sys.argv = [{str(Path(sys.executable).parent / "freefloat")!r}, "plan"]
from freefloat.cli import main
sys.exit(main())
"""
    result = _python(code, tmp_path)
    assert result.returncode == 130
    assert result.stderr == "freefloat: interrupted\n"
    assert list(tmp_path.iterdir()) == []


def test_a_library_import_installs_no_handler():
    code = (
        "import signal, freefloat; "
        "print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=_env(), check=True
    )
    assert result.stdout.strip() == "True"


def test_main_restores_the_handlers(capsys):
    from freefloat.cli import main

    before = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    assert main(["plan", "--samples", "1"]) == 2
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before
    capsys.readouterr()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_after_the_command_ended_is_no_traceback(tmp_path, signum):
    """The race the hostile campaign once met: the signal lands after the command's work,
    while the process exits (its handlers then were the start-up guard's, which raised in
    the atexit callbacks: a traceback). The command's code and output stand, nothing more."""
    code = f"""
import os, sys
sys.argv = [{str(Path(sys.executable).parent / "freefloat")!r}, "--version"]
from freefloat.cli import main
code = main()
os.kill(os.getpid(), {int(signum)})  # delivered at once, in the main thread
print("still here", flush=True)
sys.exit(code)
"""
    result = _python(code, tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "still here" and result.stderr == ""
