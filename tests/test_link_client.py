"""RobotClient over the simulated-board link with the Python fake firmware."""

from __future__ import annotations

import pytest

from proleg.errors import LinkError
from proleg.link import BufferedReader, CommandRefused, Notifier, RobotClient
from fake_board import FakeBoard
from proleg.link.sim_link import SimLink
from proleg.protocol import BY_NAME, MESSAGES, ErrorCode, Message, ParamId, encode
from proleg.protocol.definition import reply_answers


def make(**board_kw) -> tuple[FakeBoard, RobotClient]:
    board = FakeBoard(**board_kw)
    client = RobotClient(SimLink(board, description="sim fake"))
    client.connect()
    return board, client


def test_connect_handshake_reports_robot_info():
    board, client = make()
    assert client.info is not None
    assert client.info.robot_name == "paper-r1"
    assert client.info.limbs == 2 and client.info.tick_hz == 1000
    assert client.info.header()["gait_table_hash"] == f"{board.gait_hash:08x}"


def test_commands_carry_fresh_tokens_and_wait_for_their_ack():
    board, client = make()
    client.ping()
    client.start(0, "+x")
    client.stop()
    client.set_telemetry_rate(100)
    client.set_param("drive_duty", 0, 5000)
    client.load_gait([0, 2, 3, 1])
    client.start("user", "-x")
    client.estop()
    client.clear()
    names = [m.name for m in board.received]
    # the clear asks whether a coil is given up (the fallback's), to take it back
    assert names == ["GET_INFO", "PING", "START", "STOP", "SET_TELEMETRY_RATE", "SET_PARAM", "LOAD_GAIT",
                     "START", "ESTOP", "CLEAR", "GET_ACTUATOR_MAP"]
    tokens = [m.token for m in board.received]
    assert len(set(tokens)) == len(tokens) and 0 not in tokens
    assert board.drive_duty == 5000 and board.telemetry_hz == 100 and board.user_gait == (0, 2, 3, 1)


def test_nack_raises_command_refused_naming_the_error_code():
    board, client = make()
    client.estop()
    with pytest.raises(CommandRefused, match="ESTOP_LATCHED") as e:
        client.start(0)
    assert e.value.error == ErrorCode.ESTOP_LATCHED
    with pytest.raises(CommandRefused, match="SAFETY_LIMIT"):
        client.set_param(ParamId.DRIVE_DUTY, 0, 9000)
    assert client.stats.nacks == 2


def test_silent_robot_times_out_with_one_clear_line():
    board, client = make()
    board.silent = True
    with pytest.raises(LinkError) as e:
        client.ping()
    assert str(e.value) == "no reply to PING within 0.5 s on sim fake"
    assert client.stats.timeouts == 1


def test_a_stale_ack_for_another_command_with_the_same_token_does_not_confirm_estop():
    board, client = make()
    board.silent = True  # the ESTOP is lost on the way...
    token = client._token % 255 + 1  # ...and the token it will carry was last used by a PING
    board._send(Message.new("ACK", token=token, cmd=BY_NAME["PING"].id))
    with pytest.raises(LinkError, match="no reply to ESTOP"):
        client.estop()
    assert [m.name for m in board.received[-1:]] == ["ESTOP"]


def test_a_nack_for_another_command_with_the_same_token_does_not_refuse_this_one():
    board, client = make()
    token = client._token % 255 + 1
    board._send(Message.new("NACK", token=token, cmd=BY_NAME["START"].id, error=int(ErrorCode.NOT_ALLOWED), detail=0))
    client.stop()  # answered by its own ACK, the stale NACK is ignored


def test_each_command_waits_for_the_reply_the_protocol_definition_names():
    for spec in MESSAGES:
        if spec.direction == "h2r":
            assert spec.reply in ("ACK", "INFO", "STATS", "ACTUATOR_MAP", "LEVEL")
    assert BY_NAME["GET_INFO"].reply == "INFO" and BY_NAME["GET_STATS"].reply == "STATS"
    assert BY_NAME["GET_LEVEL"].reply == "LEVEL" and BY_NAME["CALIBRATE_LEVEL"].reply == "ACK"
    stop = BY_NAME["STOP"]
    assert reply_answers("ACK", {"token": 3, "cmd": stop.id}, stop)
    assert reply_answers("NACK", {"token": 3, "cmd": stop.id}, stop)
    assert not reply_answers("ACK", {"token": 3, "cmd": BY_NAME["PING"].id}, stop)
    assert not reply_answers("INFO", {"token": 3}, stop)
    assert reply_answers("INFO", {"token": 3}, BY_NAME["GET_INFO"])


def test_telemetry_iterates_in_sequence_and_times_out_when_off():
    board, client = make()
    frames = list(client.telemetry(count=20))
    seqs = [f.seq for f in frames]
    assert seqs == list(range(seqs[0], seqs[0] + 20))
    client.set_telemetry_rate(0)
    with pytest.raises(LinkError, match="no telemetry within 0.2 s"):
        next(iter(client.telemetry(timeout=0.2)))


def test_sequence_gaps_count_lost_frames():
    board, client = make(drop_every=10)
    list(client.telemetry(count=90))
    assert client.stats.lost == 9  # 100 sent, every 10th dropped
    assert client.stats.corrupt == 0


def test_sequence_wraps_without_counting_losses():
    board, client = make()
    board.seq = 0xFFF0
    list(client.telemetry(count=40))
    assert client.stats.lost == 0 and client.stats.seq_restarts == 0


def test_corrupt_bytes_are_counted_and_valid_frames_around_them_survive():
    board, client = make()
    client.set_telemetry_rate(0)
    while client.recv(0.01) is not None:
        pass
    good = encode(Message.new("EVENT", time_ms=1, kind=0, code=0, detail=0))
    bad = bytearray(good)
    bad[-3] ^= 0x01  # a CRC byte
    board._tx += good + bytes(bad) + b"\x01\x02\x03\x00" + good
    msgs = [client.recv(0.1) for _ in range(2)]
    assert [m.name for m in msgs] == ["EVENT", "EVENT"]
    assert client.stats.crc_errors == 1 and client.stats.framing_errors == 1


def test_replies_are_found_while_a_notifier_is_reading():
    board, client = make()
    reader = BufferedReader(["TELEMETRY", "ACK"])
    notifier = Notifier(client, [reader])
    try:
        client.start(0, "+x")
        client.ping()
        names = set()
        while names != {"TELEMETRY", "ACK"}:
            rx = reader.get_message(2.0)
            assert rx is not None
            names.add(rx.message.name)
    finally:
        notifier.stop()


def test_simulated_link_tells_displacement_as_ground_truth():
    board, client = make()
    client.start(0, "+x")
    for _ in client.telemetry(count=150):
        pass
    rx = client.recv_received(1.0)
    assert rx is not None and rx.truth["displacement_mm"] > 0


class _ResettingBoard:
    """A board that, like a Nano whose port was just opened, says nothing for its first second."""

    def __init__(self, inner: FakeBoard, quiet_s: float = 1.0):
        self.inner, self.quiet_s, self.t = inner, quiet_s, 0.0

    def write(self, data: bytes) -> None:
        if self.t >= self.quiet_s:
            self.inner.write(data)

    def read(self) -> bytes:
        data = self.inner.read()
        return data if self.t >= self.quiet_s else b""

    def advance(self, seconds: float) -> None:
        self.t += seconds
        self.inner.advance(seconds)


def test_connect_keeps_asking_for_info_while_the_board_boots():
    client = RobotClient(SimLink(_ResettingBoard(FakeBoard()), description="sim fake"))
    assert client.connect().robot_name == "paper-r1"
    assert 1.0 <= client.link.clock() < 3.0


def test_connect_gives_up_after_three_seconds_with_one_clear_line():
    board = FakeBoard(silent=True)
    board.read()  # its boot INFO went out before we listened
    client = RobotClient(SimLink(board, description="sim fake"))
    with pytest.raises(LinkError, match=r"^no reply to GET_INFO within 3 s \(\d+ tries\) on sim fake$"):
        client.connect()
    assert 3.0 <= client.link.clock() < 3.1
    assert [m.name for m in board.received].count("GET_INFO") >= 50


def test_request_retries_with_the_same_token_until_acknowledged():
    board, client = make()
    board.silent = True
    with pytest.raises(LinkError, match=r"no reply to START within 0.5 s on sim fake \(3 tries\)"):
        client.request("START", retries=2, gait=0, direction=0)
    sent = [m for m in board.received if m.name == "START"]
    assert len(sent) == 3 and len({m.token for m in sent}) == 1
    assert client.stats.retries == 2 and client.stats.timeouts == 1



@pytest.mark.parametrize("call", [
    lambda c: c.set_param("hold_duty", 0, 0.3),      # a duty as a fraction: sent 0, a bang-bang hold, ACKed
    lambda c: c.set_param("psi_star_cdeg", 0, 20.5),  # sent 20: ψ* 0.20°
    lambda c: c.set_param(ParamId.DRIVE_DUTY, 0.5, 5000),
    lambda c: c.load_gait([0, 2.7, 3]),               # loaded state 2
    lambda c: c.start(0.9),                           # started gait 0
    lambda c: c.set_telemetry_rate(float("nan")),
])
def test_a_fraction_where_a_command_carries_a_whole_number_is_refused_not_truncated(call):
    board, client = make()
    with pytest.raises(LinkError, match="expected a whole number"):
        call(client)
    assert [m.name for m in board.received] == ["GET_INFO"]  # nothing sent


@pytest.mark.parametrize("ms", [1, 50, 99.0])
def test_a_link_watchdog_below_100_ms_is_refused_before_it_reaches_the_board(ms):
    """The board narrows its watchdog to any 1 ms or more, and the client's heartbeat then
    pinged every quarter of it (every 0.25 ms at 1 ms); ``proleg set-param`` refused it, the
    Python API sent it."""
    board, client = make()
    with pytest.raises(LinkError, match="expected at least 100 ms"):
        client.set_param("link_watchdog_ms", 0, ms)
    assert [m.name for m in board.received] == ["GET_INFO"]  # nothing sent


def test_whole_numbers_given_as_floats_or_numpy_ints_are_sent_as_they_are():
    import numpy as np

    board, client = make()
    client.set_param("drive_duty", 0, 5000.0)
    client.load_gait([np.int64(0), 2, 3.0, 1])
    assert board.drive_duty == 5000 and board.user_gait == (0, 2, 3, 1)
