"""A file's stamp for the in-process caches: changes whenever the file's content may have.

The caches of parsed geometry and checked pairs (:mod:`.geometry`) are kept per mesh and SRDF
file. A stamp of path, modification time and size alone misses a rewrite of the same size
within the file system's timestamp tick (a few ms), or one whose modification time was set
back (``cp -p``, ``touch -d``, an archive's extraction). So a stamp holds more:

- the change time (``st_ctime_ns``), which every write and every ``utime`` sets to the
  current time and nothing sets back, and the inode (a file replaced by a rename);
- while the file is *fresh*, changed less than :data:`FRESH_S` before the stamp was taken, a
  digest of its content: a second write within the same tick leaves every time as it was,
  and only the content tells (the rule git applies to its own index). On Windows, where the
  change time is the creation time, every stamp holds a digest.

Two stamps of one file are then equal only if its content is: either a digest says so, or
the file had been still for :data:`FRESH_S` when the first stamp was taken, so any write
since moved its change time on. A stamp compared with an earlier one that holds a digest
holds one too (``like``), so a file that was fresh when first stamped still matches later.
"""

from __future__ import annotations

import hashlib
import os
import stat
import time

__all__ = ["FRESH_S", "FileStamp", "file_stamp"]

#: A file changed less than this before its stamp (s) is stamped with a digest of its content
#: (above the coarsest timestamp tick in use, FAT's 2 s).
FRESH_S = 3.0

#: (path, modification time ns, change time ns, inode, size in bytes, digest or "").
FileStamp = tuple[str, int, int, int, int, str]


def file_stamp(path: str, like: FileStamp | None = None, digest: bool = False) -> FileStamp:
    """The stamp of the file at ``path`` (see the module doc); -1s when it cannot be read.

    With a digest of its content when the file is fresh, when ``like`` (an earlier stamp to
    compare with) holds one, on Windows, or when ``digest`` asks for one (a small file).
    """
    try:
        info = os.stat(path)
    except OSError:
        return (path, -1, -1, -1, -1, "")
    if not stat.S_ISREG(info.st_mode):  # a FIFO would block the digest's read for ever
        return (path, -1, -1, -1, -1, "")
    newest = max(info.st_mtime_ns, info.st_ctime_ns) / 1e9
    wanted = digest or os.name == "nt" or bool(like and like[-1])
    content = _digest(path) if wanted or time.time() - newest < FRESH_S else ""
    return (path, info.st_mtime_ns, info.st_ctime_ns, info.st_ino, info.st_size, content)


def _digest(path: str) -> str:
    """BLAKE2b digest of the file's bytes (hex); "unreadable" when it cannot be read."""
    hasher = hashlib.blake2b(digest_size=16)
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                hasher.update(block)
    except OSError:
        return "unreadable"
    return hasher.hexdigest()
