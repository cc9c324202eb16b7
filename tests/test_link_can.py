"""CAN: the frame mapping, the DBC, and the client over python-can's virtual bus."""

from __future__ import annotations

import itertools

import can
import cantools
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import LinkError
from proleg.link import RobotClient
from proleg.link.can_link import CanLink
from proleg.sim.can_bridge import CanBoardBridge
from proleg.protocol.can import CanIds, CanToWire, message_frames
from proleg.protocol.dbc import build_database, dbc_text, write_dbc
from fake_board import FakeBoard
from proleg.protocol import FrameDecoder, Message

_channels = (f"proleg-test-{i}" for i in itertools.count())

u8 = st.integers(0, 0xFF)
u16 = st.integers(0, 0xFFFF)
u32 = st.integers(0, 0xFFFFFFFF)
i16 = st.integers(-0x8000, 0x7FFF)

telemetry = st.builds(
    lambda seq, t, m, tg, g, d, s, f, psi, duty: Message.new(
        "TELEMETRY", seq=seq, time_ms=t, measured=m, target=tg, gait=g, direction=d, step=s, flags=f,
        psi=tuple(psi), duty=tuple(duty)),
    u16, u32, u16, u16, u8, u8, u8, u16, st.lists(i16, max_size=8), st.lists(u16, max_size=8))
replies = st.one_of(
    st.builds(lambda t, c: Message.new("ACK", token=t, cmd=c), u8, u8),
    st.builds(lambda t, c, e, d: Message.new("NACK", token=t, cmd=c, error=e, detail=d), u8, u8, u8, u16),
    st.builds(lambda t, k, c, d: Message.new("EVENT", time_ms=t, kind=k, code=c, detail=d), u32, u8, u8, u16),
    st.builds(lambda t, *v: Message.new("STATS", token=t, **dict(zip(
        ("rx_ok", "crc_errors", "framing_errors", "unknown_ids", "bad_length", "bad_value", "nacks",
         "tx_frames", "tx_dropped", "tick_overruns"), v))), u8, *([u32] * 10)),
)
commands = st.one_of(
    st.builds(lambda t, s: Message.new("LOAD_GAIT", token=t, states=tuple(s)), u8, st.lists(u16, max_size=24)),
    st.builds(lambda t, p, i, v: Message.new("SET_PARAM", token=t, param=p, index=i, value=v), u8, u8, u8,
              st.integers(-2**31, 2**31 - 1)),
)


def _through_can(msgs: list[Message], ids: CanIds, from_host: bool) -> list[Message]:
    rx = CanToWire(ids, from_host=from_host)
    dec = FrameDecoder()
    out = []
    for m in msgs:
        for arbitration_id, data in message_frames(m, ids, from_host=from_host):
            assert len(data) <= 8 and arbitration_id <= 0x7FF
            out += dec.feed(rx.feed(arbitration_id, data))
    assert rx.dropped == 0
    return out


@settings(max_examples=150, deadline=None)
@given(st.lists(st.one_of(telemetry, replies), min_size=1, max_size=6), st.integers(0, 15))
def test_robot_messages_survive_the_can_mapping(msgs, node):
    assert _through_can(msgs, CanIds(node=node), from_host=False) == msgs


@settings(max_examples=80, deadline=None)
@given(st.lists(commands, min_size=1, max_size=4))
def test_commands_survive_segmentation(msgs):
    assert _through_can(msgs, CanIds(node=5, base=0x300), from_host=True) == msgs


def test_a_missing_telemetry_frame_drops_that_message_only():
    ids = CanIds(node=1)
    t1 = Message.new("TELEMETRY", seq=1, time_ms=10, measured=0, target=1, gait=0, direction=0, step=0, flags=0,
                     psi=(100, 200), duty=(0, 5000))
    t2 = Message(t1.name, {**t1.fields, "seq": 2})
    frames = message_frames(t1, ids, from_host=False)
    rx, dec = CanToWire(ids, from_host=False), FrameDecoder()
    out = []
    for arbitration_id, data in frames[:2] + frames[3:] + message_frames(t2, ids, from_host=False):
        out += dec.feed(rx.feed(arbitration_id, data))
    assert [m.seq for m in out] == [2] and rx.dropped == 1


def test_other_nodes_frames_are_ignored():
    mine, other = CanIds(node=2), CanIds(node=3)
    ack = Message.new("ACK", token=7, cmd=1)
    rx = CanToWire(mine, from_host=False)
    assert all(rx.feed(i, d) == b"" for i, d in message_frames(ack, other, from_host=False))


def test_id_layout_is_base_plus_slot_and_node():
    ids = CanIds(node=3, base=0x100)
    assert [ids.id(s) for s in range(8)] == [0x103, 0x113, 0x123, 0x133, 0x143, 0x153, 0x163, 0x173]
    with pytest.raises(LinkError, match="node id 16"):
        CanIds(node=16)


def test_client_runs_over_a_virtual_can_bus_shared_with_another_robot():
    channel = next(_channels)
    buses = [can.Bus(interface="virtual", channel=channel) for _ in range(2)]
    boards = [FakeBoard(build_id=0xA0), FakeBoard(build_id=0xB0)]
    bridges = [CanBoardBridge(b, bus, node=n).start(speed=1.0) for b, bus, n in zip(boards, buses, (1, 2))]
    try:
        with RobotClient(CanLink(channel, "virtual", node=2)) as client:
            assert client.connect().build_id == 0xB0
            client.start(0, "-x")
            frames = list(client.telemetry(count=5))
            assert all(f.direction == 1 for f in frames[1:])
            assert client.stats.lost == 0 and client.stats.corrupt == 0
        assert [m.name for m in boards[0].received] == []  # robot 1 heard nothing meant for robot 2
        assert [m.name for m in boards[1].received][-1] == "START"
    finally:
        for b in bridges:
            b.stop()
        for bus in buses:
            bus.shutdown()


def test_generated_dbc_decodes_simulated_telemetry_on_the_bus():
    channel = next(_channels)
    robot_bus = can.Bus(interface="virtual", channel=channel)
    sniffer = can.Bus(interface="virtual", channel=channel)
    board = FakeBoard()
    board.running, board.sequence = True, (0, 2, 3, 1)
    bridge = CanBoardBridge(board, robot_bus, node=4)
    sent: list[Message] = []
    recorder = FrameDecoder()
    original_read = board.read

    def read_and_keep() -> bytes:  # what the firmware sent, decoded independently
        data = original_read()
        sent.extend(m for m in recorder.feed(data) if m.name == "TELEMETRY")
        return data

    board.read = read_and_keep  # type: ignore[method-assign]
    for _ in range(100):
        bridge.step(0.01)
    db = cantools.database.load_string(dbc_text(nodes=(4,)), "dbc")
    decoded: dict[int, dict] = {}
    current: dict = {}
    while (frame := sniffer.recv(0.05)) is not None:
        msg = db.get_message_by_frame_id(frame.arbitration_id)
        values = msg.decode(frame.data, decode_choices=False)
        if msg.name == "TELEMETRY_A":
            current = dict(values)
            decoded[int(values["seq"])] = current
        else:
            current.update(values)
    robot_bus.shutdown()
    sniffer.shutdown()
    assert len(sent) >= 15 and len(decoded) == len(sent)
    for m in sent:
        d = decoded[m.seq]
        for k in ("time_ms", "measured", "target", "gait", "direction", "step", "flags"):
            assert d[k] == m[k], k
        assert d["psi_count"] == len(m.psi) and d["duty_count"] == len(m.duty)
        for i, p in enumerate(m.psi):
            assert d[f"psi_{i}"] == pytest.approx(p / 100)  # degrees
        for j, u in enumerate(m.duty):
            assert d[f"duty_{j}"] == pytest.approx(u / 100)  # percent


def test_dbc_describes_every_frame_of_each_node(tmp_path):
    path = write_dbc(tmp_path / "proleg.dbc", nodes=(0, 7), base=0x200)
    db = cantools.database.load_file(str(path))
    assert {m.frame_id for m in db.messages} == {0x200 + (s << 4) + n for s in range(8) for n in (0, 7)}
    assert db.get_message_by_name("TELEMETRY_PSI_0_N7").get_signal_by_name("psi_0").unit == "deg"
    assert len(build_database().messages) == 8


def test_unknown_can_interface_is_one_clear_link_error():
    with pytest.raises(LinkError) as e:
        CanLink("can0", "no-such-interface")
    assert "unknown or unavailable CAN interface 'no-such-interface'" in str(e.value)
    assert "\n" not in str(e.value)
