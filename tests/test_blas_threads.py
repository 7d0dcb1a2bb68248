"""freefloat's calls run BLAS on one thread, and give the process its threads back after."""

from __future__ import annotations

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import freefloat as ff
import freefloat.pipeline as pipeline

from conftest import ROOT


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_plan_runs_blas_on_one_thread_and_restores_the_pools(monkeypatch):
    if not _blas_threads():
        pytest.skip("no BLAS pool found in this process")
    seen = []
    inner = pipeline._plan
    monkeypatch.setattr(
        pipeline, "_plan", lambda *args: seen.append(_blas_threads()) or inner(*args)
    )
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "worked_example.toml")
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        ff.plan(scenario)
        after = _blas_threads()
    assert seen and all(n == 1 for n in seen[0])
    assert after == before
