from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

import freefloat as ff

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session", autouse=True)
def no_stray_meshcat_servers():
    """After the whole run, no meshcat server this run started may be left.

    Only this process's descendants count: other runs on a shared machine have their own.
    """
    yield
    out = subprocess.run(
        ["pgrep", "-f", "meshcat.servers.zmqserver"], capture_output=True, text=True, check=False
    )
    mine = [pid for pid in out.stdout.split() if _descends_from(int(pid), os.getpid())]
    assert mine == [], "meshcat servers left running"


def _descends_from(pid: int, ancestor: int) -> bool:
    """Whether process ``pid`` is a descendant of ``ancestor`` (Linux /proc)."""
    while pid > 1:
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            return False
        pid = int(stat.rsplit(")", 1)[1].split()[1])  # the parent's pid
        if pid == ancestor:
            return True
    return False


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


def as_older_format(doc: dict, fmt: str = "freefloat.plan/3") -> dict:
    """A plan document as a file of an older format holds the same plan (:mod:`legacy`), and
    without the objective record for /2."""
    from legacy import as_format_3

    old = as_format_3(doc)
    old["format"] = fmt
    if fmt == "freefloat.plan/2":
        old.pop("objective", None)
    return old


def coal_hull(vertices, triangles):
    """Coal's true convex hull (qhull, "Qt") of a triangle mesh's vertices (m)."""
    import coal

    model = coal.BVHModelOBBRSS()
    model.beginModel(len(triangles), len(vertices))
    model.addVertices(vertices)
    model.addTriangles(triangles)
    model.endModel()
    model.buildConvexHull(True, "Qt")
    return model.convex


def quintic_motion(start, goal, duration: float):
    """The rest-to-rest quintic from ``start`` to ``goal`` (rad or m) in ``duration`` (s), as
    verification's polynomial motion (its monomial coefficients written out here)."""
    from freefloat.verify.motion import PolynomialMotion

    d = goal - start
    return PolynomialMotion.from_monomials(
        [
            [s, 0, 0, 10 * x / duration**3, -15 * x / duration**4, 6 * x / duration**5]
            for s, x in zip(start, d, strict=True)
        ],
        duration,
    )
