"""Outputs of several files are moved into their folder at once, or not at all.

A full disk or a Ctrl-C while figures were written left some of them beside the old run's
others (or an empty folder), and the main job's plan without its page and plots. Truth: the
folders' listings and file contents before and after, read with the standard library.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from freefloat.cli import main
from freefloat.staged import staged_folder


def _listing(folder):
    return sorted(
        (str(p.relative_to(folder)), p.read_bytes() if p.is_file() else None)
        for p in folder.rglob("*")
    )


def test_a_failure_while_writing_leaves_the_folder_as_it_was(tmp_path):
    folder = tmp_path / "plots"
    folder.mkdir()
    (folder / "a.png").write_bytes(b"old a")
    (folder / "mine.txt").write_bytes(b"the user's")
    before = _listing(tmp_path)
    with pytest.raises(KeyboardInterrupt), staged_folder(folder) as stage:
        (stage / "a.png").write_bytes(b"new a")
        (stage / "b.png").write_bytes(b"new b")
        raise KeyboardInterrupt
    assert _listing(tmp_path) == before  # no new file, no hidden staging folder


def test_a_failure_makes_no_folder_and_a_success_moves_every_file(tmp_path):
    folder = tmp_path / "new" / "deeper" / "plots"
    with pytest.raises(OSError), staged_folder(folder) as stage:
        (stage / "a.png").write_bytes(b"a")
        raise OSError(28, "No space left on device")
    assert list(tmp_path.iterdir()) == []
    with staged_folder(folder) as stage:
        (stage / "sub").mkdir()
        (stage / "sub" / "b.png").write_bytes(b"b")
        (stage / "a.png").write_bytes(b"a")
    assert _listing(tmp_path / "new") == [
        ("deeper", None),
        ("deeper/plots", None),
        ("deeper/plots/a.png", b"a"),
        ("deeper/plots/sub", None),
        ("deeper/plots/sub/b.png", b"b"),
    ]


def test_the_main_job_interrupted_while_drawing_leaves_no_plan(tmp_path, monkeypatch, capsys):
    """Interrupted in its plots, the main job left freefloat-out/plan.json alone."""
    import matplotlib.figure

    drawn = []

    def interrupted(self, *args, **kwargs):
        drawn.append(args[0])
        if len(drawn) == 3:
            raise KeyboardInterrupt
        return original(self, *args, **kwargs)

    original = matplotlib.figure.Figure.savefig
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", interrupted)
    monkeypatch.chdir(tmp_path)
    assert main(["plan", "-q"]) == 130
    assert list(tmp_path.iterdir()) == []


def test_a_urdf_and_its_srdf_are_written_both_or_neither(tmp_path, monkeypatch):
    """compose on a full disk left the new SRDF beside the old URDF (or alone)."""
    import os

    import freefloat as ff
    from freefloat.staged import write_together

    urdf, srdf = tmp_path / "s.urdf", tmp_path / "s.srdf"
    urdf.write_text("old urdf")
    srdf.write_text("old srdf")
    real = os.fsync
    calls = []

    def full(fd):  # the second file's flush finds the disk full
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        return real(fd)

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(ff.FileError, match=r"cannot write .*s\.urdf: No space left on device"):
        write_together({srdf: "new srdf", urdf: "new urdf"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.srdf", "s.urdf"]
    assert (urdf.read_text(), srdf.read_text()) == ("old urdf", "old srdf")
    monkeypatch.setattr(os, "fsync", real)
    assert write_together({srdf: "new srdf", urdf: "new urdf"}) == urdf
    assert (urdf.read_text(), srdf.read_text()) == ("new urdf", "new srdf")


def test_an_existing_folder_is_staged_in_itself_a_new_one_beside(tmp_path, monkeypatch):
    """Staged beside an existing output folder, plots into a mount point failed ("Invalid
    cross-device link"), and into a writable folder of a read-only parent: a folder that
    exists is its own staging ground (same file system, writable)."""
    import tempfile

    homes = []
    real = tempfile.mkdtemp

    def recorded(*args, **kwargs):
        if kwargs["prefix"].startswith(".freefloat-stage-"):  # not the move's kept files
            homes.append(Path(kwargs["dir"]))
        return real(*args, **kwargs)

    monkeypatch.setattr(tempfile, "mkdtemp", recorded)
    folder = tmp_path / "plots"
    for _ in range(2):  # made, then existing
        with staged_folder(folder) as stage:
            (stage / "a.png").write_bytes(b"a")
    assert homes == [tmp_path, folder]
    assert sorted(p.name for p in folder.iterdir()) == ["a.png"]


def _failing_rename(monkeypatch, failing, watched=None):
    """os.replace failing (EIO) at its calls numbered in ``failing`` (from 1); the calls, each
    with whether the ``watched`` file existed just before it."""
    import os

    real, calls = os.replace, []

    def replace(source, destination):
        there = None if watched is None else watched.exists()
        calls.append((Path(source).name, Path(destination).name, there))
        if len(calls) in failing:
            raise OSError(5, "Input/output error")
        return real(source, destination)

    monkeypatch.setattr(os, "replace", replace)
    return calls


def test_a_rename_failing_halfway_puts_back_what_it_replaced(tmp_path, monkeypatch):
    """The third file's rename fails after two old files were replaced and a new folder
    made: every old file comes back, nothing new or hidden stays, and no file was ever
    missing (each is kept by a hard link while the new one takes its place)."""
    folder = tmp_path / "out"
    (folder / "plots").mkdir(parents=True)
    for name in ("a.json", "b.html", "plots/c.png", "mine.txt"):
        (folder / name).write_bytes(f"old {name}".encode())
    before = _listing(tmp_path)
    # renames: a.json in, b.html in, new/d.png in (fails), then b.html and a.json put back
    calls = _failing_rename(monkeypatch, {3}, folder / "b.html")
    with pytest.raises(OSError, match="Input/output error"), staged_folder(folder) as stage:
        for name in ("a.json", "b.html", "new/d.png", "plots/c.png"):
            (stage / name).parent.mkdir(exist_ok=True)
            (stage / name).write_bytes(b"new")
    assert [c[:2] for c in calls] == [
        ("a.json", "a.json"),
        ("b.html", "b.html"),
        ("d.png", "d.png"),
        ("b.html", "b.html"),
        ("a.json", "a.json"),
    ]
    assert all(there for _, _, there in calls)  # b.html was there at every rename
    assert _listing(tmp_path) == before


def test_a_file_that_cannot_be_put_back_is_named_with_its_old_content(tmp_path, monkeypatch):
    import freefloat as ff

    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "a.json").write_bytes(b"old a")
    (folder / "b.html").write_bytes(b"old b")
    _failing_rename(monkeypatch, {2, 3})  # b.html's rename in, then a.json's put back
    with pytest.raises(ff.FileError) as caught, staged_folder(folder) as stage:
        (stage / "a.json").write_bytes(b"new a")
        (stage / "b.html").write_bytes(b"new b")
    message = str(caught.value)
    assert "a.json could not be put back: its previous content is in" in message
    kept = Path(message.rsplit(" is in ", 1)[1])
    assert (kept / "a.json").read_bytes() == b"old a"  # said, not lost
    assert (folder / "a.json").read_bytes() == b"new a"
    assert (folder / "b.html").read_bytes() == b"old b"  # never replaced


def test_without_hard_links_the_files_are_kept_by_renames(tmp_path, monkeypatch):
    """A file system that makes no hard links (FAT, some network ones): kept by a rename."""
    import os

    def no_links(*args, **kwargs):
        raise OSError(1, "Operation not permitted")

    monkeypatch.setattr(os, "link", no_links)
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "a.json").write_bytes(b"old a")
    (folder / "b.html").write_bytes(b"old b")
    before = _listing(tmp_path)
    # a.json kept, a.json in, b.html kept, b.html in (fails), then both put back
    calls = _failing_rename(monkeypatch, {4})
    with pytest.raises(OSError), staged_folder(folder) as stage:
        (stage / "a.json").write_bytes(b"new a")
        (stage / "b.html").write_bytes(b"new b")
    assert len(calls) == 6 and _listing(tmp_path) == before
    monkeypatch.undo()
    with staged_folder(folder) as stage:
        (stage / "a.json").write_bytes(b"new a")
    assert sorted(p.name for p in folder.iterdir()) == ["a.json", "b.html"]
    assert (folder / "a.json").read_bytes() == b"new a"


@pytest.mark.parametrize("kind", ["folder", "fifo"])
def test_a_destination_that_is_no_regular_file_is_refused_before_any_move(tmp_path, kind):
    import os

    import freefloat as ff

    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "a.json").write_bytes(b"old a")
    if kind == "folder":
        (folder / "b.html").mkdir()
    else:
        os.mkfifo(folder / "b.html")
    before = _listing(tmp_path)
    said = "it is a folder" if kind == "folder" else "regular files only"
    with pytest.raises(ff.FileError, match=said), staged_folder(folder) as stage:
        (stage / "a.json").write_bytes(b"new a")
        (stage / "b.html").write_bytes(b"new b")
    assert _listing(tmp_path) == before


def test_files_written_together_are_put_back_when_a_rename_fails(tmp_path, monkeypatch):
    """compose's URDF renamed in, its SRDF's rename failing: the old URDF comes back."""
    import freefloat as ff
    from freefloat.staged import write_together

    urdf, srdf = tmp_path / "s.urdf", tmp_path / "s.srdf"
    urdf.write_text("old urdf")
    srdf.write_text("old srdf")
    _failing_rename(monkeypatch, {2})  # urdf in, srdf in (fails), urdf put back
    with pytest.raises(ff.FileError, match=r"cannot write .*: Input/output error"):
        write_together({urdf: "new urdf", srdf: "new srdf"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.srdf", "s.urdf"]
    assert (urdf.read_text(), srdf.read_text()) == ("old urdf", "old srdf")


def test_files_written_together_make_their_folders_and_remove_them_on_failure(tmp_path):
    import freefloat as ff
    from freefloat.staged import write_together

    urdf = tmp_path / "new" / "sub" / "s.urdf"
    (tmp_path / "afile").write_text("")
    with pytest.raises(ff.FileError):  # a third file under a file: no folder can be made
        write_together({urdf.with_suffix(".srdf"): "s", urdf: "u", tmp_path / "afile" / "x": ""})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]  # nothing else made
    assert write_together({urdf.with_suffix(".srdf"): "srdf", urdf: "urdf"}) == urdf
    assert (urdf.read_text(), urdf.with_suffix(".srdf").read_text()) == ("urdf", "srdf")


def test_a_stage_left_by_sigkill_is_removed_by_the_next_one(tmp_path):
    """SIGKILL cannot be caught: a process killed while its files were staged left a hidden
    ``.freefloat-stage-*`` folder for good. The next stage in that folder removes it; a stage
    in use (locked), another host's, or an older freefloat's is kept. Truth: a real child
    process killed with SIGKILL inside the stage, and the folder's listing."""
    import subprocess
    import sys

    code = (
        "import os, signal, sys\n"
        "from freefloat.staged import staged_folder\n"
        "with staged_folder(sys.argv[1]) as stage:\n"
        "    (stage / 'half.png').write_bytes(b'half')\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    folder = tmp_path / "plots"
    folder.mkdir()
    (folder / "old.png").write_bytes(b"old")
    child = subprocess.run([sys.executable, "-c", code, str(folder)], check=False)
    assert child.returncode == -9
    left = [p.name for p in folder.iterdir() if p.name.startswith(".freefloat-stage-")]
    assert len(left) == 1 and (folder / left[0] / "half.png").exists()
    host = left[0].removeprefix(".freefloat-stage-").split("-")[0]
    kept = [
        ".freefloat-stage-otherhost-1-abc",  # another host's
        ".freefloat-stage-x1y2z3",  # an older freefloat's: no maker in its name
    ]
    for name in kept:
        (folder / name).mkdir()
    with staged_folder(folder) as outer:  # in use (locked): the inner stage leaves it alone
        with staged_folder(folder) as stage:
            assert outer.exists() and outer.name.startswith(f".freefloat-stage-{host}-")
            (stage / "new.png").write_bytes(b"new")
        (outer / "outer.png").write_bytes(b"outer")
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["new.png", "old.png", "outer.png", *kept]
    )


def test_a_file_system_without_locks_stages_unlocked_and_cleans_nothing(tmp_path, monkeypatch):
    """Where flock fails (NFS without locks: ENOLCK), staging made a new folder forever."""
    import errno
    import fcntl

    def refuse(descriptor, operation):
        raise OSError(errno.ENOLCK, "No locks available")

    folder = tmp_path / "plots"
    folder.mkdir()
    (folder / ".freefloat-stage-somehost-1-abc").mkdir()  # whose, nothing can tell here
    monkeypatch.setattr(fcntl, "flock", refuse)
    with staged_folder(folder) as stage:
        (stage / "a.png").write_bytes(b"a")
    assert sorted(p.name for p in folder.iterdir()) == [".freefloat-stage-somehost-1-abc", "a.png"]


def test_a_stage_removed_before_it_is_locked_is_made_again(tmp_path, monkeypatch):
    """Another process's cleanup may remove a new stage between its making and its lock."""
    import shutil
    import tempfile

    real, calls = tempfile.mkdtemp, []

    def raced(*args, **kwargs):
        made = real(*args, **kwargs)
        calls.append(made)
        if len(calls) == 1:
            shutil.rmtree(made)  # the cleanup came first
        return made

    monkeypatch.setattr(tempfile, "mkdtemp", raced)
    folder = tmp_path / "new" / "plots"
    with staged_folder(folder) as stage:
        (stage / "a.png").write_bytes(b"a")
    assert len(calls) == 2 and [p.name for p in folder.iterdir()] == ["a.png"]
