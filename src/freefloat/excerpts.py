"""Short printable forms of bad input values, for one-line error messages."""

from __future__ import annotations

from typing import Any

__all__ = ["EXCERPT_CHARS", "excerpt"]

#: The most characters of a bad value an error message quotes (an excerpt beyond that).
EXCERPT_CHARS = 60


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
    text = repr(value)
    if len(text) <= width:
        return text
    return f"{text[: max(width - 24, 8)]}... ({len(text)} characters)"
