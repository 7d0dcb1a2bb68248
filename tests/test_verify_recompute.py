"""verify trusts nothing in a plan file (issue 14): every number is recomputed, limits first."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
import freefloat.verify.agreement as agreement
from freefloat.cli import main
from freefloat.plans.limits import MAX_PLAN_BYTES
from freefloat.verify.recompute import compare_verification

from conftest import ROOT, as_older_format

SCENARIOS = sorted((ROOT / "robots" / "scenarios").glob("*.toml"))


def _run(capsys, *argv):
    clock = time.perf_counter()
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err.strip().splitlines(), time.perf_counter() - clock


def _refused(capsys, *argv) -> str:
    """Run the command; it must refuse in one line, exit 2, within 10 s; return the line."""
    code, _, err, seconds = _run(capsys, *argv)
    assert code == 2, err
    assert len(err) == 1 and err[0].startswith("freefloat: error: "), err
    assert len(err[0]) < 400, err[0]
    assert seconds < 10.0
    return err[0]


@pytest.fixture(scope="module")
def original(worked_plan) -> dict:
    return json.loads(worked_plan.to_json())


def _write(tmp_path: Path, data: dict | str, name: str = "plan.json") -> Path:
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def _changed(original: dict, tmp_path: Path, change) -> Path:
    data = json.loads(json.dumps(original))
    change(data)
    return _write(tmp_path, data)


def _bump_tau(d):
    d["samples"]["tau"][50][0] += 1e-6


def _double_tau(d):
    d["samples"]["tau"] = [[2.0 * v for v in row] for row in d["samples"]["tau"]]


def _free(d):
    d["free_parameters"]["q2"] = [1e-4]


def _move_ee(d):
    d["samples"]["end_effector_position"] = [
        [x + 0.1, y, z] for x, y, z in d["samples"]["end_effector_position"]
    ]


def _figure(d):
    d["verification"]["checks"][0]["value"] = 1e-10  # still passes, but is not the figure


@pytest.mark.parametrize(
    ("change", "field", "amount"),
    [
        (_bump_tau, "samples.tau", "by 1e-06 N m at t = 2.5 s (q1)"),
        (_double_tau, "samples.tau", "N m at t = "),
        (_free, "free_parameters.q2", "rad (entry 0)"),
        (_move_ee, "samples.end_effector_position", "by 0.1 m at t = 0 s (x)"),
        (  # format 4: the request defines the quintic, so the path moves with it
            lambda d: d["request"]["start_joints"].__setitem__(0, 1.0),
            "base.achieved_quaternion_xyzw",
            "rad",
        ),
        (lambda d: d["samples"]["q"][7].__setitem__(1, 0.5), "samples.q", "at t = 0.35 s (q2)"),
        (lambda d: d["samples"]["base_zyx_deg"][9].__setitem__(0, 1.0), "samples.base_zyx_deg", ""),
        (
            lambda d: d["base"].__setitem__("attitude_error_rad", 1e-6),
            "base.attitude_error_rad",
            "",
        ),
        (
            lambda d: d["feasibility"]["yaw_change_bounds_deg"].__setitem__(1, 80.0),
            "feasibility.yaw_change_bounds_deg",
            "deg",
        ),
        (
            lambda d: d["solver"]["solutions"][2].__setitem__("path_length", 1.0),
            "solver.solutions[2].path_length",
            "",
        ),
        (_figure, "verification.checks[0].value", "kg m^2/s"),
    ],
)
def test_a_number_changed_in_the_file_is_named(original, tmp_path, capsys, change, field, amount):
    line = _refused(capsys, "verify", _changed(original, tmp_path, change))
    assert f"plan field '{field}' disagrees with the recomputation" in line, line
    assert amount in line and "tolerance" in line, line


def test_the_api_raises_the_mismatch_with_its_data(worked_plan):
    tau = [list(row) for row in worked_plan.samples.tau]
    tau[100][1] += 1e-6
    samples = dict(worked_plan.samples.__dict__, tau=tau)
    bad = ff.Plan(**dict(worked_plan.__dict__, samples=ff.plans.Samples(**samples)))
    with pytest.raises(ff.PlanMismatchError) as info:
        ff.verify_plan(bad)
    error = info.value
    assert error.field == "samples.tau" and error.unit == "N m"
    assert error.difference == pytest.approx(1e-6, rel=1e-6)
    assert error.tolerance < 1e-8 and "t = 5 s (q2)" in error.where
    assert isinstance(error, ff.PlanFileError)


def test_a_stated_flag_must_say_what_the_figures_say(original, tmp_path, capsys):
    path = _changed(original, tmp_path, lambda d: d["verification"].__setitem__("passed", False))
    assert "plan field 'verification.passed' is False" in _refused(capsys, "verify", path)
    path = _changed(
        original, tmp_path, lambda d: d["verification"]["checks"][1].__setitem__("passed", False)
    )
    assert "'verification.checks[1].passed' is False" in _refused(capsys, "verify", path)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda d: d["path"]["coefficients"]["q2"].__setitem__(0, float("nan")),
            "plan field 'path.coefficients.q2[0]' is nan; every number must be finite",
        ),
        (
            lambda d: d["path"]["coefficients"]["q2"].__setitem__(0, 1e308),
            "plan field 'path.coefficients.q2[0]' is 1e+308, beyond the 1e+100",
        ),
        (
            lambda d: d["path"]["coefficients"]["q2"].__setitem__(0, 1e20),
            "its term reaches 1e+20, beyond the 1e+06 (rad or m)",
        ),
        (lambda d: d.__setitem__("duration", "nan"), "duration: expected a number, got 'nan'"),
        (lambda d: d.__setitem__("duration", 1e-300), "duration: 1e-300 is less than the minimum"),
        (
            lambda d: d["path"]["coefficients"]["q2"].__setitem__(0, "1.0"),
            "path.coefficients.q2[0]: expected a number, got '1.0'",
        ),
        (lambda d: d["samples"]["q"].pop(), "'samples.q' has 200 rows, expected 201"),
        (lambda d: d["samples"]["tau"].pop(), "'samples.tau' has 200 rows, expected 201"),
        (
            lambda d: [
                d["samples"].__setitem__(k, [])
                for k in list(d["samples"])
                if isinstance(d["samples"][k], list)  # every per-sample list emptied
            ],
            "samples.t: expected at least 2 entries, got []",
        ),
        (
            lambda d: d["path"]["coefficients"]["q2"].extend([0.0] * 30),
            "path.coefficients.q2: expected at most 25 entries",
        ),
        (  # beyond the older formats' limit too: this format's is quoted
            lambda d: d["path"]["coefficients"]["q2"].extend([0.0] * 40),
            "path.coefficients.q2: expected at most 25 entries",
        ),
        (
            lambda d: d["safety"].__setitem__(
                "obstacles", [{"name": "panel", "shape": "sphere", "size": [0.1]}] * 2
            ),
            "plan field 'safety.obstacles' must hold at most 64 keep-out objects with distinct "
            "non-empty names, as a scenario's, got ['panel', 'panel']",
        ),
        (
            lambda d: d["safety"].__setitem__(
                "obstacles", [{"name": "", "shape": "sphere", "size": [0.1]}]
            ),
            "distinct non-empty names, as a scenario's, got ['']",
        ),
        (
            lambda d: d["solver"].__setitem__("solutions", []),
            "solver.solutions: expected at least 1 entry, got []",
        ),
        (
            lambda d: d["free_parameters"]["q2"].append(0.0),
            "'free_parameters.q2' has 2 entries, expected 1",
        ),
        (
            lambda d: d["solver"].__setitem__("integration_steps", 10**12),
            "solver.integration_steps: 1000000000000 is greater than the maximum of 65536",
        ),
    ],
)
def test_hostile_plans_are_refused_in_one_line(original, tmp_path, capsys, change, message):
    line = _refused(capsys, "verify", _changed(original, tmp_path, change))
    assert message in line, line


def test_a_urdf_copy_longer_than_a_urdf_file_may_be_is_refused(
    original, tmp_path, capsys, monkeypatch
):
    """As a URDF file beyond MAX_URDF_BYTES is (the limit lowered to the copy's length - 1)."""
    from freefloat.plans import io

    length = len(original["robot"]["urdf_text"])
    monkeypatch.setattr(io, "MAX_URDF_BYTES", length - 1)
    line = _refused(capsys, "verify", _changed(original, tmp_path, lambda d: None))
    assert f"'robot.urdf_text' holds {length} characters, beyond the {length - 1} bytes" in line
    monkeypatch.setattr(io, "MAX_URDF_BYTES", length)
    code, _, err, _ = _run(capsys, "verify", _changed(original, tmp_path, lambda d: None))
    assert code == 0, err


def test_format_1_limits_are_checked_without_the_schema(original, tmp_path, capsys):
    def old(d):
        d["format"] = "freefloat.plan/1"
        d["duration"] = 1e7

    line = _refused(capsys, "verify", _changed(original, tmp_path, old))
    assert "plan field 'duration' is 10000000.0 s, outside the 0.001 to 1e+06 s" in line


def test_hostile_files_are_refused_before_reading(tmp_path, capsys):
    nested = _write(tmp_path, "[" * 20000 + "]" * 20000, "nested.json")
    assert "JSON nested too deeply" in _refused(capsys, "verify", nested)
    digits = _write(tmp_path, '{"format": ' + "1" * 5000 + "}", "digits.json")
    assert "not a plan file" in _refused(capsys, "verify", digits)
    literal = _write(tmp_path, '{"format": NaN}', "literal.json")
    assert "plan format nan is not supported" in _refused(capsys, "verify", literal)
    big = tmp_path / "big.json"
    with open(big, "wb") as handle:  # sparse: nothing is written
        handle.truncate(MAX_PLAN_BYTES + 1)
    assert "larger than the 200 MiB a plan file may have" in _refused(capsys, "verify", big)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    assert "not a regular file" in _refused(capsys, "verify", fifo)
    assert "a directory" in _refused(capsys, "verify", tmp_path)
    assert "/dev/zero: not a regular file" in _refused(capsys, "verify", "/dev/zero")


@pytest.mark.parametrize(
    ("steps", "message"),
    [
        ("0", "--replay-steps must be at least 1, got 0"),
        ("-1", "--replay-steps must be at least 1, got -1"),
        ("70000", "--replay-steps must be at most 65536, got 70000"),
    ],
)
def test_replay_steps_out_of_range_are_refused(original, tmp_path, capsys, steps, message):
    path = _write(tmp_path, original)
    assert (
        _refused(capsys, "verify", path, "--replay-steps", steps) == f"freefloat: error: {message}"
    )


@pytest.fixture(scope="module")
def shipped_plans(tmp_path_factory, worked_plan) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("shipped")
    out = {"worked_example": worked_plan.save(folder / "worked_example.json")}
    for scenario in SCENARIOS:
        if scenario.stem not in out:
            assert (
                main(["-q", "plan", str(scenario), "-o", str(folder / f"{scenario.stem}.json")])
                == 0
            )
            out[scenario.stem] = folder / f"{scenario.stem}.json"
    return out


@pytest.mark.parametrize("name", [p.stem for p in SCENARIOS])
def test_genuine_plans_agree_with_their_recomputation_a_thousandfold(
    shipped_plans, capsys, monkeypatch, name
):
    """Every shipped scenario's plan passes verify, with its disagreements far below tolerance."""
    ratios: dict[str, float] = {}
    compare = agreement.compare

    def spy(field, stored, recomputed, tolerance, *args, **kwargs):
        diff = np.abs(np.asarray(stored, float) - np.asarray(recomputed, float))
        ratio = diff / np.maximum(np.asarray(tolerance, float), 1e-300)
        ratios[field] = max(ratios.get(field, 0.0), float(np.max(ratio, initial=0.0)))
        return compare(field, stored, recomputed, tolerance, *args, **kwargs)

    monkeypatch.setattr(agreement, "compare", spy)
    code, out, err, _ = _run(capsys, "verify", shipped_plans[name])
    assert code == 0 and err == [], err
    assert "verification                            passed" in out
    assert {"samples.tau", "samples.end_effector_position", "base.achieved_quaternion_xyzw"} <= set(
        ratios
    )
    margins = {k: v for k, v in ratios.items() if not k.startswith("verification")}
    assert max(margins.values()) < 1e-3, sorted(margins.items(), key=lambda kv: -kv[1])[:3]


def test_plot_and_show_refuse_a_tampered_plan_unless_told(original, tmp_path, capsys):
    path = _changed(original, tmp_path, _double_tau)
    line = _refused(capsys, "plot", path, "-o", tmp_path / "plots")
    assert "plan field 'samples.tau' disagrees" in line
    assert "--no-verify plots it anyway" in line
    assert not (tmp_path / "plots").exists()
    page = tmp_path / "page.html"
    line = _refused(capsys, "show", path, "--html", page)
    assert "--no-verify shows it anyway" in line and not page.exists()
    code, _, err, _ = _run(capsys, "show", path, "--html", page, "--no-verify")
    assert code == 0 and page.is_file(), err


def test_sensitivity_correct_and_replay_sweeps_refuse_a_tampered_plan(original, tmp_path, capsys):
    """Each reads a plan file: each verifies it first, as show and plot do."""
    path = _changed(original, tmp_path, _double_tau)
    line = _refused(capsys, "sensitivity", path)
    assert "plan field 'samples.tau' disagrees" in line
    assert line.endswith("--no-verify assesses it anyway")
    code, out, err, _ = _run(capsys, "sensitivity", path, "--no-verify")
    assert code == 0 and "final attitude" in out, err
    corrected = tmp_path / "c.json"
    line = _refused(capsys, "correct", path, "--base-zyx-deg", "1", "0", "0", "-o", corrected)
    assert line.endswith("--no-verify corrects it anyway") and not corrected.exists()
    sweep = tmp_path / "replay.toml"
    sweep.write_text(
        f'plan = "{path.name}"\n[[axis]]\nkey = "robot.links.link1.mass"\nvalues = [1.0]\n'
    )
    rows = tmp_path / "rows.csv"
    line = _refused(capsys, "sweep", sweep, "-o", rows)
    assert f"plan {path.name}: plan field 'samples.tau' disagrees" in line
    assert not rows.exists()


def test_show_catches_a_urdf_changed_after_planning(original, tmp_path, capsys):
    urdf = tmp_path / "arm.urdf"
    shutil.copy(ROOT / "robots" / "planar_2dof.urdf", urdf)
    data = json.loads(json.dumps(original))
    data["robot"]["urdf"] = str(urdf)
    path = _write(tmp_path, data)
    page = tmp_path / "page.html"
    code, _, err, _ = _run(capsys, "show", path, "--html", page)
    assert code == 0 and page.is_file(), err  # the same robot: the plan holds
    page.unlink()
    text = urdf.read_text()
    heavier = text.replace('<mass value="30.0"/>', '<mass value="31.0"/>', 1)
    assert heavier != text
    urdf.write_text(heavier)
    line = _refused(capsys, "show", path, "--html", page)
    assert f"the URDF {urdf} has changed since the plan was made" in line
    assert not page.exists()
    # A format-3 plan carries no URDF copy: its numbers disagree with the changed file's.
    data = as_older_format(data)
    line = _refused(capsys, "show", _write(tmp_path, data), "--html", page, "-q")
    assert "disagrees with the recomputation" in line and not page.exists()


#: The worked example's integrating checks as the version before the fifth-order checks
#: (ba3c91d) wrote them into this very plan (the same path, bit for bit): name, detail,
#: value, error estimate.
RK4_FIGURES = (
    ("attitude_independent", "RK4, 128 steps", 7.195773976647053e-10, 1.0785548119811619e-08),
    ("replay_attitude", "RK4, 64 steps", 2.8788997249781203e-07, 4.373921684398019e-06),
    ("replay_joints", "RK4, 64 steps", 1.8774653669506591e-06, 2.8834068599881135e-05),
)


def _as_rk4(data: dict, value_of=lambda name, value, tolerance: value) -> None:
    """The integrating checks replaced by :data:`RK4_FIGURES` (``value_of`` may change one)."""
    checks = {c["name"]: c for c in data["verification"]["checks"]}
    for name, detail, value, estimate in RK4_FIGURES:
        check = checks[name]
        check.update(detail=detail, error_estimate=estimate)
        check["value"] = value_of(name, value, check["tolerance"])


def test_integrating_figures_of_rk4_are_compared_within_both_estimates(original, tmp_path, capsys):
    """A file made before the fifth-order checks states their figures as RK4 found them (its
    ``detail`` says so): they differ from this version's by more than this version's
    estimates allow (the RK4 error estimates were larger), yet lie within both estimates of
    them, and the plan verifies. A figure stated as RK4's but moved beyond both estimates
    is named; so is one moved while stated as this version's. An RK4 replay that said no
    verdict (an estimate covering its value) is no figure to hold this version's to."""
    path = _changed(original, tmp_path, _as_rk4)
    code, _, err, _ = _run(capsys, "verify", path)
    assert code == 0, err
    made = ff.verify_plan(ff.Plan.load(path))
    assert made.passed and made["replay_joints"].detail.startswith("RK5, ")
    with pytest.raises(ff.PlanMismatchError, match="error_estimate"):  # as this version's
        compare_verification(ff.Plan.load(path).verification, made)

    def moved(name, value, tolerance):
        return 0.5 * tolerance if name == "replay_joints" else value

    line = _refused(capsys, "verify", _changed(original, tmp_path, lambda d: _as_rk4(d, moved)))
    assert "disagrees with the recomputation" in line and "verification.checks[" in line, line

    def unresolved(d):  # an RK4 replay that could not tell: its estimate covers its value
        _as_rk4(d)
        (check,) = [c for c in d["verification"]["checks"] if c["name"] == "replay_joints"]
        check.update(detail="RK4, 8192 steps, not converged: no verdict", value=3e-4)
        check["error_estimate"] = 5e-4

    code, _, err, _ = _run(capsys, "verify", _changed(original, tmp_path, unresolved))
    assert code == 0, err

    def tampered(d):
        (check,) = [c for c in d["verification"]["checks"] if c["name"] == "replay_joints"]
        check["value"] = 0.5 * check["tolerance"]

    line = _refused(capsys, "verify", _changed(original, tmp_path, tampered))
    assert "disagrees with the recomputation" in line and "verification.checks[" in line, line
