"""Hostile-input campaign (issue 26): the command line against inputs an attacker or a careless
user would try, each judged from outside the code under test.

Classes:

- ``urdf-xml``: a shipped URDF with XML tricks (document types, entities, character
  references, CDATA, comments, namespaces, processing instructions, repeated elements, numbers
  urdfdom reads otherwise than Python). Oracle: Pinocchio given the raw file on its own. An
  accepted plan whose robot differs from that (mass or joints) is a wrong accept.
- ``inertia``: random trees with links fixed to moving bodies, masses sometimes zero,
  inertias sometimes indefinite. Oracle: the merged bodies computed here by the
  parallel-axis theorem; accepting an unphysical body is a wrong accept.
- ``device``: every writing command onto a FIFO, a socket, a device, a link to one.
- ``signal``: SIGINT, SIGTERM, SIGHUP sent the moment the temporary output appears, and at
  random instants of a loop of writes; any file left behind counts.
- ``stream``: standard output full (``/dev/full``) or closed at a random byte.
- ``plan``: edited plan files (relabelled to an older format under a cut effort limit, a
  relative path from another folder, a cleared URDF, a tampered URDF copy, duplicate keys,
  empty names) and the issue's message cases (a goal beyond its limit that also collides,
  byte-order marks, broken meshes, ``package://`` escapes, an inertia of 1e308, an arm that
  is no URDF, an empty scheduler address, a goal pitch of 90 deg).

Every run is a subprocess of ``python -m freefloat.cli``. A refusal must be exit code 2 (1 for
a plan that ``verify`` finds failing) and exactly one line ``freefloat: error: ...`` on
stderr; a traceback, ``Exception ignored`` or a second line is counted as a traceback.

Run: python scripts/hostile_campaign.py [--seed N] [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[1]
PLANAR = ROOT / "robots" / "planar_2dof.urdf"
SRC = ROOT / "src"

sys.path.insert(0, str(ROOT / "tests"))
import freefloat as ff  # noqa: E402
from freefloat.robot.parser_messages import parser_messages  # noqa: E402
from test_fuzz_outputs import WRITER  # noqa: E402
from test_fuzz_urdf import TRICKS, _merged, _physical, _random_tree  # noqa: E402


@dataclass
class Tally:
    """Outcomes of one class of inputs."""

    cases: int = 0
    outcomes: Counter[str] = field(default_factory=Counter)
    notes: list[str] = field(default_factory=list)

    def add(self, outcome: str, note: str = "") -> None:
        self.cases += 1
        self.outcomes[outcome] += 1
        if outcome in ("wrong accept", "traceback", "false refusal", "leftover") and note:
            self.notes.append(f"{outcome}: {note[:200]}")


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC), env.get("PYTHONPATH", "")])
    env["FREEFLOAT_CACHE"] = env.get("FREEFLOAT_CACHE_CAMPAIGN", str(CACHE))
    return env


CACHE = Path(tempfile.mkdtemp(prefix="ff-campaign-cache-"))


def run(argv: list[str], cwd: Path, **kwargs) -> subprocess.CompletedProcess:  # type: ignore[no-untyped-def]
    kwargs.setdefault("stdout", subprocess.PIPE)
    kwargs.setdefault("stderr", subprocess.PIPE)
    return subprocess.run(
        [sys.executable, "-m", "freefloat.cli", *map(str, argv)],
        cwd=cwd,
        env=_env(),
        text=True,
        timeout=600,
        check=False,
        **kwargs,
    )


def judged(result: subprocess.CompletedProcess, refuse: bool, codes=(2,)) -> tuple[str, str]:  # type: ignore[no-untyped-def]
    """The outcome of a run that should refuse (or accept), and the stderr as the note."""
    err = result.stderr or ""
    noisy = "Traceback" in err or "Exception ignored" in err or "ignored due to race" in err
    lines = [line for line in err.splitlines() if not line.startswith("freefloat: warning:")]
    failed_check = result.returncode == 1 and 1 in codes and not lines  # verify: FAILED rows
    if noisy or (result.returncode != 0 and len(lines) != 1 and not failed_check):
        return "traceback", err
    if refuse:
        return ("clean refusal", err) if result.returncode in codes else ("wrong accept", err)
    return ("correct accept", err) if result.returncode == 0 else ("false refusal", err)


def scenario_for(urdf: Path, folder: Path, name: str = "s.toml") -> Path:
    text = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    text = re.sub(r"^robot = .*$", f'robot = "{urdf}"', text, count=1, flags=re.M)
    path = folder / name
    path.write_text(text)
    return path


def _plan_robot_matches_raw(plan_path: Path, text: str) -> bool:
    """Whether the planned robot is what Pinocchio builds from the raw text (mass, joints)."""
    plan = json.loads(plan_path.read_text())
    robot = ff.load_robot(plan["robot"]["urdf"], text=plan["robot"]["urdf_text"])
    try:
        with parser_messages():
            raw = pin.buildModelFromXML(text.removeprefix("\ufeff"), pin.JointModelFreeFlyer())
    except (RuntimeError, ValueError):
        return False
    masses = [i.mass for i in raw.inertias], [i.mass for i in robot.model.inertias]
    return list(raw.names) == list(robot.model.names) and np.allclose(*masses, rtol=1e-12)


def campaign_urdf_xml(tally: Tally, work: Path, rng: random.Random, cases: int) -> None:
    for case in range(cases):
        text = PLANAR.read_text()
        for old, new in rng.sample(TRICKS, rng.randint(1, 3)):
            text = text.replace(old, new, 1)
        folder = work / f"xml{case}"
        folder.mkdir()
        urdf = folder / "r.urdf"
        urdf.write_text(text, encoding="utf-8")
        out = folder / "p.json"
        result = run(["plan", scenario_for(urdf, folder), "-o", out, "-q"], folder)
        outcome, note = judged(result, refuse=False)
        if result.returncode == 0:
            same = _plan_robot_matches_raw(out, text)
            outcome = "correct accept" if same else "wrong accept"
        elif outcome == "false refusal":
            outcome = "clean refusal"  # a trick may well be refused: the line is what counts
        tally.add(outcome, note or text[:200])


def campaign_inertia(tally: Tally, work: Path, seed: int, cases: int) -> None:
    rng = np.random.default_rng(seed)
    for case in range(cases):
        text, bodies = _random_tree(rng)
        urdf = work / f"tree{case}.urdf"
        urdf.write_text(text)
        physical = all(_physical(members) for members in bodies)
        try:
            robot = ff.load_robot(urdf)
        except ff.FreeFloatError as exc:
            line_ok = "\n" not in str(exc)
            tally.add(
                "clean refusal"
                if line_ok and not physical
                else "traceback"
                if not line_ok
                else "false refusal",
                str(exc),
            )
            continue
        bodies_ok = all(
            math.isclose(robot.model.inertias[i].mass, _merged(m)[0], rel_tol=1e-12)
            for i, m in enumerate(bodies, start=1)
        )
        tally.add("correct accept" if physical and bodies_ok else "wrong accept", text)
    # the case, through the command line: a 0 kg link with izz = -100 fixed to link2
    bad = (
        '<link name="bad"><inertial><mass value="0"/><inertia ixx="0" iyy="0" izz="-100" '
        'ixy="0" ixz="0" iyz="0"/></inertial></link><joint name="fix" type="fixed">'
        '<parent link="link2"/><child link="bad"/></joint></robot>'
    )
    urdf = work / "negative.urdf"
    urdf.write_text(PLANAR.read_text().replace("</robot>", bad))
    tally.add(*judged(run(["plan", scenario_for(urdf, work), "-o", work / "n.json"], work), True))


def _non_regular(work: Path) -> tuple[socket.socket, list[Path]]:
    fifo = work / "fifo"
    os.mkfifo(fifo)
    sock = work / "sock"
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(sock))
    (work / "to_fifo").symlink_to(fifo)
    (work / "to_null").symlink_to("/dev/null")
    return server, [fifo, sock, work / "to_fifo", work / "to_null", Path("/dev/null")]


def campaign_device(tally: Tally, work: Path, plan_file: Path) -> None:
    server, targets = _non_regular(work)
    commands = [
        lambda t: ["export", plan_file, "--format", "csv", "-o", t],
        lambda t: ["export", plan_file, "--format", "mcap", "-o", t],
        lambda t: ["show", plan_file, "--html", t, "--no-verify"],
        lambda t: ["plan", "--samples", "5", "-o", t],
        lambda t: [
            "compose",
            "--arm",
            "z1",
            "--base-mass",
            "50",
            "--base-size",
            "1",
            "1",
            "1",
            "--mount",
            "0.5",
            "0",
            "0",
            "-o",
            t,
        ],
    ]
    try:
        for target in targets:
            for command in commands:
                outcome, note = judged(run(command(target), work), refuse=True)
                intact = (work / "fifo").is_fifo() and Path("/dev/null").is_char_device()
                tally.add(outcome if intact else "wrong accept", note)
    finally:
        server.close()
    _leftovers(tally, work)


def _leftovers(tally: Tally, folder: Path) -> None:
    left = [p.name for p in folder.rglob(".*") if p.is_file()]
    if left:
        tally.add("leftover", ", ".join(left))


def campaign_signal(tally: Tally, work: Path, rng: random.Random, tries: int) -> None:
    """The issue's race: the signal the moment the temporary plan file appears."""
    kinds = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
    for attempt in range(tries):
        folder = work / f"sig{attempt}"
        folder.mkdir()
        (folder / "x.json").write_text("previous")
        proc = subprocess.Popen(
            [sys.executable, "-m", "freefloat.cli", "plan", "-o", "x.json", "--samples", "2001"],
            cwd=folder,
            env=_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 120
        while proc.poll() is None and time.monotonic() < deadline:
            if any(p.name.startswith(".x.json.") for p in folder.iterdir()):
                time.sleep(rng.uniform(0.0, 0.002))
                proc.send_signal(rng.choice(kinds))
                break
            time.sleep(0.0005)
        _, err = proc.communicate(timeout=120)
        names = sorted(p.name for p in folder.iterdir())
        whole = (folder / "x.json").read_text() in ("previous",) or (
            (folder / "x.json").read_text().startswith("{")
        )
        if names != ["x.json"] or not whole:
            tally.add("leftover", f"{names}")
        elif "Traceback" in err or len(err.splitlines()) > 1:
            tally.add("traceback", err)
        else:
            tally.add("clean refusal" if proc.returncode in (129, 130, 143) else "correct accept")
    _random_instants(tally, work, rng)


def _random_instants(tally: Tally, work: Path, rng: random.Random) -> None:
    folder = work / "loop"
    folder.mkdir()
    target = folder / "x.json"
    target.write_text("x" * 200_000)
    child = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(target)],
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    child.stdout.readline()
    for _ in range(300):
        time.sleep(rng.uniform(0.0, 0.004))
        child.send_signal(rng.choice([signal.SIGINT, signal.SIGTERM, signal.SIGHUP]))
    child.send_signal(signal.SIGUSR1)
    out, err = child.communicate(timeout=120)
    ended = int(out.strip() or 0)
    left = sorted(p.name for p in folder.iterdir())
    for _ in range(ended):
        tally.add("clean refusal")
    if left != ["x.json"] or target.read_text() != "x" * 200_000:
        tally.add("leftover", f"{left}")
    if err:
        tally.add("traceback", err)


def campaign_stream(tally: Tally, work: Path, plan_file: Path, rng: random.Random) -> None:
    for argv in (["verify", plan_file], ["bounds"], ["plan", "--samples", "11", "-o", "o.json"]):
        with open("/dev/full", "w") as full:
            result = run(argv, work, stdout=full)
        tally.add(*judged(result, refuse=True))
    for _ in range(6):
        keep = rng.randrange(0, 600)
        proc = subprocess.Popen(
            [sys.executable, "-m", "freefloat.cli", "verify", str(plan_file)],
            cwd=work,
            env=_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        assert proc.stdout is not None and proc.stderr is not None
        proc.stdout.read(keep)
        proc.stdout.close()
        err = proc.stderr.read().decode()
        proc.wait(timeout=120)
        bad = err or proc.returncode not in (0, 141)
        tally.add("traceback" if bad else "clean refusal", err)
    # an error with standard error full: quiet, exit 2
    with open("/dev/full", "w") as full:
        result = run(["verify", work / "missing.json"], work, stderr=full)
    tally.add("clean refusal" if result.returncode == 2 else "traceback", str(result.returncode))


def _edited(plan_file: Path, folder: Path, edit, name: str = "p.json") -> Path:  # type: ignore[no-untyped-def]
    doc = json.loads(plan_file.read_text())
    text = edit(doc)
    path = folder / name
    path.write_text(text if isinstance(text, str) else json.dumps(doc))
    return path


def _older(doc: dict, fmt: str = "freefloat.plan/3") -> None:
    doc["format"] = fmt
    del doc["robot"]["urdf_text"], doc["robot"]["urdf_sha256"]


def campaign_plans(tally: Tally, work: Path, ur5_plan: Path) -> None:
    """Edited plans: each refused (verify exit 1 or 2), or accepted when it is sound."""
    folder = work / "plans"
    (folder / "robot").mkdir(parents=True)
    doc = json.loads(ur5_plan.read_text())
    peak = max(abs(v) for row in doc["samples"]["tau"] for v in row)
    cut = re.sub(r'effort="[0-9.e+-]+"', f'effort="{peak / 3:.6g}"', doc["robot"]["urdf_text"])
    (folder / "robot" / "robot.urdf").write_text(cut)

    def relabel(d):  # type: ignore[no-untyped-def]
        _older(d, "freefloat.plan/2")
        del d["objective"]
        checks = d["verification"]["checks"]
        d["verification"]["checks"] = [c for c in checks if c["name"] != "joint_effort_limits"]
        d["robot"]["urdf"] = "robot/robot.urdf"

    def tamper(d):  # type: ignore[no-untyped-def]
        d["robot"]["urdf_text"] = d["robot"]["urdf_text"].replace('effort="', 'effort="9', 1)

    def duplicate(d):  # type: ignore[no-untyped-def]
        return json.dumps(d).replace('"duration": ', '"duration": 1.0, "duration": ', 1)

    def empty(d):  # type: ignore[no-untyped-def]
        d["robot"]["joints"][0] = ""

    def changed(d):  # type: ignore[no-untyped-def]
        d["robot"]["urdf"] = str(folder / "robot" / "robot.urdf")

    for edit in (relabel, tamper, duplicate, empty, changed):
        path = _edited(ur5_plan, folder, edit, f"{edit.__name__}.json")
        tally.add(*judged(run(["verify", path], work), refuse=True, codes=(1, 2)))
    # sound plans: the URDF gone (a cleared cache), a relative path read from the plan's folder
    gone = folder / "gone"
    gone.mkdir()
    shutil.copy(ROOT / "robots" / "ur5_servicer.urdf", gone / "r.urdf")
    path = _edited(ur5_plan, gone, lambda d: d["robot"].update(urdf=str(gone / "r.urdf")))
    (gone / "r.urdf").unlink()
    tally.add(*judged(run(["verify", path], work), refuse=False))
    elsewhere = folder / "elsewhere"
    (elsewhere / "robot").mkdir(parents=True)
    (elsewhere / "robot" / "robot.urdf").write_text(cut)  # another robot.urdf in the cwd
    shutil.copy(ROOT / "robots" / "ur5_servicer.urdf", gone / "robot.urdf")

    def relative(d):  # type: ignore[no-untyped-def]
        # a genuine format-3 file (monomials in t, no URDF copy: the path is what is read),
        # written by the tests' own writer of that format, not by freefloat
        sys.path.insert(0, str(ROOT / "tests"))
        from legacy import as_format_3

        d.clear()
        d.update(as_format_3(json.loads(ur5_plan.read_text())))
        d["robot"]["urdf"] = "robot.urdf"

    path = _edited(ur5_plan, gone, relative, "relative.json")
    tally.add(*judged(run(["verify", "-q", path], elsewhere), refuse=False))


def campaign_messages(tally: Tally, work: Path, plan_file: Path) -> None:
    folder = work / "messages"
    folder.mkdir()
    cases = _message_cases(folder, plan_file)
    for argv, refuse, needle in cases:
        result = run(argv, folder)
        outcome, note = judged(result, refuse=refuse)
        if outcome in ("clean refusal", "correct accept") and needle not in result.stderr:
            outcome, note = "traceback", f"message without {needle!r}: {result.stderr}"
        tally.add(outcome, note)


def _message_cases(folder: Path, plan_file: Path) -> list[tuple[list, bool, str]]:
    planar = PLANAR.read_text()
    (folder / "bom.urdf").write_bytes(b"\xef\xbb\xbf" + PLANAR.read_bytes())
    bom = scenario_for(folder / "bom.urdf", folder, "bom.toml")
    bom.write_bytes(b"\xef\xbb\xbf" + bom.read_bytes())
    cylinder = '<geometry><cylinder radius="0.05" length="1.0"/></geometry>'
    (folder / "broken.stl").write_text("solid x\nfacet normal 0 0 1\nouter loop\n")
    urdfs = {
        "escape": planar.replace(
            cylinder, '<geometry><mesh filename="package://../../../../etc/passwd"/></geometry>'
        ),
        "huge": planar.replace('izz="3.33"', 'izz="1e308"'),
        "mesh": planar.replace(
            cylinder, f'<geometry><mesh filename="{folder / "broken.stl"}"/></geometry>'
        ),
    }
    for name, text in urdfs.items():
        (folder / f"{name}.urdf").write_text(text)
    mesh_plan = folder / "mesh.json"
    run(
        ["plan", scenario_for(folder / "mesh.urdf", folder, "mesh.toml"), "-o", mesh_plan, "-q"],
        folder,
    )
    joints = "joint1 = 0.0, joint3 = 0.0, joint4 = 30.0, joint5 = 0.0, joint6 = 0.0, joint7 = 0.0"
    xarm = folder / "xarm.toml"
    xarm.write_text(
        'duration = 10.0\n[robot]\narm = "xarm7"\nbase_mass = 100.0\nbase_size = [0.6, 0.6, 0.6]\n'
        "mount = [0.3, 0.0, 0.0]\nmount_rpy_deg = [0.0, 90.0, 0.0]\n"
        f"[start]\njoints = {{ joint2 = 0.0, {joints} }}\n"
        f"[goal]\njoints = {{ joint2 = 150.0, {joints} }}\nbase_zyx_deg = [1.0, 0.0, 0.0]\n"
    )
    compose = ["--base-mass", "100", "--base-size", "1", "1", "1", "--mount", "0.5", "0", "0"]
    return [
        (["plan", bom, "-o", "bom.json"], False, ""),
        (["plan", xarm, "-o", "x.json"], True, "is outside its limits"),
        (
            ["plan", scenario_for(folder / "escape.urdf", folder, "e.toml"), "-o", "e.json"],
            True,
            "leaves its package",
        ),
        (
            ["plan", scenario_for(folder / "huge.urdf", folder, "h.toml"), "-o", "h.json"],
            True,
            "izz='1e308'",
        ),
        (["show", mesh_plan, "--html", "m.html"], True, "broken.stl"),
        (["compose", "--arm", "/etc/passwd", *compose, "-o", "c.urdf"], True, "malformed URDF XML"),
        (["sweep", "none.toml", "-o", "r.csv", "--scheduler", ""], True, "--scheduler is empty"),
        (
            ["plan", scenario_for(PLANAR, folder, "d.toml"), "--samples", "5", "-o", "/dev/null"],
            True,
            "regular files only",
        ),
        (["verify", plan_file], False, ""),
        *_pitch90_case(folder),
        *_edited_and_misnamed_cases(folder, plan_file),
        *_round_25_cases(folder),
        *_round_26_cases(folder, plan_file),
        *_round_31_cases(folder, plan_file),
        *_round_32_cases(folder),
        *_round_33_cases(folder),
        *_round_34_cases(folder),
        *_round_35_cases(folder),
    ]


def _round_25_cases(folder: Path) -> list[tuple[list, bool, str]]:
    """The twenty-fifth round's trials: a malformed SRDF (a traceback), a keep-out object no
    body can be checked against, a hull box with decimal commas (both accepted wrongly), a URL
    as robot, a lock list locking every joint, a negative number in exponent notation, a plan
    written over its own robot."""
    ur5 = (
        (ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
        .read_text()
        .replace('robot = "ur5_servicer"', f'robot = "{ROOT / "robots" / "ur5_servicer.urdf"}"')
    )
    (folder / "garbage.srdf").write_text("not xml <<<")
    (folder / "srdf.toml").write_text(ur5 + '\n[safety]\nsrdf = "garbage.srdf"\n')
    comma = (ROOT / "robots" / "ur5_servicer.urdf").read_text()
    comma = comma.replace('<box size="0.6 0.6 0.6"/>', '<box size="0,6 0,6 0,6"/>')
    (folder / "comma.urdf").write_text(comma)
    (folder / "comma.toml").write_text(
        ur5.replace(str(ROOT / "robots" / "ur5_servicer.urdf"), "comma.urdf")
    )
    post = scenario_for(PLANAR, folder, "post.toml")
    post.write_text(
        post.read_text().replace("check = false", "margin_m = 0.05")
        + '\n[[obstacles]]\nname = "post"\nsphere = 0.3\nxyz = [1.5, 0.9, 0.0]\n'
    )
    url = scenario_for(PLANAR, folder, "url.toml")
    url.write_text(url.read_text().replace(f'robot = "{PLANAR}"', 'robot = "https://x.org/r.urdf"'))
    shutil.copy(PLANAR, folder / "own.urdf")
    own = scenario_for(folder / "own.urdf", folder, "own.toml")
    return [
        (["check", folder / "srdf.toml"], True, "garbage.srdf is not XML"),
        (["check", folder / "comma.toml"], True, "collision box size='0,6 0,6 0,6'"),
        (["check", post], True, "keep-out object 'post' cannot be kept clear"),
        (["plan", url, "-o", "u.json"], True, "is a URL"),
        (["plan", own, "-o", folder / "own.urdf"], True, "is a file this command reads"),
        (["correct", "absent.json", "--base-zyx-deg", "-1e9", "0", "0"], True, "is outside"),
    ]


def _round_26_cases(folder: Path, plan_file: Path) -> list[tuple[list, bool, str]]:
    """The twenty-sixth round's trials: a locked first joint that hid the hull (a wrong
    accept), a start outside an end-effector cone (a 33 s search), a tampered plan used by
    sensitivity, a joint locked twice."""
    locked = folder / "lockpan.urdf"
    compose = ["--base-mass", "100", "--base-size", "0.6", "0.6", "0.6", "--mount", "0.3", "0", "0"]
    compose += ["--mount-rpy", "0", "90", "0"]
    run(
        ["compose", "--arm", "ur5", *compose, "--lock", "shoulder_pan_joint=0", "-o", locked],
        folder,
    )
    inside = "shoulder_lift_joint = 155.0, elbow_joint = -55.0, wrist_1_joint = -60.0"
    (folder / "lockpan.toml").write_text(
        f'robot = "{locked}"\nduration = 20.0\n[start]\njoints = {{ {inside}, '
        "wrist_2_joint = 0.0, wrist_3_joint = 90.0 }\n[goal]\njoints = { "
        f"{inside}, wrist_2_joint = 0.0, wrist_3_joint = 80.0 }}\n"
    )
    cone = scenario_for(PLANAR, folder, "cone.toml")
    cone.write_text(
        cone.read_text() + "\n[constraints.end_effector_cone]\naxis = [1.0, 0.0, 0.0]\n"
        "direction = [0.342, 0.94, 0.0]\nhalf_angle_deg = 35.0\n"
    )
    tampered = folder / "tampered.json"
    data = json.loads(Path(plan_file).read_text())
    data["samples"]["tau"] = [[2.0 * v for v in row] for row in data["samples"]["tau"]]
    tampered.write_text(json.dumps(data))
    twice = ["--lock", "elbow_joint=90", "elbow_joint=45", "-o", "t.urdf"]
    return [
        (["plan", folder / "lockpan.toml", "-o", "l.json"], True, "upper_arm_link_0"),
        (["plan", cone, "-o", "c.json"], True, "breaks end_effector_cone"),
        (["sensitivity", tampered], True, "disagrees with the recomputation"),
        (["compose", "--arm", "ur5", *compose, *twice], True, "given twice"),
    ]


def _round_31_cases(folder: Path, plan_file: Path) -> list[tuple[list, bool, str]]:
    """The thirty-first round's trials: a NaN vertex in a mesh (a traceback), a sweep drawn
    over 1e308 (a traceback), 1 000 001 sample times (minutes of schema walk), a joint locked
    twice in [robot] (silently the last), a prefix with a line break, an empty --name, a name
    too long for the file system, a bag through a dangling link (made at its end), and a
    correction whose written plan verify refused (it must now verify)."""
    import struct

    corners = [(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (math.nan, 0.0, 0.1)]
    faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]
    body = b"".join(
        struct.pack("<12fH", 0.0, 0.0, 0.0, *(x for k in f for x in corners[k]), 0) for f in faces
    )
    (folder / "nan.stl").write_bytes(b"\0" * 80 + struct.pack("<I", len(faces)) + body)
    collision = (
        f'<collision><geometry><mesh filename="{folder / "nan.stl"}"/></geometry></collision>'
    )
    planar = PLANAR.read_text()
    link1 = planar.index("</link>", planar.index('<link name="link1">'))
    (folder / "nan.urdf").write_text(planar[:link1] + collision + planar[link1:])
    nan_scenario = scenario_for(folder / "nan.urdf", folder, "n.toml")
    nan_scenario.write_text(nan_scenario.read_text().replace("check = false", "check = true"))
    scenario_for(PLANAR, folder, "base31.toml")
    (folder / "huge31.toml").write_text(
        'scenario = "base31.toml"\n[[axis]]\nkey = "goal.joints.q2"\n'
        "values = { uniform = [-1e308, 1e308], samples = 2 }\n"
    )
    data = json.loads(Path(plan_file).read_text())
    data["samples"]["t"] = data["samples"]["t"] + [0.0] * 1_000_000
    (folder / "long.json").write_text(json.dumps(data))
    twice = scenario_for(PLANAR, folder, "twice.toml")
    text = twice.read_text()
    twice.write_text(
        text.replace(f'robot = "{PLANAR}"', "")
        + f'[robot]\nurdf = "{PLANAR}"\nlock = ["q2", {{ joint = "q2", value = 45.0 }}]\n'
    )
    compose = ["--base-mass", "100", "--base-size", "1", "1", "1", "--mount", "0.5", "0", "0"]
    (folder / "dangling").symlink_to(folder / "nowhere")
    corrected = folder / "c179.json"
    run(["correct", plan_file, "--base-zyx-deg", "179", "0", "0", "-o", corrected, "-q"], folder)
    return [
        (["check", nan_scenario], True, "not finite"),
        (["sweep", folder / "huge31.toml", "-o", "h.csv"], True, "magnitude at most 1e+09"),
        (["verify", folder / "long.json"], True, "more than the 1000000"),
        (["check", twice], True, "names joint 'q2' twice"),
        (["compose", "--arm", "ur5", "--prefix", "a\nb_", *compose, "-o", "p.urdf"], True, "break"),
        (["compose", "--arm", "ur5", *compose, "--name", "", "-o", "n.urdf"], True, "--name"),
        (["check", "a" * 300], True, "File name too long"),
        (["export", plan_file, "--format", "ros2-bag", "-o", folder / "dangling"], True, "nothing"),
        (["verify", corrected], False, ""),
    ]


def _round_32_cases(folder: Path) -> list[tuple[list, bool, str]]:
    """The thirty-second round's new keys, [constraints.base_swing] and [payload] held_by: bad
    bounds, a goal beyond the bound, a plan whose recorded bound was edited (tightened, or to
    nonsense), a loop whose check overflowed, reach with a bound (a traceback), a payload
    held by the spacecraft (it was accepted)."""
    base = scenario_for(PLANAR, folder, "swing.toml").read_text()
    cases: list[tuple[list, bool, str]] = []
    for k, (value, said) in enumerate(
        [
            ("-1", "between 0 and 180"),
            ("0", "between 0 and 180"),
            ("180", "between 0 and 180"),
            ("inf", "between 0 and 180"),
            ("nan", "between 0 and 180"),
            ('"5"', "between 0 and 180"),
            ("true", "between 0 and 180"),
            ("[5]", "between 0 and 180"),
            ("30", "goal attitude breaks base_swing"),
        ]
    ):
        path = folder / f"swing{k}.toml"
        path.write_text(base + f"\n[constraints.base_swing]\nmax_deg = {value}\n")
        cases.append((["plan", path, "-o", f"swing{k}.json"], True, said))
    for name, table in (("swing_missing", ""), ("swing_extra", "max_deg = 60\naxis = 1\n")):
        (folder / f"{name}.toml").write_text(base + f"\n[constraints.base_swing]\n{table}")
        cases.append((["plan", folder / f"{name}.toml", "-o", "x.json"], True, "base_swing"))
    good = folder / "swing_ok.toml"
    good.write_text(base + "\n[constraints.base_swing]\nmax_deg = 60\n")
    planned = folder / "swing_ok.json"
    run(["plan", good, "-o", planned, "-q"], folder)
    for name, bound, said in (("tight", 1.0, "disagrees"), ("nonsense", -5.0, "between 0")):
        doc = json.loads(planned.read_text())
        for item in doc["constraints"]:
            if item["name"] == "base_swing":
                item["parameters"]["max_deg"] = bound
        (folder / f"swing_{name}.json").write_text(json.dumps(doc))
        cases.append((["verify", folder / f"swing_{name}.json"], True, said))
    nan = folder / "swing_nan.toml"  # a loop of planar joints: the check once overflowed
    nan.write_text(
        'robot = "planar_2dof"\nduration = 10.0\n[start]\njoints = { q1 = 80.0, q2 = 30.0 }\n'
        "[goal]\njoints = { q1 = 80.0, q2 = 30.0 }\nbase_zyx_deg = [10.0, 0.0, 0.0]\n"
        "[constraints.base_swing]\nmax_deg = 10.5\n"
    )
    ur5 = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
    ur5 = ur5.replace('"ur5_servicer"', f'"{ROOT / "robots" / "ur5_servicer.urdf"}"')
    held = folder / "held_spacecraft.toml"
    held.write_text(
        ur5 + '\n[payload]\nmass = 5.0\nbox = [0.1, 0.1, 0.1]\nheld_by = "spacecraft"\n'
    )
    reach = folder / "swing_reach.toml"
    reach.write_text(ur5 + "\n[constraints.base_swing]\nmax_deg = 14\n")
    pointing = folder / "pointing.toml"
    for k, (table, said) in enumerate(
        [
            ("axis = [0, 0, 0]\nhalf_angle_deg = 5", "must be a non-zero vector"),
            ("axis = [1, 0, 0]\nhalf_angle_deg = -5", "between 0 and 180"),
            ("axis = [1, 0, 0]\ndirection = [1e400, 0, 0]\nhalf_angle_deg = 5", "finite"),
            ("axis = [1, 0, 0]\ndirection = [-1, 0, 0]\nhalf_angle_deg = 90", "start attitude"),
            ("half_angle_deg = 5", "missing 'axis'"),
        ]
    ):
        pointing.write_text(base + f"\n[constraints.base_pointing]\n{table}\n")
        cases.append((["plan", pointing, "-o", f"pointing{k}.json"], True, said))
        pointing = folder / f"pointing{k + 1}.toml"
    return [
        *cases,
        (["verify", planned], False, ""),
        (["plan", nan, "-o", "nan.json"], True, "no path reaches"),
        (["check", held], True, "is not one of the scenario's end effectors: 'tool0'"),
        (["reach", reach, "-q", "--jobs", "1"], False, ""),
    ]


def _round_33_cases(folder: Path) -> list[tuple[list, bool, str]]:
    """The thirty-third round's: a goal on the swing bound (to the last digit) while the plain
    path swings far beyond it (refused before), and a sweep results file written before the
    largest_turn_deg column, resumed (refused: another sweep; nothing written)."""
    ur5 = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
    ur5 = ur5.replace('"ur5_servicer"', f'"{ROOT / "robots" / "ur5_servicer.urdf"}"')
    turned = re.sub(r"base_zyx_deg = .*", "base_zyx_deg = [6.0, 3.0, 0.0]", ur5)
    start = ff.quat_from_zyx(0.0, 0.0, 0.0)
    goal = ff.quat_from_zyx(math.radians(6.0), math.radians(3.0), 0.0)
    on_bound = folder / "on_bound.toml"
    on_bound.write_text(
        turned
        + "\n[constraints.base_swing]\nmax_deg = "
        + f"{math.degrees(ff.geodesic_angle(start, goal))!r}\n"
    )
    shutil.copy(ROOT / "robots" / "scenarios" / "worked_example.toml", folder / "we33.toml")
    sweep = folder / "sweep33.toml"
    sweep.write_text(
        'scenario = "we33.toml"\nsamples = 21\n[[axis]]\nkey = "goal.base_zyx_deg.0"\n'
        "values = [40.0, 45.0]\n"
    )
    done = folder / "sweep33.csv"
    run(["sweep", sweep, "-o", done, "--workers", "1", "-q"], folder)
    header, *rows = done.read_text().splitlines()
    names = header.split(",")
    gone = names.index("largest_turn_deg")
    older = [",".join(c for k, c in enumerate(r.split(",")) if k != gone) for r in [header, *rows]]
    (folder / "sweep33_old.csv").write_text("\n".join(older[:2]) + "\n")
    return [
        (["plan", on_bound, "-o", "on_bound.json", "-q"], False, ""),
        (["sweep", sweep, "-o", "sweep33_old.csv", "-q"], True, "holds another sweep"),
    ]


def _round_34_cases(folder: Path) -> list[tuple[list, bool, str]]:
    """The thirty-fourth round's: a correction of a plan with a pointing cone from a measured
    attitude outside it (the cone turned with the plan before, and this planned), and from
    one inside it (planned, the cone where the mission fixed it)."""
    ur5 = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()
    ur5 = ur5.replace('"ur5_servicer"', f'"{ROOT / "robots" / "ur5_servicer.urdf"}"')
    coned = folder / "coned.toml"
    coned.write_text(ur5 + "\n[constraints.base_pointing]\naxis = [0, 0, 1]\nhalf_angle_deg = 10\n")
    run(["plan", coned, "-o", "coned.json", "-q"], folder)
    measured = ["--base-zyx-deg", "-7.6", "-3.0", "-11.0"]  # the z axis 11.4 deg from the start's
    return [
        (["correct", "coned.json", *measured, "-o", "out.json"], True, "correcting motion starts"),
        (["correct", "coned.json", "--base-zyx-deg", "-7.0", "-1.5", "-8.0", "-q"], False, ""),
    ]


def _round_35_cases(folder: Path) -> list[tuple[list, bool, str]]:
    """The thirty-fifth round's: the worked example kept within an end-effector cone and
    corrected from 10 deg (refused while the loop it starts from was picked for its turn
    alone; planned), and the UR5 servicer turned 1 deg in place within a 0.8 deg pointing
    cone (planned)."""
    scenarios = ROOT / "robots" / "scenarios"
    worked = (scenarios / "worked_example.toml").read_text()
    worked = worked.replace('"planar_2dof"', f'"{ROOT / "robots" / "planar_2dof.urdf"}"')
    cone = folder / "we_cone.toml"
    cone.write_text(
        worked + "\n[constraints.end_effector_cone]\naxis = [1.0, 0.0, 0.0]\n"
        "direction = [0.3420201433256687, 0.9396926207859083, 0.0]\nhalf_angle_deg = 60.0\n"
    )
    run(["plan", cone, "-o", "we_cone.json", "-q"], folder)
    ur5 = (scenarios / "ur5_servicer.toml").read_text()
    ur5 = ur5.replace('"ur5_servicer"', f'"{ROOT / "robots" / "ur5_servicer.urdf"}"')
    start = ur5.split("[start]\n", 1)[1].split("\n", 1)[0]
    goal = ur5.split("[goal]\n", 1)[1].split("\n[", 1)[0]
    in_place = folder / "in_place.toml"
    in_place.write_text(
        ur5.replace(goal, start + "\nbase_zyx_deg = [1.0, 0.0, 0.0]\n")
        + "\n[constraints.base_pointing]\naxis = [0, 0, 1]\nhalf_angle_deg = 0.8\n"
    )
    return [
        (
            ["correct", "we_cone.json", "--base-zyx-deg", "10", "0", "0", "-o", "c35.json"],
            False,
            "",
        ),
        (["plan", in_place, "-o", "in_place.json", "-q"], False, ""),
    ]


def _edited_and_misnamed_cases(folder: Path, plan_file: Path) -> list[tuple[list, bool, str]]:
    """The twenty-fourth round's trials: a negative margin in a plan file (a traceback from
    four commands), outputs named empty or as the input, an arm with a loop (a crash), a
    figure of another format, joint values that start negative."""
    doc = json.loads(plan_file.read_text())
    doc["safety"]["margin_m"] = -1.0
    negative = folder / "negative_margin.json"
    negative.write_text(json.dumps(doc))
    copy = folder / "own.json"
    shutil.copy(plan_file, copy)
    loop = folder / "loop.urdf"
    loop.write_text(
        PLANAR.read_text().replace(
            "</robot>",
            '<joint name="back" type="revolute"><parent link="link2"/><child link="link1"/>'
            '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
            "</robot>",
        )
    )
    compose = ["--base-mass", "100", "--base-size", "1", "1", "1", "--mount", "0.5", "0", "0"]
    ur5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
    margin = "safety.margin_m: -1.0 is less than the minimum of 0"
    return [
        (["verify", negative], True, margin),
        (["sensitivity", negative], True, margin),
        (["correct", negative, "--base-zyx-deg", "1", "0", "0"], True, margin),
        (["export", negative, "--format", "csv", "-o", "n.csv"], True, margin),
        (["show", copy, "--html", ""], True, "needs a file name"),
        (["export", copy, "--format", "csv", "-o", copy], True, "is the file this command reads"),
        (["compose", "--arm", loop, *compose, "-o", "l.urdf"], True, "closed loop"),
        (["reach", "--plot", "r.txt"], True, "a figure is written as PNG, SVG or PDF"),
        (["check", ur5, "--at", "-10,-90,90,-90,-90,0"], False, ""),
    ]


def _pitch90_case(folder: Path) -> list[tuple[list, bool, str]]:
    """A Panda plan whose goal pitch is 90 deg: it must plan, verify and plot."""
    from freefloat.physics.attitude import quat_from_zyx, quat_multiply, zyx_from_quat

    turn = quat_from_zyx(*np.radians([-6.4, -8.8, -4.1]))
    start = quat_multiply(quat_from_zyx(0.0, math.pi / 2, 0.0), turn * np.array([-1, -1, -1, 1]))
    start_deg = ", ".join(repr(float(a)) for a in np.degrees(zyx_from_quat(start)))
    text = (ROOT / "robots" / "scenarios" / "panda_servicer.toml").read_text()
    text = text.replace("base_zyx_deg = [0.0, 0.0, 0.0]", f"base_zyx_deg = [{start_deg}]")
    text = text.replace("[-6.4, -8.8, -4.1]", "[0.0, 90.0, 0.0]").replace(
        '"panda_servicer"', f'"{ROOT / "robots" / "panda_servicer.urdf"}"'
    )
    (folder / "pitch90.toml").write_text(text)
    return [
        (["plan", folder / "pitch90.toml", "-o", "pitch90.json", "-q"], False, ""),
        (["verify", "pitch90.json"], False, ""),
        (["plot", "pitch90.json", "-o", "plots90"], False, ""),
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", type=int, default=26)
    parser.add_argument("--quick", action="store_true", help="fewer cases per random class")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    n = 8 if args.quick else 30
    tallies = {
        name: Tally()
        for name in ("urdf-xml", "inertia", "device", "signal", "stream", "plan", "messages")
    }
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="ff-campaign-") as tmp:
        work = Path(tmp)
        plan_file = work / "worked.json"
        run(["plan", "-o", plan_file, "-q"], work)
        ur5 = work / "ur5.json"
        run(["plan", ROOT / "robots" / "scenarios" / "ur5_servicer.toml", "-o", ur5, "-q"], work)
        steps = [
            ("urdf-xml", lambda t: campaign_urdf_xml(t, work, rng, n)),
            ("inertia", lambda t: campaign_inertia(t, work, args.seed, 5 * n)),
            ("device", lambda t: campaign_device(t, work, plan_file)),
            ("signal", lambda t: campaign_signal(t, work, rng, n)),
            ("stream", lambda t: campaign_stream(t, work, plan_file, rng)),
            ("plan", lambda t: campaign_plans(t, work, ur5)),
            ("messages", lambda t: campaign_messages(t, work, plan_file)),
        ]
        for name, step in steps:
            clock = time.perf_counter()
            step(tallies[name])
            print(f"  {name:<10} done in {time.perf_counter() - clock:6.1f} s", file=sys.stderr)
    shutil.rmtree(CACHE, ignore_errors=True)
    return report(tallies, time.perf_counter() - started)


COLUMNS = (
    "clean refusal",
    "correct accept",
    "wrong accept",
    "false refusal",
    "traceback",
    "leftover",
)


def report(tallies: dict[str, Tally], seconds: float) -> int:
    print(f"hostile-input campaign (issue 26), {seconds:.0f} s wall time")
    print(f"  {'class':<10}{'cases':>7}" + "".join(f"{c:>16}" for c in COLUMNS))
    total = Counter()
    for name, tally in tallies.items():
        total.update(tally.outcomes)
        row = "".join(f"{tally.outcomes[c]:>16}" for c in COLUMNS)
        print(f"  {name:<10}{tally.cases:>7}{row}")
    print(
        f"  {'total':<10}{sum(t.cases for t in tallies.values()):>7}"
        + "".join(f"{total[c]:>16}" for c in COLUMNS)
    )
    for name, tally in tallies.items():
        for note in tally.notes:
            print(f"  [{name}] {note}")
    bad = sum(total[c] for c in ("wrong accept", "false refusal", "traceback", "leftover"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
