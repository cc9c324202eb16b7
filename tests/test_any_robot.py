"""Any robot a lab builds: the example robots beyond the paper build where they fit and walk
both ways on the simulator; IMUs behind a multiplexer; entry from rest; the sim's flags;
plant defaults for more than two limbs; hil_tests --robot."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from build_checks import cli

from proleg.errors import BuildError, RobotFileError
from proleg.firmware.boards import load_board
from proleg.firmware.build import build
from proleg.firmware.gaits import firmware_gaits
from proleg.gait import evaluate_sequence
from proleg.protocol.codec import FrameDecoder
from proleg.protocol.definition import EventKind, FaultCode
from proleg.report import SimSession
from proleg.robot import load_robot
from proleg.sim.simulators import open_simulated

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ("inchworm-3", "caterpillar-4")


@pytest.mark.parametrize("name", EXAMPLES)
@pytest.mark.parametrize("direction", ["+x", "-x"])
def test_example_robot_walks_both_ways_on_the_simulator_without_faults(name, direction):
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    sim = open_simulated(robot, plant="table")  # the matrix is the truth here: the lookup plant
    session = SimSession(sim)
    session.advance(0.2)
    # caterpillar-4's gait 0 takes ~20 s a cycle on the table plant: a falling limb waits up
    # to CTL_SAG_WAIT_MS (500 ms) for each of its held, sagging neighbours at every step
    report = session.run_gait(direction, 0, 80.0)
    gait = firmware_gaits(robot)[direction][0]
    per_cycle = evaluate_sequence(robot.transitions, gait.states).reward
    assert report.faults == [] and report.errors == []
    assert report.cycles >= 3
    assert sim.plant.unexpected_transitions == 0
    sign = 1 if direction == "+x" else -1
    assert all(sign * d > 0 for d in report.cycle_displacements_mm)
    assert report.mean_cycle_mm == pytest.approx(per_cycle * sim.plant.params.step_mm)


def test_the_inchworm_matrix_is_in_mm_and_the_simulator_honours_it():
    robot = load_robot(ROOT / "robots" / "inchworm-3.toml")
    assert robot.units == "mm" and robot.plant.step_mm == 1.0
    sim = open_simulated(robot, plant="table")  # the matrix is the truth here: the lookup plant
    session = SimSession(sim)
    session.advance(0.2)
    report = session.run_gait("+x", 0, 20.0)
    assert report.cycle_displacements_mm and all(d == pytest.approx(12.0) for d in report.cycle_displacements_mm)


def test_a_robot_too_big_for_the_tick_is_refused_with_the_reason(tmp_path):
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text().replace("tick_hz = 500", "tick_hz = 1000")
    path = tmp_path / "caterpillar-fast.toml"
    path.write_text(text)
    # Either of the Nano's two limits says so: its measured tick budget ([budget], enforced)
    # or the I2C time of four IMU reads.
    with pytest.raises(BuildError, match=r"control.tick_hz = 1000 is too fast for board arduino-nano: 4 limbs need"
                                         r"|reading 4 IMUs \(2 channel switches\) takes about 940 us .* arduino-nano"):
        build(load_robot(path), load_board("arduino-nano"), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def _placed_behind_mux(tmp_path) -> Path:
    """inchworm-3 with its IMUs placed by hand: tail direct on sim0, middle and head behind
    the multiplexer of sim1 on channels 2 and 5, both at 0x68."""
    text = (ROOT / "robots" / "inchworm-3.toml").read_text()
    places = {
        "tail": 'imu = { bus = "sim0", address = 0x68 }',
        "middle": 'imu = { bus = "sim1", mux = 0x73, channel = 2, address = 0x68 }',
        "head": 'imu = { bus = "sim1", channel = 5, address = 0x68 }',
    }
    for limb, line in places.items():
        text = text.replace(f'name = "{limb}"\n', f'name = "{limb}"\n{line}\n', 1)
    path = tmp_path / "inchworm-mux.toml"
    path.write_text(text)
    return path


def test_imus_behind_a_multiplexer_walk_and_faults_still_name_limbs(tmp_path):
    robot = load_robot(_placed_behind_mux(tmp_path))
    sim = open_simulated(robot, plant="table")  # the matrix is the truth here: the lookup plant
    assert sim.imu_addresses == (0x68, 0x81, 0x82)
    lib = sim.board._lib
    session = SimSession(sim)
    session.advance(0.2)
    report = session.run_gait("+x", 0, 15.0)
    assert report.faults == [] and report.cycles >= 2
    # two IMUs share 0x68 on sim1: every tick switches channel 2 -> 5 -> 2
    import ctypes

    lib.sim_mux_switches.restype = ctypes.c_uint32
    lib.sim_mux_control.restype = ctypes.c_uint8
    lib.sim_mux_control.argtypes = [ctypes.c_uint8, ctypes.c_uint8]
    before = lib.sim_mux_switches()
    sim.run_ticks(10)
    assert lib.sim_mux_switches() - before == 20
    assert lib.sim_mux_control(1, 0x73) in (1 << 2, 1 << 5)
    sim.board.read()
    sim.inject("imu-silent:head")
    sim.run_ticks(50)
    msgs = FrameDecoder().feed(sim.board.read())
    faults = [m for m in msgs if m.name == "EVENT" and m.kind == EventKind.FAULT]
    assert any(f.code == FaultCode.IMU_NO_ACK and f.detail == 2 for f in faults), faults  # limb 2 = head
    assert all(sim.board.pwm(ch) == 0.0 for ch in sim.channels)


def test_sim_takes_board_objective_and_max_transitions(capsys):
    code, _, err = cli(capsys, "sim", ROOT / "robots" / "paper-r1.toml", "--board", "avr-emu", "--objective", "rate",
                       "--duration", "1")
    assert code == 2 and "board 'avr-emu': --objective and --max-transitions are host-sim's" in err
    code, out, _ = cli(capsys, "sim", ROOT / "robots" / "caterpillar-4.toml", "--board", "host-sim",
                       "--objective", "rate", "--duration", "30", "--plant", "table", "--json")
    report = json.loads(out)
    assert code == 0 and report["board"] == "host-sim" and report["cycles"] >= 1 and report["faults"] == []
    code, out, _ = cli(capsys, "sim", ROOT / "robots" / "paper-r2.toml", "--max-transitions", "4",
                       "--duration", "8", "--plant", "table", "--json")
    assert code == 0 and json.loads(out)["cycles"] >= 1


def test_build_prints_the_imu_placement(capsys, tmp_path):
    code, out, _ = cli(capsys, "build", ROOT / "robots" / "inchworm-3.toml", "--board", "bluepill-f103",
                       "-o", tmp_path / "fw")
    assert code == 0
    assert "limb head: IMU at 0x68 on bus I2C2 (automatic)" in out
    assert "I2C per tick: about 630 us (3 IMU reads, 0 multiplexer channel switches)" in out
    manifest = json.loads((tmp_path / "fw" / "proleg-build.json").read_text())
    assert manifest["imu_placement"][2] == {"limb": "head", "bus": "I2C2", "mux": None, "channel": None,
                                            "address": 0x68, "automatic": True}
    config = (tmp_path / "fw" / "gen" / "robot_config.h").read_text()
    assert "#define CFG_LIMB_IMU_BUS { 0, 0, 1 }" in config and "#define CFG_I2C_BUSES 2u" in config


def test_more_than_two_limbs_get_a_coupling_from_their_geometry(tmp_path):
    robot = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    g = robot.plant.coupling_deg
    assert g is not None and [row[i] for i, row in enumerate(g)] == [60.0] * 4
    for i, row in enumerate(g):  # the cross shares sum to cross_gain_deg and fall off with distance
        others = [x for j, x in enumerate(row) if j != i]
        assert sum(others) == pytest.approx(12.0, abs=0.01)
    assert g[0][1] > g[0][2] > g[0][3]
    assert load_robot(ROOT / "robots" / "paper-r1.toml").plant.coupling_deg is None  # the paper's two limbs: unchanged


def test_step_mm_is_refused_when_the_matrix_is_in_mm(tmp_path):
    text = (ROOT / "robots" / "inchworm-3.toml").read_text().replace("cross_gain_deg = 12.0", "step_mm = 2.0")
    path = tmp_path / "mm.toml"
    path.write_text(text)
    with pytest.raises(RobotFileError, match=r"plant.step_mm: expected 1 \(or no step_mm\) when transitions.units = \"mm\""):
        load_robot(path)


@pytest.mark.parametrize("units, step_mm", [("mm", 1.0), ("cm", 10.0), ("m", 1000.0), ("steps", 4.0)])
def test_a_length_unit_sets_the_table_plants_millimetres_per_entry(tmp_path, units, step_mm):
    text = (ROOT / "robots" / "paper-r1.toml").read_text().replace('units = "steps"', f'units = "{units}"')
    path = tmp_path / f"{units}.toml"
    path.write_text(text)
    robot = load_robot(path)
    assert robot.units == units and robot.plant.step_mm == step_mm


def test_a_unit_that_is_neither_steps_nor_a_length_is_refused(tmp_path):
    """"millimetres" used to count as steps of 4 mm: the table plant walked 4× too far."""
    path = tmp_path / "bad.toml"
    path.write_text((ROOT / "robots" / "paper-r1.toml").read_text().replace('units = "steps"', 'units = "millimetres"'))
    with pytest.raises(RobotFileError, match=r"transitions.units: expected one of 'steps', 'mm', 'cm', 'm'.*'millimetres'"):
        load_robot(path)


def test_hil_tests_run_on_the_robot_given_with_robot():
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:xdist", str(ROOT / "hil_tests"),
         "--robot", str(ROOT / "robots" / "inchworm-3.toml"), "--board", "host-sim"],
        capture_output=True, text=True, cwd=ROOT,
    ).stdout
    ids = [line for line in out.splitlines() if "::" in line]
    gait_ids = [i for i in ids if "measured_matrix_rate" in i]
    assert gait_ids and all("inchworm-3" in i for i in gait_ids)
    assert not any("paper-r" in i for i in ids)


def _worm(tmp_path: Path, n: int) -> Path:
    """An n-limb binary worm (one coil per limb, single-limb transitions, the example
    robots' sliding rule), its 2^n-state table in a CSV file."""
    parts = [f'[robot]\nname = "worm-{n}"\n']
    parts += [f'[[limb]]\nname = "l{i + 1}"\npsi_star_deg = [20.0]\nactuator = "a{i + 1}"\n' for i in range(n)]
    parts += [f'[[actuator]]\nname = "a{i + 1}"\nchannel = {i}\n' for i in range(n)]
    parts += ['[transitions]\nfile = "worm.csv"\ndefault_duration_s = 0.8\n',
              "[control]\ntick_hz = 250\ntelemetry_hz = 10\nhold_duty = 0.0\n"]
    rows = ["from,to,reward"]
    for a in range(1 << n):
        grip = [1 - ((a >> (n - 1 - j)) & 1) for j in range(n)]
        for i in range(n):
            b = a ^ (1 << (n - 1 - i))
            d = sum(grip[i + 1:]) - sum(grip[:i])
            d = d if b > a else -d
            rows.append(f"@{a},@{b},{(d > 0) - (d < 0)}")
    (tmp_path / "worm.csv").write_text("\n".join(rows) + "\n")
    path = tmp_path / "worm.toml"
    path.write_text("\n".join(parts))
    return path


def test_eight_binary_limbs_build_for_the_bluepill_and_the_nano_says_why_not(tmp_path):
    robot = load_robot(_worm(tmp_path, 8))
    assert robot.n_states == 256
    result = build(robot, load_board("bluepill-f103"), tmp_path / "bp")
    assert result.flash_used < 65536 and len(result.fit.placements) == 8
    assert result.fit.flash_estimate is not None and abs(result.fit.flash_estimate - result.flash_used) < 4096
    with pytest.raises(BuildError, match=r"actuator 'a5' is on channel = 4, but board arduino-nano has 4 PWM channels: channel = 0 \(D9\)"):
        build(robot, load_board("arduino-nano"), tmp_path / "nano")


def test_a_five_limb_robot_without_friction_takes_d1_says_so_and_walks(tmp_path, capsys, caplog):
    """More than four limbs: the plant does not sweep the 2^n D1/D2 assignments (3.5 min for
    five limbs, hours for eight) but takes D1, warns once when the file is loaded, and the
    robot walks (with three of its five limbs raised, a fourth rises: the body has turned
    more than 180 deg in all, which the contact angles once read 180 deg off)."""
    from proleg.sim.physical.plant import PhysicalPlant

    path = _worm(tmp_path, 5)
    with caplog.at_level("WARNING"):
        robot = load_robot(path)
    warned = [r.getMessage() for r in caplog.records if "friction" in r.getMessage()]
    assert len(warned) == 1 and "5 limbs" in warned[0] and 'friction = "D1" or "D2"' in warned[0]
    plant = PhysicalPlant(robot)
    assert plant.mechanisms == ("D1",) * 5 and plant.mechanism_source.startswith("default")
    for direction, sign in (("+x", 1), ("-x", -1)):
        code, out, _ = cli(capsys, "sim", path, "--direction", direction, "--duration", "40", "--json")
        result = json.loads(out)
        assert code == 0 and result["faults"] == [], result["faults"]
        assert result["cycles"] >= 2 and sign * result["displacement_mm"] > 0

    declared = path.read_text().replace('actuator = "a', 'friction = "D1"\nactuator = "a')
    path.write_text(declared)
    caplog.clear()
    with caplog.at_level("WARNING"):
        load_robot(path)
    assert not [r for r in caplog.records if "friction" in r.getMessage()]


def test_a_coil_shared_by_limbs_apart_is_explained_as_one_coil(tmp_path, caplog):
    """Both ends of a three-limb worm on one actuator: the model's coil sits at the first limb
    that names it and cannot bend the far end; the warning says so and what to do, rather
    than suggesting another ψ* or body length."""
    path = _worm(tmp_path, 3)
    text = path.read_text().replace('actuator = "a3"', 'actuator = "a1"')
    path.write_text(text.replace('[[actuator]]\nname = "a3"\nchannel = 2\n', ""))
    with caplog.at_level("WARNING"):
        load_robot(path)
    warned = [r.getMessage() for r in caplog.records if "limb 'l3'" in r.getMessage()]
    assert len(warned) == 1 and "that coil sits at limb 'l1'" in warned[0], warned
    assert "give 'l3' a coil of its own" in warned[0] and "lower psi_star_deg" not in warned[0]


def test_build_leaves_out_a_direction_whose_gait_0_raises_one_limb_of_a_shared_coil_alone(tmp_path, capsys):
    """Every optimal gait of both directions needs a state the shared coil cannot make. The build
    used to refuse the robot, so a lab could not even learn its matrix (proleg learn and load-gait
    build the same firmware); now it leaves both directions' gaits out and says why."""
    import json

    from proleg.cli.main import main

    fixture = Path(__file__).parent / "fixtures" / "four-shared.toml"
    assert main(["build", str(fixture), "--board", "host-sim", "-o", str(tmp_path / "b")]) == 0
    captured = capsys.readouterr()
    err = captured.err
    assert "Traceback" not in err
    assert ("proleg: warning: +x: none of its optimal gaits can run on this robot (the best-ranked, "
            "gait 0000 0100 1100") in err
    # the far limb p2 alone: coil1 sits at p1 and bends p2 to 8.6°, so 0100 is not even reachable
    # (that reason comes first); raising p2 without p1 is the shared coil's error as well
    assert ("goes to states 0100 (step 1), 1100 (step 2)" in err and "which the robot cannot reach" in err
            and "in 0100 'p2' needs ψ ≥ 21.0° and gets at most 8.6°" in err)
    assert "the firmware carries no +x gait (START +x is refused: NACK NO_GAIT)" in err
    assert "  +x gaits: none (left out: the hardware cannot make its optimal gaits, warned above)" in captured.out
    manifest = json.loads((tmp_path / "b" / "proleg-build.json").read_text())
    assert manifest["gaits"] == {"+x": [], "-x": []}
    assert set(manifest["gaits_left_out"]) == {"+x", "-x"}


def test_many_unholdable_states_are_summarised_not_listed(caplog):
    import logging

    fixture = Path(__file__).parent / "fixtures" / "four-shared.toml"
    with caplog.at_level(logging.WARNING, logger="proleg.robot"):
        load_robot(fixture)
    held = [r.getMessage() for r in caplog.records if "cannot be held" in r.getMessage()]
    assert len(held) == 4  # three examples and a count, not ten lines
    assert held[-1].endswith("5 more lines like these: in all, 7 of the 16 states the matrix enters cannot be held "
                             "on the simulated body because of a limb lifted by its own coil, shared with a raised "
                             "limb (-v lists every line)")


def test_a_default_channel_the_board_lacks_is_called_the_default_not_quoted(tmp_path):
    # "actuator 'a5' is on channel = 4": the file had no channel key to quote
    path = _worm(tmp_path, 5)
    path.write_text("\n".join(ln for ln in path.read_text().splitlines() if not ln.startswith("channel =")))
    robot = load_robot(path)
    with pytest.raises(BuildError) as e:
        build(robot, load_board("arduino-nano"), tmp_path / "nano")
    assert str(e.value).startswith(f"{path}: actuator 'a5' (the 5th [[actuator]], no channel key) is on channel 4 "
                                   "by default, its position, but board arduino-nano has 4 PWM channels: channel = 0 (D9)")
    assert not (tmp_path / "nano").exists()


def test_a_tie_the_hardware_can_make_is_gait_0_when_the_first_ranked_cannot_be(tmp_path, capsys):
    """Two limbs on one coil, 00 -> 01 -> 00 and 00 -> 10 -> 00 both +1 a step: the engine ranks
    00 01 00 first (by states), which the shared coil cannot hold, and the build refused the
    robot (gait 0 cannot run) though 00 10 00 was an optimal tie it can walk."""
    from proleg.cli.main import main
    from proleg.firmware.gaits import firmware_gaits

    path = tmp_path / "shared.toml"
    path.write_text("\n".join([
        '[robot]', 'name = "shared"',
        '[[limb]]', 'name = "a"', 'psi_star_deg = [20.0]', 'actuator = "c"',
        '[[limb]]', 'name = "b"', 'psi_star_deg = [20.0]', 'actuator = "c"',
        '[[actuator]]', 'name = "c"',
        '[control]', 'hold_margin_deg = 1.0',
        '[transitions]', 'matrix = [[0, 1, 1, "x"], [1, 0, "x", "x"], [1, "x", 0, "x"], ["x", "x", "x", 0]]', '']))
    robot = load_robot(path)
    gaits = firmware_gaits(robot)["+x"]
    labels = [" ".join(robot.transitions.label(s) for s in g.states) for g in gaits]
    assert labels[0] == "00 10 00" and "00 01 00" in labels, labels
    assert main(["build", str(path), "--board", "host-sim", "-o", str(tmp_path / "b")]) == 0
    capsys.readouterr()


def test_a_tie_the_firmware_would_walk_is_gait_0_when_the_first_ranked_would_fault(tmp_path, capsys):
    """00 -> 01 -> 00 and 00 -> 10 -> 00 tie at +1 a step, and the engine ranks 00 01 00 first
    (by states); the robot file says 00 -> 01 takes 20 s, past the 8 s state timeout, so the
    firmware would stop that gait (STATE_TIMEOUT). START ran it by default, the build warning
    "expect a fault" about gait 0, though the tie 00 10 00 walks without one."""
    from proleg.cli.main import main
    from proleg.firmware.gaits import firmware_gaits

    path = tmp_path / "slow.toml"
    path.write_text("\n".join([
        '[robot]', 'name = "slow"',
        '[[limb]]', 'name = "a"', 'psi_star_deg = [20.0]', 'actuator = "ca"',
        '[[limb]]', 'name = "b"', 'psi_star_deg = [20.0]', 'actuator = "cb"',
        '[[actuator]]', 'name = "ca"', 'channel = 0',
        '[[actuator]]', 'name = "cb"', 'channel = 1',
        '[transitions]', 'matrix = [[0, 1, 1, "x"], [1, 0, "x", "x"], [1, "x", 0, "x"], ["x", "x", "x", 0]]',
        'durations_s = [[0, 20, 1, "x"], [1, 0, "x", "x"], [1, "x", 0, "x"], ["x", "x", "x", 0]]', '']))
    robot = load_robot(path)
    labels = [" ".join(robot.transitions.label(s) for s in g.states) for g in firmware_gaits(robot)["+x"]]
    assert labels[0] == "00 10 00" and "00 01 00" in labels, labels
    assert main(["build", str(path), "--board", "host-sim", "-o", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    assert "expect a fault: gait 00 01 00: step 1 (00 -> 01) takes 20 s" in err  # still carried, still said
    assert "gait 0 of +x" not in err, err


def test_a_shared_coil_sits_at_the_same_limb_whatever_the_order_of_the_actuator_tables(tmp_path, caplog):
    """A coil's home was "the limb of the coil's own index if that limb names it, else the first
    limb naming it": listing [[actuator]] b before a moved a shared coil from the tail to the
    middle, and the load's reach warnings (and the body) changed with it."""
    import logging

    def robot(first: str, second: str) -> Path:
        text = "\n".join([
            '[robot]\nname = "shared3"',
            '[[limb]]\nname = "tail"\npsi_star_deg = [20.0]\nactuator = "coil-a"',
            '[[limb]]\nname = "mid"\npsi_star_deg = [20.0]\nactuator = "coil-a"',
            '[[limb]]\nname = "head"\npsi_star_deg = [20.0]\nactuator = "coil-b"',
            f'[[actuator]]\nname = "{first}"\nchannel = 0',
            f'[[actuator]]\nname = "{second}"\nchannel = 1',
            '[transitions]\nunits = "steps"\nmatrix = [' + ", ".join(
                "[" + ", ".join("0" if i == j else ("1" if bin(i ^ j).count("1") == 1 else '"x"') for j in range(8)) + "]"
                for i in range(8)) + "]",
        ])
        path = tmp_path / f"{first}-{second}.toml"
        path.write_text(text + "\n")
        return path

    seen = []
    for order in (("coil-a", "coil-b"), ("coil-b", "coil-a")):
        caplog.clear()
        path = robot(*order)
        with caplog.at_level(logging.WARNING, logger="proleg"):
            load_robot(path)
        seen.append(sorted(r.getMessage().replace(str(path), "FILE") for r in caplog.records))
    assert seen[0] == seen[1] and any("sits at limb 'tail'" in m for m in seen[0])


def test_inject_names_the_ends_as_the_conditions_do():
    """``--inject`` takes rear/front (the first and last limb, and their coils) as ``--condition``
    does, where no limb or coil has that name: inchworm-3's front is its head and sma-head, and
    caterpillar-4's front is its front proleg (a limb of that name)."""
    for name, end, limb in (("inchworm-3", "front", 2), ("caterpillar-4", "front", 2), ("inchworm-3", "rear", 0)):
        sim = open_simulated(load_robot(ROOT / "robots" / f"{name}.toml"), plant="table")
        SimSession(sim).advance(0.2)
        sim.board.read()
        sim.inject(f"imu-silent:{end}")
        sim.run_ticks(50)
        faults = [m for m in FrameDecoder().feed(sim.board.read()) if m.name == "EVENT" and m.kind == EventKind.FAULT]
        assert [(f.code, f.detail) for f in faults] == [(FaultCode.IMU_NO_ACK, limb)], (name, end)
    sim = open_simulated(load_robot(ROOT / "robots" / "inchworm-3.toml"), plant="physical")
    sim.inject("dead-actuator:front")
    assert [bool(a) for a in sim.plant.alive] == [True, True, False]  # sma-head
    with pytest.raises(Exception, match=r"\(tail, middle, head, rear, front or 0..2\)"):
        sim.inject("imu-stuck:nose")
    sim = open_simulated(load_robot(ROOT / "robots" / "caterpillar-4.toml"), plant="physical")
    sim.inject("dead-actuator:rear")  # the rear proleg's coil, as power_scale=rear reads it
    assert [bool(a) for a in sim.plant.alive] == [True, False, True, True]  # sma-rear, not sma-tail
    with pytest.raises(Exception, match=r"\(tail, rear, front, head or 0..3\)"):
        sim.inject("imu-stuck:nose")


def test_more_actuators_than_the_boards_pwm_channels_says_no_numbering_fits(tmp_path):
    """Eight coils on the Nano named only the first actuator past its 4 channels: renumbering
    that one led to "a channel no other actuator uses", and only then to the real limit. The
    line now says the robot has more actuators than the board has channels, and what fits."""
    robot = load_robot(_worm(tmp_path, 8))
    with pytest.raises(BuildError) as info:
        build(robot, load_board("arduino-nano"), tmp_path / "nano")
    msg = str(info.value)
    assert "has 8 actuators and board arduino-nano drives at most 4" in msg and "share" in msg and "\n" not in msg


def test_hil_gait_test_walks_a_robot_file_with_var_dx_only(tmp_path):
    """`proleg sim --measure-matrix --out` and `proleg learn` write `var_dx` beside the matrix:
    a variance of Δx, no motion in the plane. hil_tests skipped such a robot's gait test as
    'a planar robot (its matrix has Δy/Δθ statistics)', so a measured or learned robot file lost
    its plant-truth test on every target without a word."""
    text = (ROOT / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    text = text.replace('name = "paper-r1"', 'name = "r1-var-dx"', 1)
    var_dx = "var_dx = [[0, 0.01, 0.01, 0.01], [0.01, 0, 0.01, 0.01], [0.01, 0.01, 0, 0.01], [0.01, 0.01, 0.01, 0]]\n"
    text = text.replace("\n[safety]", "\n" + var_dx + "\n[safety]", 1)
    robot = tmp_path / "r1-var-dx.toml"
    robot.write_text(text, encoding="utf-8")
    assert load_robot(robot).transitions.planar is not None  # var_dx is read
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:xdist", "-p", "no:cacheprovider", str(ROOT / "hil_tests"),
         "--robot", str(robot), "--target", "host-sim", "-k", "measured_matrix_rate and +x"],
        capture_output=True, text=True, cwd=ROOT,
    ).stdout
    assert "planar robot" not in out, out
    assert "1 passed" in out, out


def test_hil_tests_feed_a_short_link_watchdog(tmp_path):
    """A robot file with link_watchdog_ms = 100, the least the loader takes: the hil tests' client
    pinged every 0.5 s (a quarter of the default 2 s) and the on-time test every 500 ms, so the
    firmware stopped them all with LINK_WATCHDOG (3 of the focused subset failed on host-sim)."""
    text = (ROOT / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    text = text.replace("\n[control]", "\nlink_watchdog_ms = 100\n\n[control]", 1)
    robot = tmp_path / "r1-short-watchdog.toml"
    robot.write_text(text, encoding="utf-8")
    assert load_robot(robot).safety.link_watchdog_ms == 100
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:xdist", "-p", "no:cacheprovider", str(ROOT / "hil_tests"),
         "--robot", str(robot), "--target", "host-sim", "-k", "test_no_coil_stays_on_longer or ct1_and_ct2"],
        capture_output=True, text=True, cwd=ROOT,
    ).stdout
    assert "failed" not in out and "passed" in out, out
