"""The generated firmware, as a robot: link, gaits, safety and faults.

Each test runs against the simulated board (default) and, where it is not marked
``plant``, unchanged against a real board (``--target serial:PORT``).
"""

from __future__ import annotations

import pytest

from proleg.gait import evaluate_sequence
from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.protocol.definition import EventKind, FaultCode, Flag

from .conftest import PAPER_ROBOTS


def events(received, kind=None):
    out = [r for r in received if r.message.name == "EVENT"]
    return [r for r in out if kind is None or r.message.kind == kind]


# ---------------------------------------------------------------------------------------
# link


def test_boots_and_answers_ping_and_get_info_with_its_robot_board_and_gait_hash(target):
    info = target.client.get_info()
    assert info.robot_name == target.robot.name
    assert info.board == target.board.name
    assert info.limbs == len(target.robot.limbs)
    assert info.actuators == len(target.robot.actuators)
    assert info.gait_hash == target.expected_gait_hash
    assert target.client.ping() >= 0.0


def test_telemetry_streams_with_consecutive_sequence_numbers(target):
    frames = list(target.client.telemetry(count=20))
    seqs = [f.seq for f in frames]
    assert all((b - a) & 0xFFFF == 1 for a, b in zip(seqs, seqs[1:]))
    assert all(len(f.psi) == len(target.robot.limbs) for f in frames)
    assert target.client.stats.lost == 0


# ---------------------------------------------------------------------------------------
# gaits: measured displacement per cycle against the gait engine's prediction


def _gait_cases(opposing: bool):
    """(robot, direction, gait index) of every optimal gait in the firmware, split by whether
    some step raises one limb while lowering another (proleg.states.opposing_steps)."""
    from proleg.firmware.build import firmware_gaits
    from proleg.robot import load_robot
    from proleg.states import opposing_steps

    from .conftest import ROBOTS

    for name in PAPER_ROBOTS:
        robot = load_robot(ROBOTS / f"{name}.toml")
        for direction, gaits in firmware_gaits(robot).items():
            for i, gait in enumerate(gaits):
                if bool(opposing_steps(gait.states, robot.levels)) == opposing:
                    walk = "-".join(robot.transitions.label(s) for s in gait.states)
                    yield pytest.param(name, direction, i, id=f"{name}{direction}:{walk}")


CYCLES = 5  # complete gait cycles a gait test measures (at most 40 s)


def _run_gait(t, direction, gait_index, seconds=40.0, cycles_wanted: int | None = CYCLES):
    """Run a gait until ``cycles_wanted`` cycles are complete (at most ``seconds``): the
    plant's true displacement in each cycle, and what the firmware sent.

    A cycle runs from one report of reaching step 0 to the next (as received); it holds the true
    transitions that began inside it (the transition into step 0 began before the report,
    which comes once the limbs have settled)."""
    t.client.start(gait_index, direction)
    received, waited = [], 0.0
    while waited < seconds:
        received += t.wait(1.0)
        waited += 1.0
        marks = [r for r in events(received, EventKind.STATE_REACHED) if r.message.code == 0]
        if cycles_wanted is not None and len(marks) > cycles_wanted:
            break
    t.client.stop()
    # Cycle marks on the host's clock (emulated real time, the plant's), not the firmware's
    # time_ms: a firmware whose ticks overrun keeps a slow clock (issue 11), which would
    # misplace the cycles against the plant's transitions.
    marks = [r.time for r in events(received, EventKind.STATE_REACHED) if r.message.code == 0]
    trans = t.sim.plant.transitions
    cycles = [sum(x.reward_mm for x in trans if a <= x.t_s < b) for a, b in zip(marks, marks[1:])]
    return cycles, received


def _focused_first(cases: list) -> list:
    """Every case but the first is ``emu_long``: an emulated MCU's focused subset walks one gait."""
    return cases[:1] + [pytest.param(*c.values, id=c.id, marks=pytest.mark.emu_long) for c in cases[1:]]


@pytest.mark.plant
@pytest.mark.parametrize("robot_name,direction,gait_index", _focused_first(list(_gait_cases(opposing=False))))
def test_optimal_gait_moves_the_robot_as_the_gait_engine_predicts(open_target, robot_name, direction, gait_index):
    from proleg.firmware.build import firmware_gaits

    t = open_target(robot_name)
    gait = firmware_gaits(t.robot)[direction][gait_index]
    predicted = evaluate_sequence(t.robot.transitions, gait.states).reward * t.sim.plant.params.step_mm

    cycles, received = _run_gait(t, direction, gait_index)
    assert len(cycles) >= CYCLES, f"only {len(cycles)} cycles in 40 s"
    assert not events(received, EventKind.FAULT)
    # Every cycle should move the robot by exactly J * step (the plant's noise is 0 here).
    assert all(abs(c - predicted) < 1e-6 for c in cycles), f"predicted {predicted:+.1f} mm per cycle, measured {cycles}"


@pytest.mark.plant
@pytest.mark.emu_long
@pytest.mark.parametrize("robot_name,direction,gait_index", list(_gait_cases(opposing=True)))
def test_a_step_that_raises_one_limb_and_lowers_another_is_synchronised(
    open_target, robot_name, direction, gait_index, record_property
):
    """Heating is fast and cooling slow, so the controller cannot make both crossings of such
    a step coincide to within the plant's 30 ms; it pre-positions the rising limb near its
    crossing and releases it as the falling one arrives. Measured on R3's 01 -> 10: the two
    crossings, from the plant's true transitions, lie 0.04-0.06 s apart (0.47-0.58 s when
    the rising limb does not wait), and the gait keeps cycling without a fault."""
    from proleg.firmware.build import firmware_gaits
    from proleg.states import opposing_steps

    t = open_target(robot_name)
    gait = firmware_gaits(t.robot)[direction][gait_index]
    step = opposing_steps(gait.states, t.robot.levels)[0]
    a, b = gait.states[step], gait.states[step + 1]
    plant = t.sim.plant
    cycles, received = _run_gait(t, direction, gait_index, cycles_wanted=None)  # the whole 40 s
    assert len(cycles) >= CYCLES and not events(received, EventKind.FAULT)

    skews, trans = [], plant.transitions
    for first, second in zip(trans, trans[1:]):
        if first.src == a and second.dst == b and first.dst != b:
            skews.append(second.t_s - first.t_s)  # made as two transitions
        elif first.src == a and first.dst == b:
            skews.append(0.0)  # made as one (within the plant's simultaneity window)
    record_property("opposing_step_skews_s", [round(s, 3) for s in skews])
    assert len(skews) >= 5
    assert max(skews) < 0.1, f"{t.robot.transitions.label(a)} -> {t.robot.transitions.label(b)}: {skews}"


def test_a_robot_with_no_gait_in_a_direction_refuses_to_start_it(open_target):
    t = open_target("paper-r1-one-actuator")
    from proleg.link import CommandRefused

    with pytest.raises(CommandRefused, match="NO_GAIT"):
        t.client.start(0, "-x")


# ---------------------------------------------------------------------------------------
# safety


def _all_off(sim) -> bool:
    return all(sim.board.pwm(ch) == 0.0 for ch in sim.channels)


def _start_until_driving(target) -> None:
    """START the +x gait and run tick by tick until some MOSFET is on (at most 4 s)."""
    sim = target.sim
    target.client.start(0, "+x")
    for _ in range(4000):
        sim.run_ticks(1)
        if not _all_off(sim):
            return
    raise AssertionError("no actuator came on within 4 s")


#: On an MCU a tick's work takes time: what a tick decides reaches the pins up to its busy
#: time later, at most 70 % of the period when the firmware meets its budget (issue 11).
#: host-sim runs a tick's work at the tick's instant.
MCU_BUSY_BUDGET = 0.7


def _us_until_all_off(target, limit_us: float) -> float:
    """Run until every MOSFET is off: emulated µs it took (10 µs steps on an emulated MCU,
    whole ticks on host-sim). Fails once ``limit_us`` has passed with a coil still on."""
    sim = target.sim
    board = sim.board
    step = getattr(board, "run_us", None)
    t0 = board.time_us
    while not _all_off(sim):
        if step is not None:
            step(10)
        else:
            sim.run_ticks(1)
        took = board.time_us - t0
        assert took <= limit_us, f"a MOSFET still on {took} µs later (allowed {limit_us:.0f} µs)"
    return board.time_us - t0


def _tick_allowance_us(target, ticks: int) -> float:
    tick = target.sim.board.tick_us
    return ticks * tick + (MCU_BUSY_BUDGET * tick if target.emulated else 0.0)


@pytest.mark.plant
def test_estop_turns_every_mosfet_off_within_one_control_tick(target, record_property):
    """Within one tick of the ESTOP frame's arrival (its bytes take their time on the wire:
    6 bytes are 521 µs at 115200 baud), plus the tick's busy budget on an MCU."""
    sim = target.sim
    _start_until_driving(target)
    sim.run_ticks(100)  # mid-drive, a phase of the tick that the start does not choose
    frame = encode(Message.new("ESTOP", token=99))
    wire_us = len(frame) * 10 * 1e6 / target.board.uart_baud
    sim.write(frame)
    took = _us_until_all_off(target, wire_us + _tick_allowance_us(target, 1))
    record_property("estop_to_pins_us", took)
    # latched: stays off while the gait would have driven the coils again
    sim.run_ticks(500)
    assert _all_off(sim)


@pytest.mark.plant
def test_imu_that_stops_answering_faults_and_turns_all_mosfets_off_within_two_ticks(target, record_property):
    sim = target.sim
    _start_until_driving(target)
    sim.run_ticks(100)
    sim.inject("imu-silent:right")
    record_property("imu_loss_to_pins_us", _us_until_all_off(target, _tick_allowance_us(target, 2)))
    received = target.wait(0.2)
    faults = [r.message for r in events(received, EventKind.FAULT)]
    assert any(f.code == FaultCode.IMU_NO_ACK for f in faults), faults
    tel = [r.message for r in received if r.message.name == "TELEMETRY"]
    assert tel and tel[-1].flags & Flag.FAULT


@pytest.mark.plant
@pytest.mark.parametrize("fault", ["imu-stuck:left", "imu-garbage:left"])
def test_imu_returning_nonsense_is_a_fault_with_all_mosfets_off(target, fault):
    sim = target.sim
    target.client.start(0, "+x")
    target.wait(1.0)
    sim.inject(fault)
    received = target.wait(1.0)
    faults = [r.message for r in events(received, EventKind.FAULT)]
    assert any(f.code in (FaultCode.IMU_BAD_DATA, FaultCode.IMU_NO_ACK) for f in faults), faults
    assert _all_off(sim)


@pytest.mark.plant
def test_no_coil_stays_on_longer_than_max_on_ms(target, record_property):
    """Both coils dead (they heat, nothing moves): the gait's first step keeps asking for
    heat, and the on-time limit is what turns the coil off, on the board's clock. Sampled
    every plant step (2 ms): a sampled on-period is never longer than the true one."""
    sim = target.sim
    robot = target.robot
    max_on_us = robot.safety.max_on_ms * 1000
    for a in robot.actuators:
        sim.inject(f"dead-actuator:{a.name}")
    target.client.start(0, "+x")
    on_since: dict[int, int] = {}
    longest = 0
    received = []
    t_end = sim.board.time_us + max_on_us + 1_000_000
    while sim.board.time_us < t_end:
        sim.step()
        now = sim.board.time_us
        for ch in sim.channels:
            if sim.board.pwm(ch) > 0.0:
                longest = max(longest, now - on_since.setdefault(ch, now))
            else:
                on_since.pop(ch, None)
        received += target.wait(0.0)
    record_property("longest_on_us", longest)
    assert longest <= max_on_us + sim.board.tick_us, f"a coil stayed on {longest} µs (max_on_ms {robot.safety.max_on_ms})"
    assert longest >= max_on_us - 2 * sim.plant_dt_s * 1e6, "the limit was never reached: the test proved nothing"
    faults = [r.message for r in events(received, EventKind.FAULT)]
    assert any(f.code == FaultCode.SMA_ON_LIMIT for f in faults), faults


@pytest.mark.plant
@pytest.mark.emu_long
def test_dead_actuator_is_reported_as_a_state_timeout(target):
    sim = target.sim
    sim.inject("dead-actuator:sma-left")
    target.client.start(0, "+x")  # 00 -> 10 needs the left coil
    received = target.wait(target.robot.safety.state_timeout_ms / 1000 + 2.0)
    faults = [r.message for r in events(received, EventKind.FAULT)]
    assert any(f.code == FaultCode.STATE_TIMEOUT for f in faults), faults
    assert _all_off(sim)


# ---------------------------------------------------------------------------------------
# link robustness


def test_corrupted_and_random_bytes_are_counted_and_valid_commands_still_work(target):
    import random

    rng = random.Random(5)
    client = target.client
    before = client.firmware_stats()
    junk = bytes(rng.randrange(256) for _ in range(3000))
    good = encode(Message.new("PING", token=7))
    bad_crc = bytearray(good)
    bad_crc[2] ^= 0x40
    client.link.write(junk + b"\0" + bytes(bad_crc) + b"\0" + junk[:100] + b"\0")
    target.wait(0.2)
    assert client.ping() >= 0  # the link still works
    after = client.firmware_stats()
    errors = lambda s: s.crc_errors + s.framing_errors + s.unknown_ids + s.bad_length + s.bad_value
    assert errors(after) > errors(before)
    assert after.rx_ok > before.rx_ok
    info = client.get_info()
    assert info.robot_name == target.robot.name
