"""Level calibration (core/level.c, proleg calibrate): the firmware measures each IMU's rest
tilt, keeps it in non-volatile memory with a CRC, takes it off every sample, refuses while a
gait runs, and with the slope levelled too the gait keeps running on ±10° inclines."""

from __future__ import annotations

import pytest

from proleg.cli.main import main
from proleg.link.client import CommandRefused, RobotClient
from proleg.link.level import calibrate_level, clear_level, get_level
from proleg.link.sim_link import SimLink
from proleg.paths import resolve_robot
from proleg.protocol.definition import ErrorCode, EventKind, LevelResult, LevelStatus
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot, make_plant

MOUNT = ["imu_offset_deg=left:8", "imu_offset_deg=right:-8"]


@pytest.fixture(scope="module")
def r1(tmp_path_factory):
    """R1 without its climb guard ([control] max_climb_deg): these tests start it up slopes it
    cannot climb to see the levelling itself (tests/test_climb_guard.py checks the guard, and
    test_level_at_rest_stateful.py both together)."""
    text = resolve_robot("paper-r1").read_text(encoding="utf-8")
    kept = [line for line in text.splitlines(keepends=True) if not line.startswith("max_climb_deg")]
    assert len(kept) == len(text.splitlines()) - 1
    path = tmp_path_factory.mktemp("r1") / "paper-r1.toml"
    path.write_text("".join(kept), encoding="utf-8")
    robot = load_robot(path)
    assert robot.control.max_climb_deg is None
    return robot


def connect(sim: SimulatedRobot) -> RobotClient:
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
    client.connect()
    return client


def reset(sim: SimulatedRobot, client: RobotClient) -> RobotClient:
    """Power-cycle the board (its NV block stays, as EEPROM or flash does) and reconnect."""
    client.close()
    sim.board.reset(7)
    return connect(sim)


def wait(client: RobotClient, seconds: float) -> None:
    end = client.link.clock() + seconds
    while client.link.clock() < end:
        client.recv(0.05)


def rest_psi_cdeg(client: RobotClient) -> tuple[float, ...]:
    """Each limb's ψ at rest, the mean of 20 telemetry frames (the IMUs' noise is ±0.3°)."""
    wait(client, 0.5)  # past the IMUs' start-up
    frames = [m.psi for m in client.telemetry(count=20)]
    return tuple(sum(f[i] for f in frames) / len(frames) for i in range(len(frames[0])))


def test_a_fresh_board_has_no_calibration_and_applies_none(r1):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    reading = get_level(client)
    assert reading.status == LevelStatus.NONE and reading.offsets_cdeg == (0, 0) == reading.ground_cdeg
    left, right = rest_psi_cdeg(client)
    assert abs(left - 800) < 40 and abs(right + 800) < 40  # the mounting tilt, uncorrected


def test_calibration_is_stored_applied_and_survives_a_reset(r1):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    outcome = calibrate_level(client)
    assert outcome.ok and outcome.result == LevelResult.STORED
    left, right = outcome.reading.offsets_cdeg
    assert outcome.reading.status == LevelStatus.STORED
    assert abs(left - 800) < 15 and abs(right + 800) < 15
    assert all(abs(p) < 15 for p in rest_psi_cdeg(client))  # at rest, ψ reads 0 again
    client = reset(sim, client)
    kept = get_level(client)
    assert kept.status == LevelStatus.STORED and kept.offsets_cdeg == (left, right)
    assert all(abs(p) < 15 for p in rest_psi_cdeg(client))
    # the record in the board's NV block: magic, limbs, offsets (LE), CRC-16/CCITT-FALSE
    raw = bytes(sim.board._lib.sim_nv_peek(i) for i in range(8))
    from binascii import crc_hqx

    assert raw[:2] == b"\x4c\x02" and int.from_bytes(raw[2:4], "little", signed=True) == left
    assert int.from_bytes(raw[6:8], "little") == crc_hqx(raw[:6], 0xFFFF)
    assert clear_level(client).status == LevelStatus.NONE
    client = reset(sim, client)
    assert get_level(client).status == LevelStatus.NONE
    client.close()


@pytest.mark.parametrize("byte, value, status", [(0, 0xFF, LevelStatus.NONE), (3, 0x55, LevelStatus.CORRUPT),
                                                 (1, 0x03, LevelStatus.CORRUPT), (0, 0x4D, LevelStatus.CORRUPT)])
def test_a_blank_or_corrupt_record_means_no_calibration_not_garbage(r1, byte, value, status):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    sim.board._lib.sim_nv_poke(byte, value)
    client = reset(sim, client)
    reading = get_level(client)
    assert reading.status == status and reading.offsets_cdeg == (0, 0)
    left, _ = rest_psi_cdeg(client)
    assert abs(left - 800) < 40  # nothing applied
    client.close()


def test_refused_while_a_gait_runs_and_interrupted_by_a_start(r1):
    sim = SimulatedRobot(r1)
    client = connect(sim)
    client.start(0, "+x")
    for name in ("CALIBRATE_LEVEL", "CLEAR_LEVEL"):
        with pytest.raises(CommandRefused) as e:
            client.request(name, **({"ground": 0} if name == "CALIBRATE_LEVEL" else {}))
        assert e.value.error == ErrorCode.NOT_ALLOWED
    assert get_level(client).status == LevelStatus.NONE
    client.stop()
    wait(client, 2.5)  # at rest for 2 s since the gait (the next test)
    client.request("CALIBRATE_LEVEL", ground=0)
    client.start(0, "+x")  # within the 64 sampling ticks
    ev = next(m for m in iter(lambda: client.recv(1.0), None) if m.name == "EVENT" and m.kind == EventKind.LEVEL_DONE)
    assert ev.code == LevelResult.INTERRUPTED
    assert get_level(client).status == LevelStatus.NONE
    client.close()


def test_a_tilt_beyond_20_degrees_is_refused_and_the_old_record_kept(r1):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    old = calibrate_level(client).reading
    sim.plant = make_plant(r1, "physical", ["imu_offset_deg=right:-15", "imu_bias_deg=right:-10"])
    wait(client, 0.3)
    outcome = calibrate_level(client)
    assert outcome.result == LevelResult.TOO_TILTED and outcome.limbs_mask == 0b10
    assert outcome.reading == old
    client.close()


def run_gait(client: RobotClient, sim: SimulatedRobot, direction: str, seconds: float) -> tuple[float, list]:
    x0 = sim.plant.displacement_mm
    client.clear()
    client.start(0, direction)
    faults = []
    end = client.link.clock() + seconds
    while client.link.clock() < end:
        m = client.recv(0.1)
        if m is not None and m.name == "EVENT" and m.kind == EventKind.FAULT:
            faults.append(m.code)
    client.stop()
    return sim.plant.displacement_mm - x0, faults


def test_crooked_imus_stall_the_gait_until_calibrated_on_the_flat(r1):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    _, faults = run_gait(client, sim, "+x", 25)
    assert faults  # 8° of mounting tilt: a limb never reaches its sensed ψ*, STATE_TIMEOUT
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    dx, faults = run_gait(client, sim, "+x", 25)
    assert not faults and dx > 5


@pytest.mark.parametrize("incline", [10, -10])
def test_calibrated_on_the_flat_a_robot_started_at_rest_on_a_slope_levels_itself(r1, incline):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    on_slope = MOUNT + [f"incline_deg={incline}"]
    sim.plant = make_plant(r1, "physical", on_slope)
    wait(client, 0.3)  # started before the firmware has seen it at rest for 2 s: the flat record alone
    _, faults = run_gait(client, sim, "+x", 25)
    assert faults  # the slope itself tilts each end's IMU by ±10°: the flat calibration cannot know it
    assert get_level(client).ground_cdeg == (0, 0)
    sim.plant = make_plant(r1, "physical", on_slope)  # cold again, at rest on the slope
    client.clear()
    wait(client, 2.5)
    for direction in ("+x", "-x"):
        _, faults = run_gait(client, sim, direction, 25)
        assert not faults, direction
        reading = get_level(client)
        first, last = reading.ground_cdeg  # the slope as each end sees it: up, down
        assert abs(first - 100 * incline) < 40 and abs(last + 100 * incline) < 40, reading
        assert reading.status == LevelStatus.STORED  # the flat record stays as it was


def test_levelling_at_start_needs_the_robot_at_rest_and_a_flat_record(r1):
    """START levels only after 2 s at rest: a START soon after STOP (a limb still cooling
    back) keeps the ground in use; after a rest on the flat the ground it finds is flat. With
    no flat record there is nothing to measure the ground against and nothing is applied."""
    sim = SimulatedRobot(r1, conditions=MOUNT + ["incline_deg=8"])
    client = connect(sim)
    wait(client, 3.0)
    client.start(0, "+x")
    wait(client, 1.0)
    client.stop()
    assert get_level(client).ground_cdeg == (0, 0)  # no record: the 8° on top of the mounting stays

    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    sim.plant = make_plant(r1, "physical", MOUNT + ["incline_deg=-10"])
    wait(client, 2.5)
    client.start(0, "+x")
    wait(client, 8.0)
    client.stop()
    levelled = get_level(client).ground_cdeg
    assert abs(levelled[0] + 1000) < 40 and abs(levelled[1] - 1000) < 40
    for pause in (0.0, 0.5, 1.5):  # not yet at rest for 2 s: the ground stays
        sim.plant = make_plant(r1, "physical", MOUNT)  # back on the flat, mid-stride
        wait(client, pause)
        client.start(0, "+x")
        wait(client, 3.0)
        client.stop()
        assert get_level(client).ground_cdeg == levelled, pause
    wait(client, 6.0)  # the coils cool, the limbs come back down and rest
    client.start(0, "+x")
    client.stop()
    assert all(abs(g) < 60 for g in get_level(client).ground_cdeg)  # the flat ground, within 0.6°
    client.close()


def test_a_refused_start_does_not_level(r1):
    """A START the firmware refuses (no gait loaded) changes nothing, the ground included; the
    next START that runs levels as usual."""
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    sim.plant = make_plant(r1, "physical", MOUNT + ["incline_deg=10"])
    wait(client, 2.5)
    with pytest.raises(CommandRefused) as e:
        client.start("user", "+x")
    assert e.value.error == ErrorCode.NO_GAIT
    assert get_level(client).ground_cdeg == (0, 0)
    client.start(0, "+x")
    first, last = get_level(client).ground_cdeg
    assert abs(first - 1000) < 40 and abs(last + 1000) < 40
    client.close()


def test_levelling_at_start_refuses_a_tilt_beyond_20_degrees_and_keeps_the_ground(r1):
    """At rest, but one end reads 22° below the flat record's zero (a knocked IMU: mounted −8°,
    now −20° and biased −10°): START keeps the ground in use, as a calibration on this ground
    refuses it (TOO_TILTED)."""
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    assert calibrate_level(client).ok
    sim.plant = make_plant(r1, "physical", ["imu_offset_deg=left:8", "imu_offset_deg=right:-20", "imu_bias_deg=right:-10"])
    wait(client, 3.0)
    client.start(0, "+x")
    wait(client, 0.5)
    client.stop()
    assert get_level(client).ground_cdeg == (0, 0)
    wait(client, 2.5)  # at rest 2 s since the gait: the board calibrates again
    outcome = calibrate_level(client, ground=True)
    assert outcome.result == LevelResult.TOO_TILTED  # the same verdict by hand
    client.close()


def test_levelled_by_hand_on_the_slope_the_gait_keeps_running(r1):
    sim = SimulatedRobot(r1, conditions=MOUNT + ["incline_deg=10"])
    client = connect(sim)
    sim.plant = make_plant(r1, "physical", MOUNT)
    assert calibrate_level(client).ok
    sim.plant = make_plant(r1, "physical", MOUNT + ["incline_deg=10"])
    wait(client, 0.5)  # at once: not yet at rest long enough to level by itself
    outcome = calibrate_level(client, ground=True)
    assert outcome.ok
    first, last = outcome.reading.ground_cdeg
    assert abs(first - 1000) < 30 and abs(last + 1000) < 30
    _, faults = run_gait(client, sim, "+x", 25)
    assert not faults


def test_cli_calibrate_prints_each_limb_by_name(capsys):
    assert main(["calibrate", "paper-r1", "--sim"]) == 0
    out = capsys.readouterr().out
    assert "level calibration stored" in out and "limb left" in out and "limb right" in out and "°" in out
    assert main(["calibrate", "paper-r1", "--sim", "--show"]) == 0
    assert "no level calibration stored" in capsys.readouterr().out  # a new simulated board each run


def test_the_calibration_table_lines_up_under_wide_limb_names():
    """``前`` takes two columns on a terminal: padded by ``len``, its row's tilt stood one
    column right of the other rows'."""
    from proleg.cli.calibrate import _table
    from proleg.names import display_width

    rows = _table(["前", "tail", "後ろ"], (150, -200, 0), ["ok", "ok", "ok"]).splitlines()
    assert [display_width(r[:r.index("rest tilt")]) for r in rows] == [display_width("  limb tail  ")] * 3


def test_the_sim_report_names_the_limb_a_fault_is_on(capsys):
    main(["sim", "paper-r1", "--duration", "15", "--condition", "imu_offset_deg=left:8",
          "--condition", "imu_offset_deg=right:-8"])
    out = capsys.readouterr().out
    assert "FAULT at" in out and "STATE_TIMEOUT on left" in out and "limb/channel" not in out


@pytest.mark.parametrize("ground", [2, 7, 255])
def test_a_ground_other_than_flat_or_this_one_is_refused_and_nothing_starts(r1, ground):
    sim = SimulatedRobot(r1, conditions=MOUNT)
    client = connect(sim)
    with pytest.raises(CommandRefused) as e:
        client.request("CALIBRATE_LEVEL", ground=ground)
    assert e.value.error == ErrorCode.OUT_OF_RANGE and e.value.detail == 1
    assert "ground" in str(e.value)
    wait(client, 0.5)  # no calibration was begun: no LEVEL_DONE, nothing stored
    assert get_level(client).status == LevelStatus.NONE
    client.close()


def test_calibrate_refuses_a_robot_whose_ends_are_still_coming_down(r1, capsys):
    """The board checks only that no gait runs and that no limb tilts 20°: right after a gait's
    STOP, its ends still bent and cooling, proleg calibrate stored +7° and +17° of "rest tilt",
    and every START on flat ground after it was refused (TOO_STEEP)."""
    from types import SimpleNamespace

    from proleg.cli.calibrate import _calibrate

    sim = SimulatedRobot(r1, seed=4)
    client = connect(sim)
    assert client.wait_known_state()
    client.start(0, "+x")
    wait(client, 3.5)  # 00 -> 10 -> 11: both ends up
    client.stop()
    args = SimpleNamespace(show=False, clear=False, ground=False, sim=True)
    with pytest.raises(Exception, match=r"not at rest, nothing asked of the board: .*(is still moving|is heating)"):
        _calibrate(args, r1, client, [])
    assert get_level(client).status == LevelStatus.NONE  # nothing stored
    wait(client, 10.0)  # the coils cool, the body settles
    assert _calibrate(args, r1, client, []) == 0
    reading = get_level(client)
    assert reading.status == LevelStatus.STORED and max(abs(v) for v in reading.offsets_cdeg) < 100  # under 1°
    client.close()


def _ends_up_then_stopped(r1) -> tuple[SimulatedRobot, RobotClient]:
    """R1 (seed 4) walked until both ends are up, then STOPped: its ends are still coming down."""
    sim = SimulatedRobot(r1, seed=4)
    client = connect(sim)
    assert client.wait_known_state()
    client.start(0, "+x")
    wait(client, 3.5)  # both ends up
    client.stop()
    return sim, client


def test_the_board_refuses_to_calibrate_until_at_rest_2_s_after_a_gait(r1):
    """A host that asks the board itself (not proleg calibrate, which checks rest first): a flat
    calibration 5 ms after STOP stored R1's still-falling ends (7.6° and 17.4°) as mounting
    tilts, and START +x on flat ground was refused TOO_STEEP from then on, across resets. The
    board now refuses (NOT_ALLOWED 6) until every limb has been at level 0 for 2 s with no gait
    and no fault since; a fresh board, at rest from its reset, calibrates at once."""
    sim, client = _ends_up_then_stopped(r1)
    for gap_s in (0.005, 1.0):
        wait(client, gap_s)
        with pytest.raises(CommandRefused) as e:
            client.request("CALIBRATE_LEVEL", ground=0)
        assert (e.value.error, e.value.detail) == (ErrorCode.NOT_ALLOWED, 6)
    assert get_level(client).status == LevelStatus.NONE
    wait(client, 10.0)  # the coils cool, the ends come down and rest
    assert calibrate_level(client).ok
    reading = get_level(client)
    assert reading.status == LevelStatus.STORED and max(abs(v) for v in reading.offsets_cdeg) < 100
    client = reset(sim, client)
    client.request("CALIBRATE_LEVEL", ground=0)  # from a reset: nothing was driven
    client.close()


@pytest.mark.parametrize("cause", ["external", "brown-out", "watchdog"])
def test_a_reset_that_is_not_a_power_on_does_not_make_a_falling_robot_at_rest(r1, cause):
    """A Nano resets when a host opens its port, and the firmware started every reset at rest:
    a host that reconnected 0.1 s after STOP and calibrated 0.95 s later got the board's ACK
    and R1's still-falling ends (9.7° and 4.3°) stored as mounting tilts, kept across power
    cycles. A reset that keeps the coils' budget now keeps "a gait ran since the last 2 s at
    rest" too (NOT_ALLOWED 6), and a board reset at rest still calibrates at once."""
    sim, client = _ends_up_then_stopped(r1)
    wait(client, 0.1)
    client.close()
    sim.board.restart(cause)
    client = connect(sim)
    wait(client, 0.95)
    assert max(next(client.telemetry(count=1)).psi) > 300, "still coming down"
    with pytest.raises(CommandRefused) as e:
        client.request("CALIBRATE_LEVEL", ground=0)
    assert (e.value.error, e.value.detail) == (ErrorCode.NOT_ALLOWED, 6)
    wait(client, 10.0)  # the coils cool, the ends come down and rest
    client.close()
    sim.board.restart(cause)  # at rest: nothing to wait for
    client = connect(sim)
    assert client.wait_known_state()
    outcome = calibrate_level(client)
    assert outcome.ok and max(abs(v) for v in outcome.reading.offsets_cdeg) < 100
    client.close()
