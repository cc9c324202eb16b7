"""A robot whose guessed matrix leads its optimal gaits through states its hardware cannot make:
the build leaves those directions out (it refused the robot, and with it proleg learn and
load-gait --sim, which build the same firmware); learning never asks for a transition the
hardware cannot make and writes it "x"; a START of the left-out direction is still refused,
with the reason."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from proleg.cli.main import main
from proleg.firmware.gaits import firmware_gaits
from proleg.learn.makeable import impossible, makeable_robot
from proleg.robot import load_robot

#: Limbs a and b on one coil (in the model it sits at a and bends b to 8.1°, short of its 21°
#: entry edge: every state with b raised is out of reach), c on a coil of its own. The guessed
#: matrix rewards the way through those states most; the square 000 100 101 001 the hardware
#: can make walks +x too, by less.
ROBOT = """\
[robot]
name = "shared-two"
description = "two limbs on one coil, one on its own (made up)"

[[limb]]
name = "a"
psi_star_deg = [20.0]
actuator = "c0"

[[limb]]
name = "b"
psi_star_deg = [20.0]
actuator = "c0"

[[limb]]
name = "c"
psi_star_deg = [20.0]
actuator = "c1"

[[actuator]]
name = "c0"
channel = 0

[[actuator]]
name = "c1"
channel = 1

[transitions]
units = "steps"
default_duration_s = 0.8
matrix = [
  [0, -1, 0, "x", 1, "x", "x", "x"],
  [1, 0, "x", -1, "x", 1, "x", "x"],
  [0, "x", 0, -1, "x", "x", 1, "x"],
  ["x", 1, 1, 0, "x", "x", "x", 0],
  [-1, "x", "x", "x", 0, 0, 3, "x"],
  ["x", 0, "x", "x", 1, 0, "x", 0],
  ["x", "x", -1, "x", -1, "x", 0, 3],
  ["x", "x", "x", 3, "x", 0, 0, 0],
]

[safety]
max_on_ms = 8000
min_cooldown_ms = 800
max_duty = 0.8
state_timeout_ms = 8000
"""


def _robot_file(tmp_path: Path) -> Path:
    path = tmp_path / "shared-two.toml"
    path.write_text(ROBOT, encoding="utf-8")
    return path


def test_the_made_up_robot_is_one_whose_gait_0_cannot_be_made(tmp_path):
    robot = load_robot(_robot_file(tmp_path))
    fw = firmware_gaits(robot)
    assert fw["+x"] == () and "+x" in fw.left_out and "which the robot cannot reach" in fw.left_out["+x"]
    t = robot.transitions
    gone = {(t.label(int(t.src[e])), t.label(int(t.dst[e]))) for e in impossible(robot)}
    # into a state with b up (unreachable, or raising b alone on the shared coil), and out of one
    assert ("000", "010") in gone and ("100", "110") in gone and ("110", "100") in gone
    kept = makeable_robot(robot).transitions
    assert {(kept.label(a), kept.label(b)) for a, b in zip(kept.src.tolist(), kept.dst.tolist())} == {
        ("000", "001"), ("000", "100"), ("001", "000"), ("001", "101"),
        ("100", "000"), ("100", "101"), ("101", "001"), ("101", "100")}


def test_load_gait_sim_loads_a_gait_the_hardware_can_make(tmp_path, capsys):
    path = _robot_file(tmp_path)
    assert main(["load-gait", str(path), "000,100,101,001", "--sim"]) == 0
    out = capsys.readouterr().out
    assert "loaded 000 → 100 → 101 → 001 → 000 as the user gait on sim shared-two" in out


def test_learn_sim_explores_what_the_hardware_can_make_and_forbids_the_rest(tmp_path, capsys):
    path = _robot_file(tmp_path)
    log, out = tmp_path / "t.jsonl", tmp_path / "learned.toml"
    assert main(["learn", str(path), "--sim", "--plant", "table", "--repeats", "2", "--log", str(log), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    said, report = captured.err, captured.out
    assert ("24 allowed transitions, 16 of them impossible on this hardware, not asked for (000->010, 001->011, "
            "010->000, 010->011, 010->110, … (11 more); 000->010: raises 'b' but not 'a', which share actuator "
            "'c0'") in said
    assert ": 8 × 2 = 16 trials" in said
    trials = [json.loads(line) for line in log.read_text().splitlines()[1:]]
    asked = {(tr["from"], tr["to"]) for tr in trials}
    assert len(trials) >= 16 and not [x for x in asked if "1" == x[1][1]]  # never b up
    assert "000->010   0         -        -     impossible here" in report
    assert "impossible on this hardware, not asked for (marked \"x\" in the learned file): 16 of 24" in report
    assert "too few trials" not in report

    learned = tomllib.loads(out.read_text())["transitions"]
    assert learned["matrix"][0][2] == "x" and learned["matrix"][4][6] == "x" and learned["matrix"][6][4] == "x"
    assert learned["matrix"][0][4] == pytest.approx(4.0)  # 1 step of 4 mm, measured on the table plant
    assert "# forbidden (\"x\") now: the hardware cannot make them" in out.read_text()
    # the learned file's gaits are ones the hardware makes: the build carries them again
    fw = firmware_gaits(load_robot(out))
    assert not fw.left_out and fw["+x"]  # (no cycle of the learned matrix walks -x)
    b_up = {2, 3, 6, 7}
    assert not [g for d in ("+x", "-x") for g in fw[d] if b_up & set(g.states)]


def test_start_of_the_left_out_direction_is_still_refused(tmp_path, capsys):
    """The user asks for gait 0 of +x: proleg sim refuses it with the reason, and the firmware,
    which carries no +x gait, refuses START with NACK NO_GAIT that the host explains."""
    from proleg.learn.simulated import simulated_robot
    from proleg.link.client import CommandRefused
    from proleg.protocol.definition import ErrorCode

    path = _robot_file(tmp_path)
    assert main(["sim", str(path), "--duration", "5"]) == 2
    err = capsys.readouterr().err
    assert (f"proleg: error: --gait 0 of +x: {path}: +x: none of its optimal gaits can run on this robot (the "
            "best-ranked, gait 010 110 111 011 010: goes to states 110 (step 1)") in err
    assert "which the robot cannot reach on the simulated body" in err
    assert "the firmware carries no +x gait (START +x is refused: NACK NO_GAIT)" in err

    _sim, client, _pose = simulated_robot(load_robot(path))
    with client:
        client.connect()
        with pytest.raises(CommandRefused) as refused:
            client.start(0, "+x")
    assert refused.value.error == ErrorCode.NO_GAIT
    assert "the board has no gait 0 in that direction" in str(refused.value)
    assert "a direction whose optimal gaits the hardware cannot make is left out" in str(refused.value)
