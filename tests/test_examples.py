"""Every script in examples/ runs as a user would run it, writing into a temporary folder."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import freefloat as ff

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples").glob("*.py"))

#: What each example must write (relative to its output folder).
WRITES = {
    "plan_worked_example.py": ["worked_example.plan.json"],
    "servicer_three_axis.py": ["ur5_servicer.urdf", "ur5_three_axis.plan.json"],
    "cartesian_goal.py": ["cartesian.toml", "cartesian.plan.json"],
    "export_mcap.py": ["worked_example.mcap"],
}


def test_every_example_is_listed():
    assert sorted(p.name for p in EXAMPLES) == sorted(WRITES)


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(script, tmp_path):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(ff.__file__).resolve().parents[1])
    env["FREEFLOAT_CACHE"] = str(tmp_path / "cache")
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, str(script), str(out)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert "wrote " in proc.stdout
    for name in WRITES[script.name]:
        assert (out / name).exists(), name
    for name in WRITES[script.name]:
        if name.endswith(".plan.json"):
            # the file alone, every number recomputed and every check run again
            assert ff.verify_plan(ff.Plan.load(out / name)).passed
