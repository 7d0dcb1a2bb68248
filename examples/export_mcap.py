"""Plan the worked example and export it to MCAP for Foxglove (ROS 2 messages, no ROS needed).

Usage: python examples/export_mcap.py [OUT_DIR]   (default: ./freefloat-examples)
Writes OUT_DIR/worked_example.mcap (resampled at 50 Hz) and lists its topics read back.
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

from mcap.reader import make_reader

import freefloat as ff
from freefloat.export import export


def main(out: Path) -> None:
    """Plan, export to MCAP at 50 Hz and list the topics read back."""
    plan = ff.plan(ff.Scenario.from_toml(ff.default_scenario_path()))
    path = export(plan, out / "worked_example.mcap", "mcap", rate=50.0)  # Hz
    with open(path, "rb") as handle:
        counts = Counter(channel.topic for _, channel, _ in make_reader(handle).iter_messages())
    for topic, count in sorted(counts.items()):
        print(f"{topic}: {count} message(s)")
    print(f"wrote {path}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "freefloat-examples"))
