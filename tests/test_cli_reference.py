"""docs/reference.md's command-line section names every command and option of the real parser."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from freefloat.cli import build_parser

REFERENCE = Path(__file__).resolve().parents[1] / "docs" / "reference.md"

#: Options every command takes (described once for all, not in each synopsis line).
COMMON = {"-h", "--help", "-v", "--verbose", "-q", "--quiet"}


def _section() -> str:
    text = REFERENCE.read_text()
    start = text.index("\n## Command line\n")
    return text[start : text.index("\n## ", start + 1)]


def _synopses(section: str) -> dict[str, str]:
    """Each command's synopsis (its ``freefloat NAME ...`` lines in the code block)."""
    block = section[section.index("```\n") + 4 : section.index("\n```", section.index("```\n"))]
    out: dict[str, str] = {}
    for chunk in re.split(r"\n(?=freefloat )", block):
        name = chunk.split()[1]
        out[name] = chunk
    return out


def _mentions(text: str, option: str) -> bool:
    return re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", text) is not None


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    (sub,) = (a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_command_and_option_of_the_parser_is_in_the_reference():
    section = _section()
    synopses = _synopses(section)
    commands = _commands()
    assert set(commands) <= set(synopses), "commands missing from the synopsis"
    assert set(synopses) - {"[-v"} == set(commands), "a synopsis of no command"
    prose = section.replace(section[section.index("```\n") : section.index("\n```\n") + 4], "")
    missing = []
    for name, parser in commands.items():
        if not re.search(rf"^- `{name}`", section, re.MULTILINE):
            missing.append(f"{name}: no bullet '- `{name}`' describing it")
        for action in parser._actions:
            options = action.option_strings
            if not options or set(options) <= COMMON:
                missing += [f"{o} (common)" for o in options if not _mentions(prose, o)]
                continue
            if not any(_mentions(synopses[name], o) for o in options):
                missing.append(f"{name} {'/'.join(options)}: not in its synopsis")
            for option in options:
                if option.startswith("--") and not _mentions(prose, option):
                    missing.append(f"{name} {option}: not described beyond the synopsis")
    assert not missing, "; ".join(missing)
    assert _mentions(section, "--version")
