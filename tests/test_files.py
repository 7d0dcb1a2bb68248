"""Atomic writes create files with the mode an ordinary open() gives: 0666 less the umask."""

from __future__ import annotations

import os
import stat

import pytest

from freefloat.files import atomic_write_text


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_plan_files_respect_the_umask(worked_plan, tmp_path, umask):
    previous = os.umask(umask)
    try:
        written = worked_plan.save(tmp_path / "plan.json")
        reference = tmp_path / "reference.txt"
        reference.write_text("x")  # what open() does under this umask
        text = atomic_write_text(tmp_path / "sub" / "t.txt", "y")
    finally:
        os.umask(previous)
    expected = stat.S_IMODE(reference.stat().st_mode)
    assert expected == 0o666 & ~umask
    assert stat.S_IMODE(written.stat().st_mode) == expected
    assert stat.S_IMODE(text.stat().st_mode) == expected
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json", "reference.txt", "sub"]
