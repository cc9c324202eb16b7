"""Host unit tests of the hand-written firmware core (firmware_templates/core, hal/sim).

Each C test in tests/c/ is compiled with the host cc (C99, -Wall -Wextra -Werror -pedantic,
AddressSanitizer/UBSan when the compiler has them) against a robot_config.h/gait_table.c
rendered by ``render_config`` from a small robot described here, then run; its output
names every C test case. The last tests load the whole firmware built for the simulated
board and talk to it in its own protocol (E-stop, IMU faults, safety envelope).
"""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from proleg.errors import BuildError
from proleg.firmware.render import render_config
from proleg.protocol import definition as d
from proleg.link import CommandRefused, RobotClient
from proleg.link.sim_link import SimLink
from proleg.protocol.codec import Message, encode
from proleg.protocol.render import render_c
from proleg.robot import robot_from_dict
from proleg.sim.board import SimBoard
from proleg.transitions import TransitionTable

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
SIM = ROOT / "firmware_templates" / "hal" / "sim"
CDIR = Path(__file__).resolve().parent / "c"
CC = shutil.which("cc") or shutil.which("gcc")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-g", "-O1"]

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")

SIM_BOARD = {
    "name": "host-sim",
    "family": "sim",
    "pwm_channels": ["SIM0", "SIM1", "SIM2", "SIM3"],
    "i2c": {"hz": 400000, "imu_addresses": [0x68, 0x69]},
    "uart_baud": 115200,
    "clock_hz": 0,
}


def _robot_doc(**over):
    doc = {
        "robot": {"name": "test-r1"},
        "limb": [
            {"name": "left", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a0"},
            {"name": "right", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a1"},
        ],
        "actuator": [{"name": "a0", "channel": 0}, {"name": "a1", "channel": 1}],
        "transitions": {"matrix": [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]},
        "safety": {"max_on_ms": 50, "min_cooldown_ms": 20, "max_duty": 0.8, "state_timeout_ms": 200},
        "control": {
            "tick_hz": 1000,
            "drive_duty": 0.6,
            "debounce_ticks": 3,
            "hold_ms": 10,
            "telemetry_hz": 50,
            "hold_margin_deg": 1.0,
        },
    }
    doc.update(over)
    return doc


def _gait(*states):
    return SimpleNamespace(states=tuple(states))


def _r1_fast():
    robot = robot_from_dict(_robot_doc(), Path("tests/r1-fast.toml"))
    return robot, {"+x": [_gait(0, 2, 3, 1, 0), _gait(0, 2, 0)], "-x": []}, SIM_BOARD


def _r1_stroke():
    """R1 with full strokes ([[limb]] stroke_deg: left 60°, right 50°, the right leading the way
    down; test_ctl_stroke.c)."""
    doc = _robot_doc()
    doc["limb"][0]["stroke_deg"] = 60.0
    doc["limb"][1]["stroke_deg"] = 50.0
    doc["control"]["stroke_fall_lead"] = "right"
    robot = robot_from_dict(doc, Path("tests/r1-stroke.toml"))
    return robot, {"+x": [_gait(0, 3, 0)], "-x": []}, SIM_BOARD


def _r1_one_actuator():
    doc = _robot_doc(
        actuator=[{"name": "a0", "channel": 0}],
        transitions={"matrix": [[0, "x", 1, "x"], ["x", "x", "x", "x"], [-1, "x", 0, 1], ["x", "x", 0, 0]]},
    )
    doc["limb"][1]["actuator"] = "a0"
    robot = robot_from_dict(doc, Path("tests/r1-1act.toml"))
    return robot, {"+x": [_gait(0, 2, 3, 2, 0)], "-x": []}, SIM_BOARD


def _multi_level():
    doc = _robot_doc(
        limb=[
            {"name": "left", "levels": 3, "psi_star_deg": [-10.0, 15.0], "hysteresis_deg": 4.0, "actuator": "a0"},
            {"name": "right", "psi_star_deg": [30.0], "hysteresis_deg": 2.0, "actuator": "a1"},
        ],
        transitions={"matrix": [[0 if a == b else 1 for b in range(6)] for a in range(6)]},
    )
    robot = robot_from_dict(doc, Path("tests/multi.toml"))
    return robot, {"+x": [_gait(0, 3, 5, 0)], "-x": [_gait(0, 1, 0)]}, SIM_BOARD


def _big():
    """128 states (7 binary limbs): the allowed transitions become a sorted key list."""
    base = robot_from_dict(_robot_doc(), Path("tests/big.toml"))
    limb = base.limbs[0]
    limbs = tuple(dataclasses.replace(limb, name=f"l{i}", actuator="a0") for i in range(7))
    src, dst = [], []
    for a in range(128):
        for b in {(a + 1) % 128, (3 * a + 7) % 128}:
            if a != b:
                src.append(a)
                dst.append(b)
    table = TransitionTable.from_edges((2,) * 7, src, dst, np.ones(len(src)))
    robot = dataclasses.replace(base, limbs=limbs, actuators=base.actuators[:1], transitions=table)
    board = dict(SIM_BOARD, i2c={"imu_addresses": list(range(0x68, 0x6F))})
    return robot, {"+x": [_gait(0, 1, 0)], "-x": []}, board


def _inchworm_entry():
    """robots/inchworm-3.toml with gaits off the rest state (entry paths, test_seq_entry.c)."""
    from proleg.robot import load_robot

    robot = load_robot(Path(__file__).resolve().parents[1] / "robots" / "inchworm-3.toml")
    board = dict(SIM_BOARD, i2c={"imu_addresses": [0x68, 0x69, 0x6A]})
    return robot, {"+x": [_gait(3, 7, 3), _gait(7, 3, 7)], "-x": [_gait(1, 5, 1)]}, board


CONFIGS = {"inch-entry": _inchworm_entry, "r1-fast": _r1_fast, "r1-stroke": _r1_stroke, "r1-1act": _r1_one_actuator, "multi": _multi_level, "big": _big}

# C test → (config, core sources, extra sources, defines)
C_TESTS = {
    "test_psi.c": ("r1-fast", ["psi.c", "angle.c"], [], []),
    "test_psi_multilevel.c": ("multi", ["psi.c", "angle.c", "seq.c", "count.c"], ["gait_table.c"], []),
    "test_sma.c": ("r1-fast", ["sma.c", "elapsed.c"], [], []),
    "test_safety.c": ("r1-fast", ["safety.c", "elapsed.c"], [], []),
    "test_ctl.c": ("r1-fast", ["ctl.c", "psi.c", "angle.c", "limbmap.c"], [], []),
    "test_ctl_shared.c": ("r1-1act", ["ctl.c", "psi.c", "angle.c", "limbmap.c"], [], []),
    "test_ctl_stroke.c": ("r1-stroke", ["ctl.c", "psi.c", "angle.c", "limbmap.c"], [], []),
    "test_ctl_chain.c": ("inch-entry", ["ctl.c", "psi.c", "angle.c", "limbmap.c"], [], []),
    "test_seq.c": ("r1-fast", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_transitions.c": ("r1-1act", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_edges.c": ("big", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_seq_entry.c": ("inch-entry", ["seq.c", "psi.c", "angle.c", "count.c"], ["gait_table.c"], []),
    "test_sim_mpu6050.c": ("r1-fast", ["mpu6050.c", "imubus.c"], [SIM / "sim_mpu6050.c"], ["-DFAKE_HAL_SIM_MPU"]),
}


@pytest.fixture(scope="session")
def sanitizers(tmp_path_factory) -> list[str]:
    flags = ["-fsanitize=address,undefined", "-fno-omit-frame-pointer"]
    d_ = tmp_path_factory.mktemp("san")
    (d_ / "t.c").write_text("int main(void) { return 0; }\n")
    ok = subprocess.run([CC, *flags, str(d_ / "t.c"), "-o", str(d_ / "t")], capture_output=True).returncode == 0
    return flags if ok else []


@pytest.fixture(scope="session")
def rendered(tmp_path_factory):
    cache: dict[str, Path] = {}

    def get(name: str) -> Path:
        if name not in cache:
            robot, gaits, board = CONFIGS[name]()
            out = tmp_path_factory.mktemp(f"cfg-{name}")
            for fname, text in render_config(robot, gaits, board).items():
                (out / fname).write_text(text)
            for fname, text in render_c(len(robot.limbs), len(robot.actuators)).items():
                (out / fname).write_text(text)
            cache[name] = out
        return cache[name]

    return get


@pytest.mark.parametrize("test_file", sorted(C_TESTS))
def test_c_unit(test_file, rendered, sanitizers, tmp_path):
    config, core, extra, defines = C_TESTS[test_file]
    gen = rendered(config)
    sources = [CDIR / test_file, CDIR / "fake_hal.c"] + [CORE / c for c in core]
    sources += [gen / e if isinstance(e, str) else e for e in extra]
    exe = tmp_path / test_file.removesuffix(".c")
    cmd = [CC, *CFLAGS, *sanitizers, *defines, f"-I{CORE}", f"-I{gen}", f"-I{SIM}", f"-I{CDIR}"]
    cmd += [str(s) for s in sources] + ["-o", str(exe), "-lm"]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    print(run.stdout)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "FAIL" not in run.stdout


def test_render_is_deterministic_and_names_its_inputs():
    robot, gaits, board = _r1_fast()
    a = render_config(robot, gaits, board)
    b = render_config(robot, gaits, board)
    assert a == b
    assert set(a) == {"robot_config.h", "gait_table.c"}
    head = a["robot_config.h"].splitlines()[:4]
    assert any("proleg.firmware.render" in line for line in head)
    assert any("sha256" in line for line in head)
    assert "#define CFG_GAIT_TABLE_HASH 0x" in a["robot_config.h"]


def test_gait_hash_changes_with_the_gaits_but_build_inputs_do_not_leak_time():
    robot, gaits, board = _r1_fast()
    a = render_config(robot, gaits, board)["robot_config.h"]
    b = render_config(robot, {"+x": gaits["+x"][:1], "-x": []}, board)["robot_config.h"]
    pick = lambda t: [line for line in t.splitlines() if "CFG_GAIT_TABLE_HASH" in line]  # noqa: E731
    assert pick(a) != pick(b)


def test_render_refuses_a_channel_the_board_lacks():
    robot, gaits, board = _r1_fast()
    with pytest.raises(BuildError, match="channel"):
        render_config(robot, gaits, dict(board, pwm_channels=["SIM0"]))


def test_render_refuses_a_pin_the_avr_hal_cannot_drive():
    robot, gaits, board = _r1_fast()
    avr = dict(board, name="nano", family="avr", pwm_channels=["D9", "D7"])
    with pytest.raises(BuildError, match="D7"):
        render_config(robot, gaits, avr)


def test_render_refuses_a_band_reaching_90_degrees():
    """The loader refuses such a file (tests/test_robot_file.py); a Robot made otherwise is
    still refused by the renderer, whose C would otherwise wrap the band's edge."""
    from dataclasses import replace

    robot = robot_from_dict(_robot_doc(), Path("tests/steep.toml"))
    steep = replace(robot, limbs=(replace(robot.limbs[0], psi_star_deg=(89.5,)), *robot.limbs[1:]))
    with pytest.raises(BuildError, match="90"):
        render_config(steep, {"+x": [], "-x": []}, SIM_BOARD)


def test_no_gait_in_either_direction_still_renders_valid_c(rendered, tmp_path):
    robot, _, board = _r1_fast()
    files = render_config(robot, {"+x": [], "-x": []}, board)
    assert "#define CFG_N_GAITS_PX 0u" in files["robot_config.h"]
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    r = subprocess.run(
        [CC, *CFLAGS, f"-I{CORE}", f"-I{tmp_path}", "-c", str(tmp_path / "gait_table.c"), "-o", str(tmp_path / "g.o")],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr


# ------------------------------------------------------------------ the whole firmware on the simulated board


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
    b.run(5)
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
    board.run(1000)
    tel = [m for m in board.log if m.spec.name == "TELEMETRY"]
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
