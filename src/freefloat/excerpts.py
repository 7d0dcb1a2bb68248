"""Short printable forms of bad input values, for one-line error messages."""

from __future__ import annotations

import datetime
from typing import Any

__all__ = [
    "EXCERPT_CHARS",
    "LABEL_CHARS",
    "PATH_CHARS",
    "apart",
    "excerpt",
    "path_excerpt",
    "shortened",
]

#: The most characters of a bad value an error message quotes (an excerpt beyond that).
EXCERPT_CHARS = 60
#: The most characters of a name a figure's legend or title shows (its middle cut beyond).
LABEL_CHARS = 40
#: The most characters of a path a message quotes (its middle cut beyond: both the folder it
#: starts in and the file it ends with tell the reader which it is).
PATH_CHARS = 120


def excerpt(value: Any, width: int = EXCERPT_CHARS) -> str:
    """A short printable form of ``value`` for an error message: at most about ``width`` chars.

    Long values are cut and say how long they were (``[1.0, 1.0, ...] (1000000 items)``,
    ``'aaaa...' (5000 characters)``, ``999999999999... (400 digits)``), so a message never
    echoes a megabyte of input. Lists and tables are not turned into text whole: only their
    first items are looked at.
    """
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int):
        try:
            text = str(value)
        except ValueError:  # more digits than Python turns into text
            return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
        if len(text) <= width:
            return text
        return f"{text[:12]}... ({len(text.lstrip('-'))} digits)"
    if isinstance(value, (list, tuple, dict)):
        opening, closing = ("{", "}") if isinstance(value, dict) else ("[", "]")
        if width < 10:
            return f"{opening}...{closing}" if value else f"{opening}{closing}"
        items = list(value.items())[:width] if isinstance(value, dict) else list(value[:width])
        parts: list[str] = []
        room = width - 16  # what the items may take, leaving room for the count
        for item in items:
            if isinstance(value, dict):
                part = f"{excerpt(str(item[0]), room // 2).strip(chr(39))} = "
                part += excerpt(item[1], max(room // 2, 0))
            else:
                part = excerpt(item, room // 2)
            if sum(len(p) + 2 for p in parts) + len(part) > room:
                break
            parts.append(part)
        if len(parts) == len(value):
            return opening + ", ".join(parts) + closing
        return f"{opening}{', '.join([*parts, '...'])}{closing} ({len(value)} items)"
    if isinstance(value, (datetime.date, datetime.time)):  # TOML's dates, as written
        kind = "date" if type(value) is datetime.date else "time"
        kind = "date and time" if isinstance(value, datetime.datetime) else kind
        return f"{value.isoformat()} (a {kind})"
    text = repr(value)
    if len(text) <= width:
        return text
    return f"{text[: max(width - 24, 8)]}... ({len(text)} characters)"


def apart(value: float, *bounds: float) -> str:
    """``value`` to 6 significant digits, or to as many more as tell it from ``bounds``.

    A value just outside a limit is never printed as the limit (``0.50000001``, not ``0.5``,
    beside a limit of 0.5); a value equal to a bound prints as the bound does.
    """
    value = float(value) + 0.0  # no negative zero
    for digits in range(6, 18):
        text = f"{value:.{digits}g}"
        if all(f"{bound:.{digits}g}" != text for bound in bounds if bound != value):
            return text
    return repr(value)


def shortened(text: str, width: int = LABEL_CHARS) -> str:
    """``text`` itself, or its start and end around ``...`` in about ``width`` characters.

    For names in figures (a joint named with 20,000 characters would squeeze a legend's axes
    to nothing); both ends are kept, since names of one robot often share their start.
    """
    if len(text) <= width:
        return text
    head = (width - 3) // 2
    return f"{text[:head]}...{text[len(text) - (width - 3 - head) :]}"


def path_excerpt(path: Any) -> str:
    """A path quoted for a message: whole up to :data:`PATH_CHARS`, else both its ends."""
    text = str(path)
    if len(text) <= PATH_CHARS:
        return repr(text)
    return f"{shortened(text, PATH_CHARS)!r} ({len(text)} characters)"
