"""``sim --measure-matrix`` keeps to the firmware's safety envelope: its idealised drive's
duties go through the duty ceiling, the on-time limit, the mean-duty window and the state
timeout (``sim/physical/envelope.py``), and a transition it could make only past them is not
measured, with the fault the firmware would latch named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from proleg.cli.main import main
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.physical import measure_matrix
from proleg.sim.closed_loop import plant_conditions

R1 = robots_dir() / "paper-r1.toml"


def _same(a, b) -> bool:
    return bool(np.array_equal(a.matrix_mm, b.matrix_mm, equal_nan=True)) and a.coil_peak_c == b.coil_peak_c


def test_a_duty_past_the_ceiling_is_measured_as_the_ceiling():
    """R1's max_duty is 0.8: asked for 1.0, the envelope clamps every heat to 0.8 (sma_clamp),
    so the measurement is the 0.8 one to the bit; the bare drive heats at 1.0, and its coils
    get hotter."""
    robot = load_robot(R1)
    assert robot.safety.max_duty == 0.8
    at_ceiling = measure_matrix(robot, repeats=1, duty=0.8)
    asked_more = measure_matrix(robot, repeats=1, duty=1.0)
    bare = measure_matrix(robot, repeats=1, duty=1.0, envelope=False)
    assert _same(at_ceiling, asked_more)
    assert not _same(at_ceiling, bare)
    assert max(bare.coil_peak_c.values()) > max(at_ceiling.coil_peak_c.values())
    assert not at_ceiling.latched and not bare.latched


def test_a_supply_that_cannot_make_the_steps_latches_the_firmwares_faults():
    """At 30 % of the heating power R1's coils, even boosted to max_duty, barely pass As: every
    transition ends in the fault the firmware would latch (the state timeout, or the on-time
    limit where a coil heats on for a state never reached), none is measured, and the bare
    drive latches nothing."""
    robot = load_robot(R1)
    weak = plant_conditions(robot, ["power=0.3"])
    m = measure_matrix(robot, weak, repeats=1)
    bare = measure_matrix(robot, weak, repeats=1, envelope=False, timeout_s=4.0)
    _, allowed = robot.transitions.dense()
    steps = {(a, b) for a in range(4) for b in range(4) if a != b and allowed[a][b]}
    assert set(m.latched) == steps
    assert set(m.latched.values()) <= {"STATE_TIMEOUT", "SMA_ON_LIMIT"}
    assert int(m.samples.sum()) == 0
    assert not bare.latched  # the bare drive heats on without a limit (12 s a try, here 4)


def test_the_command_names_the_latched_faults_and_fails(capsys):
    code = main(["sim", str(R1), "--measure-matrix", "--condition", "power=0.3", "--json"])
    out = capsys.readouterr()
    assert code == 1
    got = json.loads(out.out)
    assert set(got["latched"]) == set(got["not_made"]) and len(got["not_made"]) == 12
    assert "the safety envelope latched a fault on the way to each: STATE_TIMEOUT on 00->01" in out.err


def test_the_measuring_drive_boosts_as_the_firmware_does(tmp_path, capsys):
    """R1 at power=0.4: at the drive duty 0.6 its coils lag, and the firmware's boost (on by
    default on R1) heats a lagging rise at max_duty 0.8, with which it walks. The measuring drive
    boosts by the same rule, so it measures every transition there; without the boost
    (boost_ms = 0) both give up: every transition latches, and the firmware stops with a fault."""
    def run(path):
        measured = main(["sim", str(path), "--measure-matrix", "--condition", "power=0.4", "--json"])
        m = json.loads(capsys.readouterr().out)
        walked = main(["sim", str(path), "--condition", "power=0.4", "--duration", "40", "--json"])
        w = json.loads(capsys.readouterr().out)
        return measured, m, walked, w

    measured, m, walked, w = run(R1)
    assert measured == 0 and not m["latched"] and not m["not_made"]
    assert walked == 0 and w["cycles"] >= 2 and not w["faults"], w["faults"]
    off = tmp_path / "paper-r1.toml"
    off.write_text(R1.read_text(encoding="utf-8").replace("\n[control]\n", "\n[control]\nboost_ms = 0\n"),
                   encoding="utf-8")
    measured, m, walked, w = run(off)
    assert measured == 1 and len(m["latched"]) == 12
    assert w["cycles"] == 0 and w["faults"]



def test_a_shared_coil_heats_at_the_ceiling_only_for_a_boosted_limb_that_asks(tmp_path):
    """The firmware gives a coil its limbs' strongest want (ctl.c): WANT_HEAT + the boost of the
    limb that asks for heat. The idealised drive boosted a coil whenever it heated and some
    boosted limb sat on it: the one-actuator R1 (boost_ms = 700, drive_duty 0.6), its left end
    boosted once and held in its band, was heated at max_duty for the right end's rise, which
    the firmware heats at the drive duty."""
    from proleg.sim.physical.drive import IdealDrive
    from proleg.sim.physical.plant import PhysicalPlant

    text = (robots_dir() / "paper-r1-one-actuator.toml").read_text(encoding="utf-8")
    assert text.count("\ndrive_duty = 0.8 ") == 1
    path = tmp_path / "one-boosted.toml"
    path.write_text(text.replace("\ndrive_duty = 0.8 ", "\nboost_ms = 700\ndrive_duty = 0.6 "), encoding="utf-8")
    robot = load_robot(path)
    drive = IdealDrive(robot, PhysicalPlant(robot), 4.0)
    assert drive.boost_s == 0.7 and drive.th == [(20.0,), (20.0,)]
    drive.boosted = {0}                                   # the left end lagged once
    assert drive.command([26.0, 0.0], 3, 0.002) == [1]    # to 11: the right end rises, the left is in its band
    assert drive.boost_act == set()                       # heated for the right end: the drive duty
    assert drive.command([10.0, 0.0], 3, 0.002) == [1]    # the left end below its band asks too
    assert drive.boost_act == {0}


def test_latched_says_what_each_transitions_last_try_did(monkeypatch):
    """``latched`` names the fault of a transition's last try: a fault in the first repeat that
    a second repeat did not latch (it timed out, or was made) is not kept; and after a latch the
    drive starts unboosted, as the firmware's run after CLEAR and START."""
    from proleg.sim.physical import measure as measure_mod
    from proleg.sim.physical.envelope import EnvelopeLatched

    tries: dict[tuple[int, int], int] = {}
    boosted_after_latch = []

    def fake_run_to(plant, drive, target, *args):
        key = (fake_run_to.start, target)
        if fake_run_to.start is None:  # going to the start state
            fake_run_to.start = target
            return 0.1
        fake_run_to.start = None
        tries[key] = tries.get(key, 0) + 1
        if key == (0, 2) and tries[key] == 1:
            drive.boosted.add(0)
            raise EnvelopeLatched("SMA_ON_LIMIT", "test")
        if key == (0, 2):
            boosted_after_latch.append(set(drive.boosted))
            return None  # the second try times out: no fault, no sample
        if key == (1, 0) and tries[key] == 1:
            return None
        if key == (1, 0):
            raise EnvelopeLatched("STATE_TIMEOUT", "test")
        return 0.2

    def fake_to(plant, drive, target, *args):
        try:
            return fake_run_to(plant, drive, target, *args)
        except EnvelopeLatched:
            fake_run_to.start = None
            raise

    fake_run_to.start = None
    monkeypatch.setattr(measure_mod, "_run_to", fake_to)
    monkeypatch.setattr(measure_mod, "_rest", lambda plant, gate, dt_s: None)
    m = measure_matrix(load_robot(R1), repeats=2)
    assert m.latched == {(1, 0): "STATE_TIMEOUT"}
    assert boosted_after_latch == [set()]


def test_faults_on_every_transition_are_named_even_where_load_warnings_foresaw_some(capsys):
    """tri-mixed warns at load of a state its body cannot hold. At power=0.3 every one of its 40
    transitions latched a fault, and the error said 'the load warnings above say which states
    the body cannot hold': the faults are why, and it names them."""
    tri = Path(__file__).resolve().parent / "fixtures" / "tri-mixed.toml"
    code = main(["sim", str(tri), "--measure-matrix", "--condition", "power=0.3"])
    out = capsys.readouterr()
    assert code == 1
    assert "the safety envelope latched a fault on the way to each: STATE_TIMEOUT on 000->001" in out.err
    assert "the load warnings above say" not in out.err
    assert "its start or end state was not reached (the safety envelope latched a fault on its way: below)" in out.out
