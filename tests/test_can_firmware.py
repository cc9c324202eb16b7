"""The firmware speaking CAN: bit timing from the board file, board files with [link]/[can],
the C framing (core/canlink.c on host-sim-can) byte for byte against proleg.protocol.can,
and a stream recorded from the firmware decoded with the generated DBC (cantools)."""

from __future__ import annotations

from pathlib import Path

import cantools
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import BoardError
from proleg.firmware.boards import load_board
from proleg.firmware.build import firmware_gaits, render_project
from proleg.firmware.can_config import (BRP_RANGE, MAX_QUANTA, MIN_QUANTA, TS1_RANGE, TS2_RANGE, BitTiming,
                                        bit_timing)
from proleg.paths import resolve_robot
from proleg.protocol import FrameDecoder, Message
from proleg.protocol.can import CanIds, CanToWire, message_frames
from proleg.protocol.dbc import dbc_text
from proleg.protocol.definition import EventKind, FaultCode, Flag
from proleg.robot import load_robot


# --------------------------------------------------------------------------- bit timing
def _all_timings(clock: int, bitrate: int) -> list[BitTiming]:
    """Every register setting that divides ``clock`` to exactly ``bitrate`` (the oracle)."""
    out = []
    for brp in BRP_RANGE:
        for ts1 in TS1_RANGE:
            for ts2 in TS2_RANGE:
                q = 1 + ts1 + ts2
                if MIN_QUANTA <= q <= MAX_QUANTA and brp * q * bitrate == clock:
                    out.append(BitTiming(clock, brp, ts1, ts2, min(4, ts2)))
    return out


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([8_000_000, 16_000_000, 24_000_000, 36_000_000, 42_000_000, 48_000_000]),
       st.sampled_from([10_000, 20_000, 33_333, 50_000, 100_000, 125_000, 250_000, 333_333, 500_000, 800_000,
                        1_000_000]),
       st.sampled_from([0.75, 0.8, 0.875, 0.9]))
def test_bit_timing_is_exact_and_has_the_sample_point_nearest_the_one_asked_for(clock, bitrate, sp):
    oracle = _all_timings(clock, bitrate)
    if not oracle:
        with pytest.raises(ValueError, match="not reachable exactly"):
            bit_timing(clock, bitrate, sp)
        return
    t = bit_timing(clock, bitrate, sp)
    assert t.brp * t.quanta * bitrate == clock
    assert t.brp in BRP_RANGE and t.ts1 in TS1_RANGE and t.ts2 in TS2_RANGE and 1 <= t.sjw <= min(4, t.ts2)
    assert abs(t.sample_point - sp) == pytest.approx(min(abs(o.sample_point - sp) for o in oracle))


def test_the_bluepill_runs_500_kbit_from_its_36_mhz_apb1_with_the_usual_register_value():
    t = load_board("bluepill-can").can.timing
    # BRP 4, 1 + 15 + 2 quanta: the setting ST's and the CiA calculators give (sample point 88.9 %)
    assert (t.brp, t.ts1, t.ts2, t.bitrate) == (4, 15, 2, 500_000)
    assert t.btr == 0x011E0003  # RM0008 §24.9.2: BRP-1 | TS1-1 << 16 | TS2-1 << 20 | SJW-1 << 24


# --------------------------------------------------------------------------- board files
def _board(tmp_path: Path, can: str, link: str = '[link]\ntranspor = "can"\n') -> Path:
    p = tmp_path / "b.toml"
    p.write_text('[board]\nextends = "bluepill-f103"\nname = "x"\n' + link + can)
    return p


CAN_OK = '[can]\nrx = "PA11"\ntx = "PA12"\nbitrate = 500000\nclock_hz = 36000000\n'


def test_a_variant_board_file_extends_its_base_and_adds_the_can_link():
    base, can = load_board("bluepill-f103"), load_board("bluepill-can")
    assert (base.transport, base.can) == ("uart", None)
    assert can.transport == "can" and can.can.pins == "PA11/PA12" and can.can.remap == 0
    assert (can.pwm_pins, can.i2c_buses, can.flash_methods, can.budget) == (
        base.pwm_pins, base.i2c_buses, base.flash_methods, base.budget)


@pytest.mark.parametrize("can, link, message", [
    (CAN_OK.replace("500000", "333000"), '[link]\ntransport = "can"\n', "can.bitrate: 333000 bit/s is not reachable"),
    (CAN_OK.replace('"PA12"', '"PB9"'), '[link]\ntransport = "can"\n', "PA11/PB9 is not a pin pair"),
    ("", '[link]\ntransport = "can"\n', 'transport = "can" needs a [can] table'),
    (CAN_OK, '[link]\ntransport = "spi"\n', "link.transport: expected one of uart, can"),
    (CAN_OK + "node = 16\n", "", "can.node: expected a whole number in 0..15"),
])
def test_a_bad_can_table_is_one_line_naming_the_key(tmp_path, can, link, message):
    with pytest.raises(BoardError) as e:
        load_board(_board(tmp_path, can, link))
    assert message in str(e.value) and "\n" not in str(e.value)


def test_the_remapped_pins_pb8_pb9_route_with_can_remap_2(tmp_path):
    b = load_board(_board(tmp_path, CAN_OK.replace("PA11", "PB8").replace("PA12", "PB9"), '[link]\ntransport = "can"\n'))
    assert b.can.remap == 2


def test_uart_boards_carry_no_can_code_and_can_boards_carry_it():
    robot = load_robot(resolve_robot("paper-r1"))
    gaits = firmware_gaits(robot)
    for name, can in (("arduino-nano", False), ("bluepill-f103", False), ("host-sim", False),
                      ("bluepill-can", True), ("host-sim-can", True)):
        files = render_project(robot, load_board(name), gaits)
        has = {k for k in files if Path(k).name.startswith("can")}
        assert bool(has) == can, name
        assert f"#define CFG_LINK_CAN {int(can)}" in files["gen/robot_config.h"]
    files = render_project(robot, load_board("bluepill-can"), gaits)
    assert "#define CFG_CAN_BTR 0x011E0003UL" in files["gen/robot_config.h"]


# --------------------------------------------------------------------------- the C framing, byte for byte
@pytest.fixture(scope="module")
def can_board():
    from proleg.sim.board import SimBoard
    from proleg.sim.closed_loop import sim_library

    robot = load_robot(resolve_robot("paper-r1"))
    return SimBoard(sim_library(robot, board="host-sim-can"))


def _command(board, msg: Message, ids: CanIds) -> None:
    for arbitration_id, data in message_frames(msg, ids, from_host=True):
        board.can_write(arbitration_id, data)


def _decode(frames, ids: CanIds) -> list[Message]:
    rx, dec = CanToWire(ids, from_host=False), FrameDecoder()
    out = []
    for i, d in frames:
        out += dec.feed(rx.feed(i, d))
    assert rx.dropped == 0
    return out


def test_the_firmware_frames_every_message_exactly_as_the_python_mapping_does(can_board):
    ids = CanIds(node=0, base=0x100)
    can_board.reset(1)
    _command(can_board, Message.new("GET_INFO", token=9), ids)
    can_board.run_ticks(150)  # the IMUs read: the board takes a START
    _command(can_board, Message.new("START", token=10, gait=0, direction=0), ids)
    _command(can_board, Message.new("GET_STATS", token=11), ids)
    can_board.run_ticks(300)
    frames = can_board.can_read()
    messages = _decode(frames, ids)
    names = [m.name for m in messages]
    assert {"INFO", "EVENT", "ACK", "STATS", "TELEMETRY"} <= set(names)
    expected = [f for m in messages for f in message_frames(m, ids, from_host=False)]
    assert frames == expected  # identifiers, segment headers, padding, fixed layouts: byte for byte
    assert [m.token for m in messages if m.name in ("INFO", "ACK", "STATS") and m.token] == [9, 10, 11]


def test_frames_for_other_nodes_never_reach_the_firmware(can_board):
    can_board.reset(1)
    can_board.run_ticks(5)
    can_board.can_read()
    _command(can_board, Message.new("ESTOP", token=3), CanIds(node=1))
    _command(can_board, Message.new("PING", token=4), CanIds(node=0, base=0x200))
    can_board.run_ticks(50)
    messages = _decode(can_board.can_read(), CanIds())
    assert not [m for m in messages if m.name in ("ACK", "NACK")]
    assert not any(m.flags & Flag.ESTOP for m in messages if m.name == "TELEMETRY")


def test_a_lost_segment_costs_that_command_only_and_is_counted_as_a_framing_error(can_board):
    ids = CanIds()
    can_board.reset(1)
    segments = message_frames(Message.new("LOAD_GAIT", token=5, states=(0, 2, 3, 1)), ids, from_host=True)
    assert len(segments) >= 2
    for i, d in segments[:1] + segments[2:]:  # the second segment is lost on the bus
        can_board.can_write(i, d)
    _command(can_board, Message.new("GET_STATS", token=6), ids)
    can_board.run_ticks(50)
    replies = [m for m in _decode(can_board.can_read(), ids) if m.name in ("ACK", "NACK", "STATS")]
    assert [m.name for m in replies] == ["STATS"]
    assert replies[0].framing_errors == 1 and replies[0].crc_errors == 0


# --------------------------------------------------------------------------- a recorded stream, decoded with the DBC
def test_a_can_stream_recorded_from_the_firmware_decodes_with_the_generated_dbc(tmp_path):
    """host-sim-can walks a gait on the plant, one IMU goes silent (a FAULT): every frame the
    firmware put on python-can's virtual bus is recorded (python-can's ASC logger), read back,
    and decoded with the DBC; each value equals the protocol decoder's."""
    import can

    from proleg.link import RobotClient
    from proleg.link.sim_can_link import sim_can_link
    from proleg.sim.simulators import open_simulated

    robot = load_robot(resolve_robot("paper-r1"))
    sim = open_simulated(robot, "host-sim", link="can", seed=2)
    channel = f"proleg-record-{id(tmp_path)}"
    sniffer = can.Bus(interface="virtual", channel=channel)
    log = tmp_path / "run.asc"
    writer = can.Logger(str(log))
    client = RobotClient(sim_can_link(sim, channel=channel), max_limbs=2, max_channels=2)
    sent: list[Message] = []
    try:
        client.connect()
        while sniffer.recv(0) is not None:  # what came before (BOOT, INFO): not part of the recording
            pass
        client.start(0, "+x")
        injected = False
        while client.link.clock() < 3.0:
            m = client.recv(0.05)
            if m is not None and m.name in ("TELEMETRY", "EVENT"):
                sent.append(m)
            if not injected and client.link.clock() > 2.0:
                sim.inject(f"imu-silent:{robot.limbs[1].name}")
                injected = True
            while (f := sniffer.recv(0)) is not None:
                writer.on_message_received(f)
        while (f := sniffer.recv(0)) is not None:
            writer.on_message_received(f)
    finally:
        writer.stop()
        client.close()
        sniffer.shutdown()
    db = cantools.database.load_string(dbc_text(nodes=(0,), robot=robot), "dbc")
    tel = {m.seq: m for m in sent if m.name == "TELEMETRY"}
    events = {(m.time_ms, EventKind(m.kind).name): m for m in sent if m.name == "EVENT"}
    current: dict = {}
    n_tel = n_ev = 0
    kinds = set()
    for frame in can.LogReader(str(log)):
        if frame.arbitration_id == 0x100:  # the host's own commands
            continue
        msg = db.get_message_by_frame_id(frame.arbitration_id)
        values = msg.decode(bytes(frame.data))
        if msg.name == "EVENT":
            e = events[(values["time_ms"], str(values["kind"]))]
            n_ev += 1
            if e.kind == EventKind.FAULT:
                assert values["fault_code"] == FaultCode(e.code).name and values["fault_detail"] == e.detail
            kinds.add(str(values["kind"]))
        elif msg.name.startswith("TELEMETRY"):
            current.update(values)
            if msg.name == "TELEMETRY_DUTY_0":
                t = tel[current["seq"]]
                n_tel += 1
                assert (current["seq"], current["time_ms"]) == (t.seq, t.time_ms)
                left, right = (limb.name.replace("-", "_") for limb in robot.limbs)
                assert current[f"psi_{left}"] == pytest.approx(t.psi[0] / 100)
                assert current[f"psi_{right}"] == pytest.approx(t.psi[1] / 100)
                for f in Flag:
                    if f.name:
                        assert bool(current[f"flag_{f.name.lower()}"]) == bool(t.flags & f), f.name
                current = {}
    assert n_tel >= 100 and n_ev >= 3
    assert {"GAIT_STARTED", "FAULT"} <= kinds


# --------------------------------------------------------------------------- the console on the bus
def test_the_console_drives_the_can_firmware_served_in_real_time_on_a_virtual_bus():
    """``CanPort.start`` serves host-sim-can's firmware on a python-can bus in real time; the
    console, as `proleg console --can CHANNEL --interface virtual` runs it, connects, shows the
    telemetry and stops the robot on leaving."""
    import io

    import can

    from proleg.cli.link_commands import console_main
    from proleg.sim.can_port import CanPort
    from proleg.sim.simulators import open_simulated

    robot = load_robot(resolve_robot("paper-r1"))
    channel = "proleg-console-can"
    bus = can.Bus(interface="virtual", channel=channel)
    port = CanPort(open_simulated(robot, "host-sim", link="can"), bus).start(speed=1.0)
    err, out = io.StringIO(), io.StringIO()
    try:
        code = console_main(can_channel=channel, interface="virtual", bitrate=500000, node=0, plain=True,
                            duration_s=0.5, out=out, err=err)
    finally:
        port.stop()
        bus.shutdown()
    assert code == 0, err.getvalue()
    assert out.getvalue().count("seq=") >= 10  # the firmware's telemetry, through the console
    assert f"robot stopped on CAN {channel} (virtual, 500000 bit/s) node 0" in err.getvalue()
    assert port.frames_in > 0 and port.frames_out > 0


# --------------------------------------------------------------------------- the exact bluepill image on arm-emu
def test_the_bluepill_can_image_frames_every_message_as_the_python_mapping_does_through_the_bxcan_model():
    """bluepill-can's firmware.elf on arm-emu: commands go in through the bxCAN model's filter
    and FIFO, the replies, events and telemetry come out of its mailboxes, byte for byte the
    frames proleg.protocol.can makes of the messages they carry; a frame for another node
    is dropped by the filter bank the firmware set up."""
    from proleg.sim.simulated_boards import SIMULATED_BOARDS

    missing = SIMULATED_BOARDS["arm-emu"].missing()
    if missing:
        pytest.skip(missing)
    from proleg.emu.arm import ArmEmuRobot

    robot = load_robot(resolve_robot("paper-r1"))
    board = ArmEmuRobot(robot, firmware_board="bluepill-can").board
    ids = CanIds()
    board.run_us(20_000)
    assert board.can.on_bus and board.can.bitrate == pytest.approx(500_000)
    _command(board, Message.new("GET_INFO", token=21), ids)
    _command(board, Message.new("PING", token=22), CanIds(node=3))  # not this node: filtered
    board.run_us(150_000)  # the IMUs read: the board takes a START
    _command(board, Message.new("START", token=23, gait=0, direction=1), ids)
    board.run_us(150_000)
    frames = board.can_read()
    messages = _decode(frames, ids)
    assert frames == [f for m in messages for f in message_frames(m, ids, from_host=False)]
    replies = [m for m in messages if m.name in ("INFO", "ACK", "NACK")]
    assert [(m.name, m.token) for m in replies] == [("INFO", 0), ("INFO", 21), ("ACK", 23)]
    assert replies[1].board == "bluepill-can"
    assert board.can.dropped_by_filter == 1  # the other node's PING (one segment)
    assert sum(m.name == "TELEMETRY" for m in messages) >= 5
