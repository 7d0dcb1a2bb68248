"""Plug-ins shipped in another package: entry points, across processes.

A tiny distribution is written into a temporary folder (a package module plus its
``<name>.dist-info`` with ``METADATA`` and ``entry_points.txt``, as pip would install it) and
put on ``PYTHONPATH``; ``freefloat plan`` and then ``freefloat verify`` run as separate
processes, so the second knows the plug-ins only through their entry points.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.errors import PluginError
from freefloat.plugins import Registry, plugin_class
from freefloat.problem.constraints import Constraint, JointPositionLimits

ROOT = Path(__file__).resolve().parents[1]

#: The user's package: a constraint (joint ``joint`` below ``ceiling_deg``) and an objective.
PLUGIN_MODULE = '''
import math

import numpy as np

from freefloat.problem.constraints import Constraint, ConstraintRows, Excess
from freefloat.problem.constraints.base import DEFAULT_INSTANTS
from freefloat.problem.objectives import Objective, ObjectiveValue


class Ceiling(Constraint):
    """Joint ``joint`` stays below ``ceiling`` (rad)."""

    name, unit, affine = "ceiling", "rad", True

    def __init__(self, joint, ceiling):
        self.joint, self.ceiling = joint, ceiling

    def to_record(self):
        return {"joint": self.joint, "ceiling_deg": math.degrees(self.ceiling)}

    @classmethod
    def from_record(cls, record):
        return cls(str(record["joint"]), math.radians(float(record["ceiling_deg"])))

    def rows(self, problem, beta, instants=DEFAULT_INSTANTS):
        i = problem.robot.joint_names.index(self.joint)
        base, dq, _ = problem.family.linear_map(np.asarray(instants, dtype=float))
        return ConstraintRows(base.q[:, i] + dq[:, i, :] @ beta - self.ceiling, dq[:, i, :])

    def excess(self, robot, path):
        (_, _), (hi, t_hi) = path.extremes(robot.joint_names.index(self.joint), 0)
        return Excess(hi - self.ceiling, 0.0, f"at t = {t_hi:.4g} s")


class WeightedNorm(Objective):
    """``weight * |beta|^2`` (rad^2)."""

    name, unit, duration_power, exact = "weighted_norm", "rad^2", 0.0, True
    description = "weighted norm of the free coefficients"

    def __init__(self, weight=2.0):
        self.weight = weight

    def evaluate(self, problem, beta):
        beta = np.asarray(beta, dtype=float)
        return ObjectiveValue(self.weight * float(beta @ beta), 2.0 * self.weight * beta)

    def to_record(self):
        return {"weight": self.weight}

    @classmethod
    def from_record(cls, record):
        return cls(float(record.get("weight", 2.0)))
'''


def _distribution(folder: Path, name: str, entry_points: str, module: str = "") -> Path:
    """Install (by hand, as pip would) a distribution ``name`` into ``folder``; return it."""
    package = folder / name.replace("-", "_")
    if module:
        package.mkdir(parents=True)
        (package / "__init__.py").write_text("")
        (package / "plugin.py").write_text(module)
    info = folder / f"{name.replace('-', '_')}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(textwrap.dedent(entry_points))
    return folder


def _freefloat(folder: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``python -m freefloat.cli ...`` in a new process that sees ``folder``'s packages."""
    path = os.pathsep.join([str(folder), str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    env = {**os.environ, "PYTHONPATH": path}
    return subprocess.run(
        [sys.executable, "-m", "freefloat.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
        check=False,
    )


def test_installed_plugins_plan_and_verify_in_new_processes(tmp_path):
    site = _distribution(
        tmp_path / "site",
        "ff-ceiling-demo",
        """
        [freefloat.constraints]
        ceiling = ff_ceiling_demo.plugin:Ceiling

        [freefloat.objectives]
        weighted_norm = ff_ceiling_demo.plugin:WeightedNorm
        """,
        PLUGIN_MODULE,
    )
    scenario = tmp_path / "scenario.toml"
    table = '\n[constraints.ceiling]\njoint = "q2"\nceiling_deg = 120.0\n'
    scenario.write_text(ff.default_scenario_path().read_text() + table)
    out = tmp_path / "plan.json"
    done = _freefloat(site, "plan", str(scenario), "-o", str(out), "--objective", "weighted_norm")
    assert done.returncode == 0, done.stderr
    data = json.loads(out.read_text())
    records = {c["name"]: c["parameters"] for c in data["constraints"]}
    assert records["ceiling"] == {"joint": "q2", "ceiling_deg": pytest.approx(120.0)}
    assert data["objective"]["name"] == "weighted_norm"
    # the check's figure against the plan's own joint path, sampled densely (not its code)
    plan = ff.Plan.load(out)
    q2 = plan.joint_positions(np.linspace(0.0, plan.duration, 20001))[:, 1]
    checks = {c["name"]: c for c in data["verification"]["checks"]}
    assert checks["ceiling"]["value"] == pytest.approx(q2.max() - math.radians(120), abs=1e-7)

    done = _freefloat(site, "verify", str(out))
    assert done.returncode == 0, done.stderr
    assert "ceiling" in done.stdout

    # verify rebuilds the constraint from its record: a lower ceiling is refused
    for item in data["constraints"]:
        if item["name"] == "ceiling":
            item["parameters"]["ceiling_deg"] = 100.0
    out.write_text(json.dumps(data))
    done = _freefloat(site, "verify", str(out))
    assert done.returncode == 2
    assert "disagrees" in done.stderr and f"by {math.radians(20):.3g} rad" in done.stderr

    # without the package, the plan names a plug-in this process does not know
    done = _freefloat(tmp_path / "elsewhere", "verify", str(out))
    assert done.returncode == 2 and "'ceiling'" in done.stderr


def test_a_broken_entry_point_is_one_line_naming_package_and_entry_point(tmp_path):
    site = _distribution(
        tmp_path, "ff-broken-demo", "[freefloat.constraints]\nnope = ff_missing.module:Nope\n"
    )
    done = _freefloat(site, "plan", str(ff.default_scenario_path()), "-o", str(tmp_path / "p"))
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "freefloat: error: plug-in 'nope' of package 'ff-broken-demo' (entry point group "
        "'freefloat.constraints'): cannot load 'ff_missing.module:Nope': "
        "ModuleNotFoundError: No module named 'ff_missing'"
    )
    assert not (tmp_path / "p").exists()


def _registry(tmp_path, monkeypatch, entry_points: str, module: str) -> Registry[type]:
    """A fresh constraint registry that sees one distribution written into ``tmp_path``."""
    _distribution(tmp_path, "ff-demo", entry_points, module)
    monkeypatch.syspath_prepend(str(tmp_path))
    builtins = {JointPositionLimits.name: JointPositionLimits}
    return Registry("constraint", builtins, plugin_class(Constraint, "constraint"))


def test_a_name_clash_with_a_builtin_is_refused(tmp_path, monkeypatch):
    entry = "[freefloat.constraints]\njoint_position_limits = ff_demo.plugin:Ceiling\n"
    registry = _registry(tmp_path, monkeypatch, entry, PLUGIN_MODULE)
    with pytest.raises(PluginError) as caught:
        list(registry)
    message = str(caught.value)
    assert "plug-in 'joint_position_limits' of package 'ff-demo'" in message
    assert "already taken by freefloat.problem.constraints.joint_position." in message
    assert message.endswith("choose another name") and "\n" not in message


@pytest.mark.parametrize(
    ("target", "reason"),
    [
        ("ff_demo.plugin:WeightedNorm", "is not a constraint (a subclass of Constraint)"),
        ("ff_demo.plugin:Ceiling", "is named 'ceiling'; the entry point must carry the same name"),
        ("ff_demo.plugin:Missing", "AttributeError"),
    ],
)
def test_an_entry_point_that_is_not_a_plugin_of_its_kind_is_refused(
    tmp_path, monkeypatch, target, reason
):
    entry = f"[freefloat.constraints]\nroof = {target}\n"
    registry = _registry(tmp_path, monkeypatch, entry, PLUGIN_MODULE)
    with pytest.raises(PluginError, match="plug-in 'roof' of package 'ff-demo'") as caught:
        _ = "roof" in registry
    assert reason in str(caught.value)
