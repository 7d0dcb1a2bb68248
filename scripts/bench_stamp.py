"""The stamp of every benchmark table: when, on what machine and versions, under what load and
by which command it was made (``scripts/bench.py`` and ``scripts/bench_reachable.py``)."""

from __future__ import annotations

import datetime
import os
import platform
import shlex
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin

import freefloat as ff

__all__ = ["machine", "stamp", "stamped_markdown"]


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"Pinocchio {pin.__version__}, freefloat {ff.__version__}"
    )


def stamp() -> str:
    """When, where and how a table was made: date, machine, versions, load and command."""
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    command = "python " + " ".join(shlex.quote(a) for a in sys.argv)
    # With PYTHONDONTWRITEBYTECODE (or -B), no .pyc is written: a module without one (an
    # editable install's own) is compiled at each start-up, about 0.2 s more per command.
    bytecode = "off (no .pyc written)" if sys.flags.dont_write_bytecode else "on"
    return (
        f"*Measured {when} on {machine()}, numpy {np.__version__}; load average {load} "
        f"(1, 5, 15 min); bytecode writing {bytecode}; command: `{command}`*"
    )


def stamped_markdown(text: str) -> str:
    """The printed report as Markdown, each table preceded by its stamp (progress dropped)."""
    out: list[str] = []
    mark = stamp()
    in_table = False
    for line in text.splitlines():
        if line.startswith("  done:") or line.startswith("machine:"):
            continue
        table = line.startswith("|")
        if table and not in_table:
            if out and out[-1].strip():
                out.append("")
            out += [mark, ""]
        out.append(line)
        in_table = table
    return "\n".join(out).strip() + "\n"
