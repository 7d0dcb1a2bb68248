"""What a user's single call costs: each case in a fresh Python process, paired rounds.

A user's ``freefloat plan`` or first ``ff.plan`` starts a process, imports, reads the scenario
and plans once: the modules a call imports on first use and the caches it fills are part of its
cost. Per round, each source tree given (this one, and optionally a baseline checkout) runs
every case in its own new process, interleaved, so both trees see the same machine load:

- ``ff.plan`` on each shipped scenario, timed inside the process (after ``import freefloat``):
  the whole call, and its solve, sample and verify stages from the plan's record;
- the README's main command (``freefloat plan``: the worked example, its playback page and
  plots), timed from outside as a whole process in an empty folder;
- ``freefloat reach SCENARIO -q`` on each shipped servicer (issue 28: at most 2 s), timed
  from outside as a whole process (on the usable cores, as a user runs it).

Medians over the rounds; the ratio of the whole call to its solve is the figure issue 25's
third target names ("the whole verified plan costs at most 2x its solve").
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = ("worked_example", "panda_servicer", "ur5_servicer", "dual_ur5_servicer")
#: Servicers whose ``freefloat reach`` is timed.
REACHED = ("panda_servicer", "ur5_servicer", "dual_ur5_servicer")

_PLAN = """
import json, sys, time
t0 = time.perf_counter()
import freefloat as ff
imported = time.perf_counter() - t0
scenario = ff.Scenario.from_toml(sys.argv[1])
t = time.perf_counter()
plan = ff.plan(scenario)
whole = time.perf_counter() - t
r = plan.solver
print(json.dumps({"import_s": imported, "whole_s": whole, "solve_s": r.solve_time_s,
                  "sample_s": r.sample_time_s, "verify_s": r.verify_time_s}))
"""


def _env(source: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(source), "OPENBLAS_NUM_THREADS": "1"}


def _plan_once(source: Path, name: str) -> dict[str, float]:
    path = REPO / "robots" / "scenarios" / f"{name}.toml"
    done = subprocess.run(
        [sys.executable, "-c", _PLAN, str(path)],
        env=_env(source),
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def _command_once(source: Path, arguments: list[str]) -> float:
    """Wall time (s) of ``freefloat ARGUMENTS`` as a whole process, in an empty folder."""
    code = f"import sys\nfrom freefloat.cli import main\nsys.exit(main({arguments!r}))"
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        command = [sys.executable, "-c", code]
        subprocess.run(command, env=_env(source), cwd=folder, capture_output=True, check=True)
        return time.perf_counter() - start


def _commands() -> dict[str, list[str]]:
    """The whole-process cases: the README's main command, then reach on each servicer."""
    reach = {
        f"reach {name}": ["reach", str(REPO / "robots" / "scenarios" / f"{name}.toml"), "-q"]
        for name in REACHED
    }
    return {"main command": ["plan", "-q"], **reach}


def bench_fresh(rounds: int, sources: dict[str, Path]) -> dict[str, dict[str, dict[str, float]]]:
    """Medians per source label and case: the plan stages (s) and the commands (s)."""
    samples: dict[str, dict[str, list[dict[str, float]]]] = {s: {} for s in sources}
    for round_ in range(rounds):
        for label, source in sources.items():
            for name in SCENARIOS:
                samples[label].setdefault(name, []).append(_plan_once(source, name))
            for case, arguments in _commands().items():
                samples[label].setdefault(case, []).append(
                    {"whole_s": _command_once(source, arguments)}
                )
        print(f"  done: fresh-process round {round_ + 1} of {rounds}", flush=True)
    return {
        label: {
            case: {key: statistics.median(r[key] for r in runs) for key in runs[0]}
            for case, runs in cases.items()
        }
        for label, cases in samples.items()
    }


def print_fresh(found: dict[str, dict[str, dict[str, float]]], rounds: int) -> None:
    """The table, one column group per source, as Markdown."""
    labels = list(found)
    print(f"\n### A user's single call: fresh processes, {rounds} paired rounds (medians)\n")
    group = "whole ms | solve ms | sample ms | verify ms | whole / solve"
    head = " | ".join(f"{label}: {group}" for label in labels)
    print(f"| case | {head} |")
    print("|---|" + "---:|" * (5 * len(labels)))
    for case in (*SCENARIOS, *_commands()):
        cells = []
        for label in labels:
            r = found[label][case]
            if "solve_s" in r:
                cells.append(
                    f"{1e3 * r['whole_s']:.0f} | {1e3 * r['solve_s']:.0f} | "
                    f"{1e3 * r['sample_s']:.0f} | {1e3 * r['verify_s']:.0f} | "
                    f"{r['whole_s'] / r['solve_s']:.2f}x"
                )
            else:
                cells.append(f"{1e3 * r['whole_s']:.0f} (whole process) | | | | ")
        print(f"| {case} | " + " | ".join(cells) + " |")
    if len(labels) == 2:
        a, b = labels
        ratios = ", ".join(
            f"{case} {found[b][case]['whole_s'] / found[a][case]['whole_s']:.2f}x"
            for case in (*SCENARIOS, *_commands())
        )
        print(f"\n{b} / {a}, whole: {ratios}")


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--baseline-src", type=Path, help="a baseline checkout's src folder")
    args = parser.parse_args()
    trees = {"this tree": REPO / "src"}
    if args.baseline_src:
        trees = {"baseline": args.baseline_src, **trees}
    print_fresh(bench_fresh(args.rounds, trees), args.rounds)
