"""``proleg check``: the firmware under random operating conditions (``report.sweep``), and
its verdicts: a row the coils can walk that the firmware does not complete, or a stop that
cooked a coil, fails the check (exit 1)."""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from build_checks import cli as run
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.cli.main import main
from proleg.errors import SimError
from proleg.report import sweep
from proleg.robot import load_robot
from proleg.sim.closed_loop import make_plant

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
R1 = ROBOTS / "paper-r1.toml"


def _row(**kw) -> sweep.Row:
    base = dict(conditions=("power=0.9",), possible=True, why_not="", idealised_mm_s=0.4, completed=True,
                speed_mm_s=0.35, fault="", note="", coil_peak_c=80.0, reported="")
    return sweep.Row(**{**base, **kw})


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32), n=st.integers(1, 6),
       robot=st.sampled_from(["paper-r1", "caterpillar-4", "inchworm-3", "planar-4"]))
def test_every_drawn_row_is_a_condition_the_plant_takes(seed, n, robot):
    """Distinct keys, limbs of the robot, values inside each key's documented range: the plant
    takes every row (an out-of-range value would be a SimError)."""
    r = load_robot(ROBOTS / f"{robot}.toml")
    limbs = [limb.name for limb in r.limbs]
    rows = sweep.draw_rows(n, seed, limbs)
    assert rows == sweep.draw_rows(n, seed, limbs)  # seeded: the same rows again
    for row in rows:
        keys = [c.partition("=")[0] for c in row]
        assert len(row) == sweep.KEYS_PER_ROW and len(set(keys)) == len(keys)
        for c in row:
            value = c.partition("=")[2]
            if ":" in value:
                assert value.partition(":")[0] in limbs
        make_plant(r, "physical", list(row))


def test_keys_given_for_every_row_are_not_drawn():
    rows = sweep.draw_rows(40, 5, ["a", "b"], leave_out=("power", "ambient_c"))
    keys = {c.partition("=")[0] for row in rows for c in row}
    assert not keys & {"power", "ambient_c"} and len(keys) > 5


@pytest.mark.parametrize("kw, verdict, failed", [
    ({}, "ok", False),
    ({"completed": False, "fault": "STATE_TIMEOUT"}, "missed", True),
    ({"completed": False, "note": "coil overheated (130 °C)", "coil_peak_c": 130.0}, "missed", True),
    ({"possible": False, "completed": False, "fault": "STATE_TIMEOUT", "coil_peak_c": 90.0}, "clean stop", False),
    ({"possible": False, "completed": False, "fault": "SMA_ON_LIMIT", "coil_peak_c": 121.0}, "hot stop", True),
    ({"possible": False, "idealised_mm_s": None}, "walked", False),
])
def test_the_verdict_of_a_row(kw, verdict, failed):
    row = _row(**kw)
    assert row.verdict == verdict and row.failed is failed
    assert row.to_json()["verdict"] == verdict


def test_check_runs_the_drawn_rows_on_the_firmware(capsys):
    rc, out, err = run(capsys, "check", str(R1), "--rows", "2", "--seed", "4", "--jobs", "1", "--json")
    report = json.loads(out)
    assert rc == 0 and report["ok"] and report["errors"] == []
    assert [tuple(r["conditions"]) for r in report["rows"]] == sweep.draw_rows(2, 4, ["left", "right"])
    assert report["summary"]["rows"] == 2 and report["run_s"] >= 40
    for r in report["rows"]:  # R1 walks these rows: each is a real run of the firmware
        assert r["verdict"] in ("ok", "walked", "clean stop") and 0 < r["coil_peak_c"] < 120
    assert "row 2 of 2" in err


def test_a_limb_named_with_spaces_at_its_ends_is_found_by_the_checks_own_draws(capsys, tmp_path):
    """A robot file may name a limb " left" (any printable text). A condition reads KEY=NAME:value
    with NAME stripped, so check's own draw power_scale= left:0.85 was "no actuator 'left'"
    (exit 2, no row run), and --condition could not name the limb at all."""
    text = R1.read_text()
    assert text.count('name = "left"') == 1 and text.count('name = "right"') == 1
    path = tmp_path / "spaced.toml"
    path.write_text(text.replace('name = "left"', 'name = " left"').replace('name = "right"', 'name = "right "'))
    rows = sweep.draw_rows(2, 1, [" left", "right "])
    assert any(": left:" in c or "=right :" in c for c in rows[1]), rows  # a per-limb key, named as drawn
    rc, out, err = run(capsys, "check", str(path), "--rows", "2", "--seed", "1", "--jobs", "1", "--json")
    assert rc == 0, err
    assert [tuple(r["conditions"]) for r in json.loads(out)["rows"]] == rows
    robot = load_robot(path)
    plant = make_plant(robot, "physical", ["imu_bias_deg= left:3", "power_scale=right :0.9"])
    assert plant.conditions.for_index("imu_bias_deg", 0, [lb.name for lb in robot.limbs]) == 3.0
    # two names alike but for their spaces: which one is meant cannot be told, so neither is taken
    both = tmp_path / "alike.toml"
    both.write_text(path.read_text().replace('name = "right "', 'name = "left "'))
    with pytest.raises(SimError, match=r"'left' names ' left', 'left ' alike .*give the index instead"):
        make_plant(load_robot(both), "physical", ["imu_bias_deg=left:3"])


def test_rows_run_in_this_process_are_as_quiet_as_a_pools(capsys):
    """--jobs 1 (or --rows 1, or a one-core machine) runs the rows in this process: seed 1's
    first row (power=1.00) printed the plant's advice for the robot file ("coil 'sma-right' ...
    would settle at 156 °C with this supply ... lower the supply") twice, where the same row in a
    pool's worker printed nothing; the progress lines still show."""
    rc, _, err = run(capsys, "check", str(R1), "--rows", "1", "--seed", "1", "--jobs", "1")
    assert rc == 0 and "row 1 of 1: ok" in err
    assert "warning" not in err, err
    assert logging.root.manager.disable == logging.NOTSET  # and logging is as it was after


def test_base_conditions_go_into_every_row(capsys):
    rc, out, _ = run(capsys, "check", str(R1), "--rows", "2", "--jobs", "1", "--json", "--condition", "power=0.9")
    report = json.loads(out)
    assert rc == 0
    for r in report["rows"]:
        assert r["conditions"][0] == "power=0.9"
        assert not any(c.startswith("power=") for c in r["conditions"][1:])


def test_what_the_robot_file_says_the_robot_is_is_not_drawn(capsys, monkeypatch, tmp_path):
    """A 15 g robot with worn coils is checked as that robot: its file's mass_g and
    fatigue_cycles are held, not replaced by draws about the paper robot's; the environment
    (power, ambient, ...) is still drawn, and a robot file without them draws them as before."""
    seen = []

    def fake(robot, conditions, run_s, **kw):
        seen.append(tuple(conditions))
        return _row(conditions=tuple(conditions))
    monkeypatch.setattr(sweep, "run_row", fake)
    mine = tmp_path / "heavy.toml"
    mine.write_text(R1.read_text() + "\n[plant]\nmass_g = 15\nfatigue_cycles = 25000\n")
    for path, held in ((mine, ["fatigue_cycles", "mass_g"]), (R1, [])):
        seen.clear()
        rc, out, _ = run(capsys, "check", str(path), "--rows", "40", "--seed", "3", "--jobs", "1", "--json")
        assert rc == 0 and json.loads(out)["held"] == held
        drawn = {c.partition("=")[0] for row in seen for c in row}
        assert drawn.isdisjoint(held) and "power" in drawn
        if not held:
            assert {"mass_g", "fatigue_cycles"} <= drawn  # seed 3 draws both in 40 rows


def test_a_missed_row_fails_the_check_and_says_which(capsys, monkeypatch):
    def fake(robot, conditions, run_s, **kw):
        hot = "power=" in " ".join(conditions)
        return _row(conditions=tuple(conditions), completed=not hot, fault="SMA_ON_LIMIT" if hot else "")
    monkeypatch.setattr(sweep, "run_row", fake)
    rc, out, err = run(capsys, "check", str(R1), "--rows", "8", "--jobs", "1")
    drawn = sweep.draw_rows(8, 1, ["left", "right"])
    bad = [i + 1 for i, row in enumerate(drawn) if any(c.startswith("power=") for c in row)]
    assert bad, "seed 1 draws power in some of its first 8 rows"
    assert rc == 1
    for i in bad:
        assert f"proleg: error: row {i} (" in err and "SMA_ON_LIMIT" in err
    assert f"missed {len(bad)}" in out


def test_a_gait_that_does_not_walk_on_the_plant_cannot_be_checked(capsys):
    """R3's matrix (the paper's) says gait 0 walks +x; on the physical plant it walks −x."""
    rc, _, err = run(capsys, "check", str(ROBOTS / "paper-r3.toml"), "--rows", "1", "--jobs", "1")
    assert rc == 1 and "cannot be checked on the nominal plant" in err and "--measure-matrix" in err


def test_a_gait_the_idealised_drive_moves_by_noise_only_cannot_be_checked(capsys, monkeypatch):
    """A six-limb robot's gait 0: the idealised drive moved it +0.0002 mm a cycle (+0.0001 mm/s,
    the plant's noise). The check went on, every row where the firmware drifted back 0.01 mm/s was
    "missed ... where the idealised drive walks +0.000 mm/s", exit 1 blaming the firmware; -0.0002
    would have said that nothing walks the gait. Under 0.001 mm a cycle (a run that "did not
    move", proleg sim's NOTE) it cannot be checked either way."""
    from proleg.report import claim

    def barely(*_a, **_kw):
        return claim.IdealisedWalk(True, "", 0.0001, 1.7)
    monkeypatch.setattr(claim, "idealised_walk", barely)
    monkeypatch.setattr(sweep, "run_row", lambda *a, **kw: pytest.fail("a row was run"))
    rc, _, err = run(capsys, "check", str(R1), "--rows", "2", "--jobs", "1")
    assert rc == 1 and "cannot be checked on the nominal plant" in err, err
    assert "even an ideal drive (true ψ) moves +0.0002 mm per cycle (under 0.001 mm: no motion)" in err


@pytest.mark.parametrize("argv, says", [
    (["--condition", "power=9"], "power"),
    (["--condition", "no_such_key=1"], "no_such_key"),
    (["--gait", "7"], "--gait 7"),
])
def test_bad_arguments_are_usage_errors(capsys, argv, says):
    rc, _, err = run(capsys, "check", str(R1), "--jobs", "1", *argv)
    assert rc == 2 and says in err and "Traceback" not in err


def test_rows_out_of_range_are_refused_by_the_parser(capsys):
    for n in ("0", "1001"):
        with pytest.raises(SystemExit) as e:
            main(["check", str(R1), "--rows", n])
        assert e.value.code == 2 and "--rows" in capsys.readouterr().err


def test_a_ctrl_c_names_the_options_that_run_the_same_rows_again(capsys, monkeypatch):
    """The line a Ctrl-C leaves said "--rows N --seed S runs them again": without the
    --condition keys (left out of the draws) and the way, that drew other rows under other
    conditions; under -q it also pointed at progress lines that were never printed."""
    calls = []

    def fake(robot, conditions, run_s, **kw):
        calls.append(conditions)
        if len(calls) == 4:  # the nominal row, two drawn rows, then Ctrl-C
            raise KeyboardInterrupt
        return _row(conditions=tuple(conditions))
    monkeypatch.setattr(sweep, "run_row", fake)
    argv = ["check", str(R1), "--rows", "9", "--seed", "5", "--jobs", "1", "--condition", "power=0.9"]
    rc, out, err = run(capsys, *argv)
    line = err.strip().splitlines()[-1]
    assert rc == 130 and out == "" and "Traceback" not in err
    assert "--rows 2 --seed 5 --condition power=0.9 runs them again" in line and "stderr above" in line
    again = line.split("nothing written: ")[1].split("; ")[-1].removesuffix(" runs them again)").split()
    assert calls[0] == ("power=0.9",)  # the nominal row: --condition alone
    assert sweep.draw_rows(2, 5, ["left", "right"], leave_out=("power",)) == [c[1:] for c in calls[1:3]]
    assert again[again.index("--condition") + 1] == "power=0.9"
    calls.clear()
    rc, _, err = run(capsys, "-q", *argv)
    assert rc == 130 and "stderr above" not in err.strip().splitlines()[-1]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_a_check_and_its_workers(sig):
    """Ctrl-C (or a CI job's timeout) mid-check: exit 130 / 143 with one line, and the worker
    processes end too (a worker forked from proleg turned SIGTERM into an ignored Ctrl-C, so the
    pool could not end it and the check ran on)."""
    from test_interrupted import _AS_FROM_A_TERMINAL

    env = {**os.environ, "PYTHONPATH": str(ROBOTS.parent / "host" / "src")}
    proc = subprocess.Popen([sys.executable, "-c", _AS_FROM_A_TERMINAL, "check", "caterpillar-4", "--rows", "200",
                             "--jobs", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not _children(proc.pid):
            time.sleep(0.2)
        workers = _children(proc.pid)
        assert workers, "the pool started"
        time.sleep(0.5)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == (130 if sig == signal.SIGINT else 128 + sig), err
    assert out == "" and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("proleg: interrupted after ")
    time.sleep(0.2)
    assert not [w for w in workers if Path(f"/proc/{w}").exists() and "Z" not in _state(w)]


def _children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"


def test_check_runs_the_exact_nano_image_on_avr_emu(capsys):
    """--board avr-emu: the rows on the arduino-nano firmware.elf (simavr), the MCU's own clock;
    the same row as on host-sim walks within a few percent (the same C, another compiler)."""
    from proleg.sim.simulated_boards import simulated_board

    lacking = simulated_board("avr-emu").missing()
    if lacking:
        pytest.skip(lacking)
    rc, out, _ = run(capsys, "check", str(R1), "--rows", "1", "--seed", "2", "--jobs", "1", "--board", "avr-emu",
                     "--json")
    emu = json.loads(out)
    rc_host, out_host, _ = run(capsys, "check", str(R1), "--rows", "1", "--seed", "2", "--jobs", "1", "--json")
    host = json.loads(out_host)
    assert rc == rc_host == 0 and emu["board"] == "avr-emu" and host["board"] == "host-sim"
    (e,), (h,) = emu["rows"], host["rows"]
    assert e["conditions"] == h["conditions"] and e["verdict"] == h["verdict"] == "ok"
    assert e["speed_mm_s"] == pytest.approx(h["speed_mm_s"], rel=0.15)


def test_each_row_is_measured_against_a_nominal_row_run_first(capsys):
    """Row 0 runs the firmware under --condition alone: each drawn row's speed is reported as a
    share of it, and the summary counts the rows that keep 75 % of it (reported, not a failure)."""
    rc, out, _ = run(capsys, "check", str(R1), "--rows", "2", "--seed", "4", "--jobs", "1", "--json")
    report = json.loads(out)
    nominal = report["nominal"]
    assert rc == 0 and nominal["conditions"] == [] and nominal["verdict"] == "ok" and nominal["speed_mm_s"] > 0
    assert len(report["rows"]) == 2 and report["summary"]["nominal_mm_s"] == nominal["speed_mm_s"]
    kept = sum(r["possible"] and r["completed"] and r["speed_mm_s"] >= 0.75 * nominal["speed_mm_s"]
               for r in report["rows"])
    assert report["summary"]["kept_75pct_of_nominal_where_possible"] == kept
    rc, out, _ = run(capsys, "check", str(R1), "--rows", "2", "--seed", "4", "--jobs", "1")
    shares = [line for line in out.splitlines() if "% of nominal" in line]
    assert len(shares) == 2 and "keep 75% of the nominal speed" in out


def test_a_nominal_row_the_firmware_does_not_complete_fails_the_check(capsys, monkeypatch):
    def fake(robot, conditions, run_s, **kw):
        return _row(conditions=tuple(conditions), completed=bool(conditions), fault="" if conditions else "STATE_TIMEOUT")
    monkeypatch.setattr(sweep, "run_row", fake)
    rc, _, err = run(capsys, "check", str(R1), "--rows", "3", "--jobs", "1")
    assert rc == 1 and "proleg: error: the nominal row (none drawn): the firmware did not complete the gait (STATE_TIMEOUT)" in err


def test_the_nominal_row_reuses_the_idealised_walk_that_set_the_run_length(capsys, monkeypatch):
    """The idealised drive's walk on the nominal plant (which sets every row's run length) is
    that row's verdict too: it is run once, not again for row 0 (caterpillar-4: 2.6 s)."""
    from proleg.report import claim

    walks: list = []
    real_walk = claim.idealised_walk
    monkeypatch.setattr(claim, "idealised_walk", lambda *a, **kw: walks.append(a[1].conditions) or real_walk(*a, **kw))
    given: list = []

    def fake(robot, conditions, run_s, *, ideal=None, **kw):
        given.append((tuple(conditions), ideal))
        return _row(conditions=tuple(conditions), possible=ideal.possible if ideal else True)
    monkeypatch.setattr(sweep, "run_row", fake)
    rc, _, _ = run(capsys, "check", str(R1), "--rows", "2", "--jobs", "1")
    assert rc == 0
    assert walks == [()]  # the nominal walk, once
    assert given[0][0] == () and isinstance(given[0][1], claim.IdealisedWalk) and given[0][1].possible
    assert [ideal for _, ideal in given[1:]] == [None, None]  # drawn rows walk their own conditions


@pytest.mark.parametrize("idealised, fails", [(0.001, False), (0.3, True)])
def test_a_row_the_gait_barely_moves_in_is_not_missed_for_drifting_back(capsys, monkeypatch, idealised, fails):
    """Where the idealised drive makes less than 5 % of its nominal speed the gait does not
    carry the robot: a firmware run there that drifts back without a fault and cool is
    "drifted", not a miss (a lab's CI does not fail on the plant's noise); the same drift where
    the idealised drive walks is a miss."""
    def fake(robot, conditions, run_s, **kw):
        if not conditions:
            return _row(conditions=(), idealised_mm_s=0.39)
        return _row(conditions=tuple(conditions), idealised_mm_s=idealised, completed=False, speed_mm_s=-0.002,
                    note="walks the wrong way (no fault)")
    monkeypatch.setattr(sweep, "run_row", fake)
    rc, out, err = run(capsys, "check", str(R1), "--rows", "2", "--jobs", "1", "--json")
    rows = json.loads(out)["rows"]
    assert [r["verdict"] for r in rows] == ["missed" if fails else "drifted"] * 2
    assert rc == (1 if fails else 0) and ("did not complete the gait (walks the wrong way" in err) == fails
    rc, out, _ = run(capsys, "check", str(R1), "--rows", "2", "--jobs", "1")
    assert ("drifted back where the gait barely moves in 2" in out) != fails


def test_a_drift_with_a_fault_or_a_hot_coil_is_still_missed_where_the_gait_barely_moves():
    drift = dict(possible=True, idealised_mm_s=0.001, completed=False, note="walks the wrong way (no fault)",
                 barely_moves=True)
    assert _row(**drift).verdict == "drifted" and not _row(**drift).failed
    assert _row(**{**drift, "fault": "STATE_TIMEOUT"}).missed
    assert _row(**{**drift, "coil_peak_c": 125.0}).missed
    assert _row(**{**drift, "note": "only 1 cycles (no fault)"}).missed


def _printed(capsys, rows: list) -> str:
    """``proleg check``'s text report of a nominal row and ``rows``."""
    import argparse

    from proleg.cli import check

    args = argparse.Namespace(condition=[], board="host-sim", gait=0, direction="+x", seed=1)
    nominal = _row(conditions=(), coil_peak_c=80.0)
    summary = {**sweep.summary(rows), **check._kept(nominal, rows),
               "hottest_c": round(max(r.coil_peak_c for r in [nominal, *rows]), 1)}
    check._print(load_robot(R1), args, "00 10 11 01 00", 40.0, nominal, rows, summary)
    return capsys.readouterr().out


def test_the_hottest_coil_reads_the_same_in_its_row_and_the_summary(capsys):
    """A row whose coil peaked at 104.5012 °C read "coils ≤ 105 °C" and the summary "hottest coil
    104 °C" (rounded to 0.1 for --json first, then to the even degree); a coil at 120.3 °C read
    "≤ 120 °C" in a row the check failed as past 120 °C, and its error "120 °C, past the 120 °C"."""
    from proleg.cli import check

    out = _printed(capsys, [_row(coil_peak_c=104.5012)])
    assert "coils ≤ 105 °C" in out and "hottest coil 105 °C" in out, out
    hot = _row(possible=False, completed=False, fault="SMA_ON_LIMIT", coil_peak_c=120.3)
    out = _printed(capsys, [_row(coil_peak_c=104.5012), hot])
    assert "coils ≤ 120.3 °C" in out and "hottest coil 120.3 °C" in out, out
    assert "heated a coil to 120.3 °C, past the 120 °C" in check._error(2, hot)


def test_a_robot_the_emulated_board_cannot_carry_is_refused_before_the_nominal_walk(capsys, monkeypatch):
    """snake-8's eight coils on the Nano's four PWM channels: refused only after the nominal
    idealised walk (minutes on a long body), the build of the first row saying it."""
    from proleg.report import sweep
    from proleg.sim.simulated_boards import simulated_board

    lacking = simulated_board("avr-emu").missing()
    if lacking:
        pytest.skip(lacking)

    def walk(*_a, **_k):
        raise AssertionError("the nominal walk ran before the board was checked")

    monkeypatch.setattr(sweep, "run_length", walk)
    snake = Path(__file__).parent / "fixtures" / "snake-8.toml"
    rc, out, err = run(capsys, "check", str(snake), "--rows", "1", "--board", "avr-emu")
    assert rc == 2 and out == "" and "but board arduino-nano has 4 PWM channels" in err, err


def test_a_nominal_row_walked_far_slower_than_the_idealised_drive_is_noted():
    """Each row's share is of the firmware's own nominal speed, so a firmware crawling on the
    nominal plant passed unremarked (a lab's wedge: -0.062 mm/s against the idealised -0.56, rows
    at 869 % of nominal). The nominal row now says its share of the idealised drive, and a share
    under half is noted; a failed nominal row is an error already, not a note."""
    from proleg.cli import check

    slow = _row(conditions=(), idealised_mm_s=-0.56, speed_mm_s=-0.062)
    assert check._kept(slow, [])["nominal_share_of_idealised"] == pytest.approx(0.111, abs=1e-3)
    note = check._slow_nominal_note(slow)
    assert note.startswith("NOTE:") and "-0.062 mm/s, 11% of the idealised drive's -0.560" in note
    assert check._slow_nominal_note(_row(conditions=(), idealised_mm_s=0.39, speed_mm_s=0.36)) is None  # R1
    assert check._slow_nominal_note(_row(conditions=(), idealised_mm_s=0.4, speed_mm_s=0.1, completed=False)) is None
    none = _row(conditions=(), idealised_mm_s=None, possible=False)
    assert check._kept(none, [])["nominal_share_of_idealised"] is None and check._slow_nominal_note(none) is None
