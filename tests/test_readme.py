"""The README's scenario block and Python blocks run as a newcomer would paste them."""

from __future__ import annotations

import re

import numpy as np

import freefloat as ff

from conftest import ROOT

README = (ROOT / "README.md").read_text()


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.+?)\n```", README, flags=re.S)


def test_the_readme_scenario_block_plans_and_keeps_its_cone(tmp_path):
    (block,) = _blocks("toml")
    path = tmp_path / "my.toml"
    path.write_text(block)
    plan = ff.plan(ff.Scenario.from_toml(path))
    # The block's cone, checked on the plan's own samples with numpy: the tool's x axis in the
    # spacecraft frame stays within 60 deg of (0.34, 0.94, 0). The planar end effector's x axis
    # is the arm's heading: q1 + q2 about z.
    q = np.asarray(plan.samples.q)
    heading = q[:, 0] + q[:, 1]
    direction = np.array([0.34, 0.94]) / np.hypot(0.34, 0.94)
    cosine = np.cos(heading) * direction[0] + np.sin(heading) * direction[1]
    assert np.degrees(np.arccos(cosine.clip(-1, 1))).max() <= 60.0 + 1e-6
    assert plan.base.attitude_error_rad < 1e-9


def test_the_readme_python_blocks_run_in_order(tmp_path, monkeypatch):
    from freefloat.problem.constraints import CONSTRAINTS

    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    blocks = _blocks("python")
    assert len(blocks) == 2
    before = set(CONSTRAINTS)
    try:
        for block in blocks:
            exec(compile(block, "README.md", "exec"), namespace)  # the README's code, as pasted
    finally:  # the README registers its constraint: not for the tests that follow
        for name in set(CONSTRAINTS) - before:
            del CONSTRAINTS[name]
    held = namespace["held"]
    # The user's ceiling of 1.6 rad on joint 1, checked on the samples with numpy.
    assert np.asarray(held.samples.q)[:, 1].max() <= 1.6 + 1e-9
    assert (tmp_path / "plan.json").is_file()
