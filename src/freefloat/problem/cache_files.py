"""Files of the servicer cache (composed, locked or payload-holding URDFs and their SRDFs).

Each is written with a digest file beside it (``NAME.sha256``, the SHA-256 of its text): a
cache file is reused only while its digest file vouches for it. One edited by hand, cut short,
or written by an older freefloat without the digest is not trusted: the servicer is composed
again and the file rewritten (an edited spacecraft mass, read back from the cache, was planned
with silently).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ..files import atomic_write_text

__all__ = ["cached_text", "write_cached"]


def _digest_file(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def cached_text(path: Path) -> str | None:
    """The text of the cache file ``path`` if its digest file vouches for it, else None."""
    try:
        text = path.read_text(encoding="utf-8")
        digest = _digest_file(path).read_text(encoding="utf-8").strip()
    except (OSError, UnicodeError):
        return None
    return text if _digest(text) == digest else None


def write_cached(path: Path, text: str) -> Path:
    """Write ``text`` to the cache file ``path`` with its digest (unless already there)."""
    if cached_text(path) != text:
        atomic_write_text(path, text)
        atomic_write_text(_digest_file(path), _digest(text) + "\n")
    return path
