from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

import freefloat as ff

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session", autouse=True)
def no_stray_meshcat_servers():
    """After the whole run, no meshcat server subprocess may be left."""
    yield
    out = subprocess.run(
        ["pgrep", "-f", "meshcat.servers.zmqserver"], capture_output=True, text=True, check=False
    )
    assert out.stdout.split() == [], "meshcat servers left running"


@pytest.fixture(scope="session")
def planar_robot() -> ff.Robot:
    return ff.load_robot(ROOT / "robots" / "planar_2dof.urdf")


@pytest.fixture(scope="session")
def worked_scenario() -> ff.Scenario:
    return ff.Scenario.from_toml(ff.default_scenario_path())


@pytest.fixture(scope="session")
def worked_plan(worked_scenario: ff.Scenario) -> ff.Plan:
    return ff.plan(worked_scenario)


def worked_problem(scenario: ff.Scenario, extra: dict[str, int]) -> ff.Problem:
    """The worked example's problem (T = 10 s) with the given free coefficients."""
    return ff.build_problem(
        scenario.robot,
        scenario.start,
        scenario.goal,
        scenario.start_attitude,
        scenario.goal_attitude,
        10.0,
        extra=extra,
    )


def deg(x: float) -> float:
    return math.radians(x)
