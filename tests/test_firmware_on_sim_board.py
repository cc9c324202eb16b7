"""The whole firmware core, built for the simulated board (firmware_templates/core + hal/sim,
one shared library per small robot of core_configs.py), stepped one control tick at a time
and talked to in its own protocol through the one client: boot, E-stop, IMU faults, the
state timeout, the safety envelope of SET_PARAM, held limbs, gait loading and telemetry.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from core_configs import CC, CORE, SIM, renderer
from proleg.link import CommandRefused, RobotClient
from proleg.link.sim_link import SimLink
from proleg.protocol import definition as d
from proleg.protocol.codec import Message, encode
from proleg.sim.board import SimBoard

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")


@pytest.fixture(scope="session")
def rendered(tmp_path_factory):
    return renderer(tmp_path_factory)


class Rig:
    """The firmware built for the simulated board (``proleg.sim.board.SimBoard``), stepped one
    control tick at a time through ``SimLink`` and talked to through the one client
    (``proleg.link.RobotClient``). ``log`` keeps every message received so far."""

    def __init__(self, so: Path, limbs: int, channels: int):
        self.board = SimBoard(so)
        self.tick_s = self.board.tick_us / 1e6
        self.client = RobotClient(SimLink(self.board, step_s=self.tick_s),
                                  max_limbs=limbs, max_channels=channels)
        self.log: list[Message] = []

    def reset(self, seed=1):
        self.board.reset(seed)
        return self.run(10)  # INFO + BOOT take a few ms at 115200 baud

    def run(self, n):
        """Run ``n`` control ticks; the messages that arrived meanwhile (and any the client
        had queued while it waited for a reply)."""
        link = self.client.link
        deadline = link.clock() + n * self.tick_s
        msgs = []
        while True:
            msg = self.client.recv(max(0.0, deadline - link.clock()))
            if msg is not None:
                msgs.append(msg)
            elif link.clock() >= deadline - 1e-9:
                break
        self.log += msgs
        return msgs

    def refused(self, name, **fields) -> CommandRefused:
        """Send command ``name``; it must be NACKed: the refusal."""
        with pytest.raises(CommandRefused) as e:
            self.client.request(name, **fields)
        return e.value

    def set_psi(self, limb, deg):
        self.board.imu_truth(0x68 + limb, deg, 0.0)

    def duty(self, ch):
        return self.board.pwm_permyriad(ch)


@pytest.fixture(scope="session")
def sim_so(rendered, tmp_path_factory):
    def build(config: str) -> Path:
        gen = rendered(config)
        out = tmp_path_factory.mktemp(f"so-{config}") / "libfirmware.so"
        srcs = sorted(CORE.glob("*.c")) + sorted(SIM.glob("*.c"))
        srcs = [p for p in srcs if not p.name.startswith("can")]  # the CAN link: CAN boards only (build._in_image)
        srcs += [gen / "gait_table.c", gen / "proto_gen.c"]
        cmd = [CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-fPIC", "-fvisibility=hidden"]
        cmd += [f"-I{CORE}", f"-I{SIM}", f"-I{gen}", *map(str, srcs), "-shared", "-lm", "-o", str(out)]
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return out

    cache: dict[str, Path] = {}

    def get(config: str) -> Path:
        if config not in cache:
            cache[config] = build(config)
        return cache[config]

    return get


@pytest.fixture
def board(sim_so):
    b = Rig(sim_so("r1-fast"), 2, 2)
    b.set_psi(0, 0.0)
    b.set_psi(1, 0.0)
    b.reset()
    assert b.client.wait_known_state()  # every IMU read: the board takes a START
    b.run(0)
    return b


def _events(msgs, kind):
    return [m for m in msgs if m.spec.name == "EVENT" and m.kind == kind]


def _heating(board: Rig) -> None:
    """Start +x gait #0 (00 -> 10 ...) and run until the left SMA is on."""
    board.client.start(0, "+x")
    for _ in range(100):
        board.run(1)
        if board.duty(0) > 0:
            return
    raise AssertionError("left SMA never switched on")


def test_boot_sends_info_and_boot_event(sim_so):
    b = Rig(sim_so("r1-fast"), 2, 2)
    msgs = b.reset()
    assert msgs[0].spec.name == "INFO" and msgs[0].token == 0 and msgs[0].robot_name == "test-r1"
    assert _events(msgs, d.EventKind.BOOT)


def test_start_is_refused_until_every_imu_has_been_read(sim_so):
    """Just after a reset no limb's angle is known: a gait started then would begin at its first
    step whatever the robot's state, and level on a ground it has not measured. The board says so."""
    b = Rig(sim_so("r1-fast"), 2, 2)
    b.set_psi(0, 0.0)
    b.set_psi(1, 0.0)
    b.reset()
    nack = b.refused("START", gait=0, direction=0)
    assert nack.error == d.ErrorCode.NOT_ALLOWED and nack.detail == 2
    assert "not known" in str(nack)
    b.run(5)
    assert not _events(b.log, d.EventKind.GAIT_STARTED) and b.duty(0) == 0 and b.duty(1) == 0
    tel = b.client.wait_known_state()
    assert tel is not None and tel.measured == 0
    b.client.start(0, "+x")
    b.run(5)
    assert _events(b.log, d.EventKind.GAIT_STARTED)


def test_start_is_refused_while_an_imu_is_bad_even_with_its_fault_cleared(board):
    board.board.imu_fault(0x69, "no-ack")
    board.run(5)
    assert _events(board.log, d.EventKind.FAULT)[-1].code == d.FaultCode.IMU_NO_ACK
    board.client.clear(d.ClearWhat.FAULTS)
    board.run(5)
    nack = board.refused("START", gait=0, direction=0)
    assert nack.error == d.ErrorCode.NOT_ALLOWED and nack.detail == 2, nack
    board.run(20)
    assert board.duty(0) == 0 and board.duty(1) == 0
    assert not _events(board.log, d.EventKind.GAIT_STARTED)


def test_estop_turns_every_mosfet_off_within_one_tick(board):
    _heating(board)
    assert board.duty(0) == 6000
    board.board.write(encode(Message.new("ESTOP", token=99)))  # timed by the tick, not by a reply
    board.run(1)
    assert all(board.duty(ch) == 0 for ch in range(4))
    board.run(5)  # the ACK and event reach the host at line speed
    assert _events(board.log, d.EventKind.ESTOP)
    assert board.refused("START", gait=0, direction=0).error == d.ErrorCode.ESTOP_LATCHED
    board.run(50)
    assert board.duty(0) == 0
    board.client.clear(d.ClearWhat.ESTOP)
    board.client.start(0, "+x")


def test_imu_that_stops_answering_turns_everything_off_within_two_ticks(board):
    _heating(board)
    board.board.imu_fault(0x68, "no-ack")
    board.run(1)
    assert board.duty(0) == 6000  # one failed read is not yet a fault
    board.run(1)
    assert board.duty(0) == 0 and board.duty(1) == 0
    board.run(5)
    faults = _events(board.log, d.EventKind.FAULT)
    assert faults and faults[-1].code == d.FaultCode.IMU_NO_ACK and faults[-1].detail == 0
    assert board.refused("START", gait=0, direction=0).error == d.ErrorCode.NOT_ALLOWED


def test_imu_garbage_is_a_fault_at_once(board):
    _heating(board)
    board.board.imu_fault(0x69, "garbage")
    board.run(2)
    assert board.duty(0) == 0
    board.run(5)
    assert _events(board.log, d.EventKind.FAULT)[-1].code == d.FaultCode.IMU_BAD_DATA


def test_stuck_imu_is_a_fault_and_clears_when_it_recovers(board):
    board.board.imu_fault(0x68, "stuck")
    board.run(400)
    fault = _events(board.log, d.EventKind.FAULT)
    assert fault and fault[-1].code == d.FaultCode.IMU_BAD_DATA
    board.board.imu_fault(0x68, "ok")
    board.client.clear(d.ClearWhat.FAULTS)
    board.run(10)
    assert _events(board.log, d.EventKind.FAULT_CLEARED)
    board.client.start(0, "+x")


def test_dead_actuator_ends_in_a_state_timeout_with_everything_off(board):
    _heating(board)  # ψ never moves: the plant is dead
    board.run(250)
    fault = _events(board.log, d.EventKind.FAULT)
    # r1-fast: the third on-limit hit on the step (latched, safety.h) may come before the timeout
    assert fault and fault[-1].code in (d.FaultCode.STATE_TIMEOUT, d.FaultCode.SMA_ON_LIMIT)
    assert fault[-1].detail == 0
    assert _events(board.log, d.EventKind.GAIT_STOPPED)[-1].code == d.StopReason.FAULT
    assert board.duty(0) == 0 and board.duty(1) == 0


def test_gait_advances_when_the_limbs_reach_their_states(board):
    _heating(board)
    board.set_psi(0, 25.0)  # left up: 10 reached
    board.run(40)
    reached = _events(board.log, d.EventKind.STATE_REACHED)
    assert [m.detail for m in reached][-1] == 2
    assert board.duty(1) == 6000  # next step 11: right SMA on


@pytest.mark.parametrize(
    "param, value, error",
    [
        (d.ParamId.DRIVE_DUTY, 8001, d.ErrorCode.SAFETY_LIMIT),
        (d.ParamId.DRIVE_DUTY, 0, d.ErrorCode.OUT_OF_RANGE),
        (d.ParamId.HOLD_DUTY, 8001, d.ErrorCode.SAFETY_LIMIT),
        (d.ParamId.HOLD_DUTY, -1, d.ErrorCode.OUT_OF_RANGE),
        (d.ParamId.MAX_ON_MS, 51, d.ErrorCode.SAFETY_LIMIT),
        (d.ParamId.MIN_COOLDOWN_MS, 19, d.ErrorCode.SAFETY_LIMIT),
        (d.ParamId.STATE_TIMEOUT_MS, 201, d.ErrorCode.SAFETY_LIMIT),
        (d.ParamId.PSI_STAR_CDEG, 9500, d.ErrorCode.OUT_OF_RANGE),
        (99, 1, d.ErrorCode.OUT_OF_RANGE),
    ],
)
def test_set_param_outside_the_envelope_is_nacked(board, param, value, error):
    nack = board.refused("SET_PARAM", param=int(param), index=0, value=value)
    assert nack.error == error and nack.detail == int(param)


def test_set_param_inside_the_envelope_is_used(board):
    board.client.set_param(d.ParamId.DRIVE_DUTY, 0, 3000)
    _heating(board)
    assert board.duty(0) == 3000


def test_a_state_held_longer_than_the_state_timeout_is_not_a_timeout(board):
    # r1-fast times a step out after 200 ms; hold_ms may be longer (a slow, deliberate gait)
    board.client.set_param("hold_ms", 0, 400)
    board.client.start(0, "+x")  # at rest, in 00: the first target is reached at once
    board.run(390)
    assert board.duty(0) == 0 and not _events(board.log, d.EventKind.FAULT)
    board.run(30)  # held 400 ms: the next step, 10, heats the left coil
    assert board.duty(0) == 6000 and not _events(board.log, d.EventKind.FAULT)
    board.run(250)  # and 10 never comes: that step times out as before
    assert _events(board.log, d.EventKind.FAULT)[-1].code in (d.FaultCode.STATE_TIMEOUT, d.FaultCode.SMA_ON_LIMIT)


def test_a_cooldown_the_debt_cannot_pay_back_is_refused_and_changes_nothing(board):
    # r1-fast: max_on 50 ms; on-time is paid back at max_on/min_cooldown in steps of 1/256
    board.client.set_param("min_cooldown_ms", 0, 255 * 50)
    nack = board.refused("SET_PARAM", param=int(d.ParamId.MIN_COOLDOWN_MS), index=0, value=256 * 50)
    assert nack.error == d.ErrorCode.OUT_OF_RANGE and "256" in str(nack)
    nack = board.refused("SET_PARAM", param=int(d.ParamId.MAX_ON_MS), index=0, value=49)
    assert nack.error == d.ErrorCode.OUT_OF_RANGE and "256" in str(nack)
    _heating(board)  # ψ never moves: on until the on-time limit (50 ms), then a 12.75 s cool-down
    board.run(300)  # ... and the step times out
    assert board.duty(0) == 0 and _events(board.log, d.EventKind.FAULT)

    def restarted() -> int:
        board.client.stop()
        board.client.clear(d.ClearWhat.FAULTS)
        board.client.start(0, "+x")
        board.run(30)  # 00 reached and held 10 ms, then 10 wants the left coil
        return board.duty(0)

    board.run(6_000)
    assert restarted() == 0  # still owed
    board.run(7_000)
    assert restarted() == 6000  # paid back: it heats again


def test_a_hysteresis_refused_for_one_band_changes_no_band(sim_so):
    b = Rig(sim_so("multi"), 2, 2)  # left: ψ* −10° and 15°, bands 4° wide
    b.reset()
    psi_star, hysteresis = int(d.ParamId.PSI_STAR_CDEG), int(d.ParamId.HYSTERESIS_CDEG)
    b.client.set_param(psi_star, 1, 500)  # ψ* −10° and 5°: 15° apart
    nack = b.refused("SET_PARAM", param=hysteresis, index=0, value=1600)  # 16°: the bands would meet
    assert nack.error == d.ErrorCode.OUT_OF_RANGE and "nothing changed" in str(nack)
    b.client.set_param(psi_star, 1, -300)  # [−5°, −1°] clears the first band as it was, [−12°, −8°]
    b.client.set_param(psi_star, 1, 500)
    b.client.set_param(hysteresis, 0, 1400)  # 14°: both bands take it
    assert b.refused("SET_PARAM", param=psi_star, index=1, value=300).error == \
        d.ErrorCode.OUT_OF_RANGE  # [−4°, 10°] meets the first band, now [−17°, −3°]


def test_a_held_limb_is_held_bang_bang_on_psi(board):
    # r1-fast allows 50 ms of continuous on-time: all of this fits inside it.
    _heating(board)
    board.set_psi(0, 25.0)  # left up, above its hold top (23°): 10 reached, coil off
    board.run(5)
    assert board.duty(0) == 0
    board.client.set_param("hold_duty", 0, 1000)
    board.run(2)
    assert board.duty(0) == 0  # the hold duty is only for synchronised waits (ctl.h)
    board.set_psi(0, 21.5)  # sagging below the hold edge (22°): the drive duty
    board.run(5)
    assert board.duty(0) == 6000
    board.set_psi(0, 22.5)  # above the edge, below the top: still heating (hysteresis)
    board.run(5)
    assert board.duty(0) == 6000
    board.set_psi(0, 23.5)  # the top: off
    board.run(5)
    assert board.duty(0) == 0


def test_load_gait_with_a_forbidden_transition_is_nacked(sim_so):
    b = Rig(sim_so("r1-1act"), 2, 1)
    b.reset()
    nack = b.refused("LOAD_GAIT", states=(0, 2, 3, 1))
    assert nack.error == d.ErrorCode.FORBIDDEN_TRANSITION and nack.detail == 2
    b.client.load_gait((0, 2, 3, 2))
    b.client.start("user", "+x")


@pytest.mark.parametrize("gait, direction", [(0, 2), (0, d.DIR_UNSTATED), (d.GAIT_USER, 2), (d.GAIT_USER, 0xFE)])
def test_start_takes_plus_x_minus_x_or_for_the_loaded_gait_unstated(board, gait, direction):
    board.client.load_gait((0, 2, 1))
    nack = board.refused("START", gait=gait, direction=direction)
    assert nack.error == d.ErrorCode.OUT_OF_RANGE and nack.detail == 2
    board.client.start("user", "unstated")
    board.run(50)
    assert any(m.spec.name == "EVENT" and m.kind == d.EventKind.GAIT_STARTED for m in board.log)


def test_telemetry_comes_at_the_configured_rate(board):
    tel = [m for m in board.run(1000) if m.spec.name == "TELEMETRY"]
    assert 49 <= len(tel) <= 51
    assert len(tel[-1].psi) == 2 and len(tel[-1].duty) == 2
    board.client.set_telemetry_rate(150)
    board.run(0)  # what arrived while the client waited for the ACK
    before = len([m for m in board.log if m.spec.name == "TELEMETRY"])
    board.run(1000)
    assert len([m for m in board.log if m.spec.name == "TELEMETRY"]) - before in (149, 150, 151)


def test_telemetry_faster_than_half_the_uart_is_refused_so_replies_keep_room(board):
    # 115200 baud carries 11,520 B/s; a 2-limb, 2-actuator TELEMETRY frame is budgeted at
    # 32 B, so at most 11520 / 32 / 2 = 180 Hz may go to telemetry.
    assert board.refused("SET_TELEMETRY_RATE", hz=181).error == d.ErrorCode.OUT_OF_RANGE
    board.client.set_telemetry_rate(180)
