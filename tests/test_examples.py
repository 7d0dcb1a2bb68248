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


def test_the_readme_sweep_file_names_the_shipped_scenario_and_its_grid():
    """examples/yaw_sweep.toml (the README's sweep command): 81 yaws x 3 elbow angles."""
    from freefloat.sweep.spec import SweepSpec

    spec = SweepSpec.from_toml(ROOT / "examples" / "yaw_sweep.toml")
    assert spec.scenario_path == (ROOT / "robots" / "scenarios" / "worked_example_sweep.toml")
    jobs = spec.jobs()
    assert len(jobs) == 81 * 3
    yaws = sorted({float(v) for v in spec.axes[0].values})
    assert yaws[0] == -55.0 and yaws[-1] == 25.0 and yaws[1] - yaws[0] == 1.0
