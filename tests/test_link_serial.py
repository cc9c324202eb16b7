"""Serial links: pyserial URLs, a pty served by the fake firmware, disconnect and reconnect."""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from pathlib import Path

import pytest
import serial

from proleg.errors import LinkError
from proleg.link import RobotClient
from proleg.link.base import LinkDisconnected
from fake_board import FakeBoard
from proleg.link.serial_link import SerialLink


class PtyBoard:
    """Serves a FakeBoard on a pseudo-terminal in real time (a stand-in for a USB adapter)."""

    def __init__(self, board: FakeBoard | None = None):
        self.board = board or FakeBoard()
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self._running = True
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        t0 = time.monotonic()
        sim = 0.0
        while self._running:
            ready, _, _ = select.select([self.master], [], [], 0.002)
            if ready:
                try:
                    data = os.read(self.master, 4096)
                except OSError:
                    data = b""
                if data:
                    self.board.write(data)
            now = time.monotonic() - t0
            if now > sim:
                self.board.advance(now - sim)
                sim = now
            out = self.board.read()
            if out:
                try:
                    os.write(self.master, out)
                except OSError:
                    pass

    def close(self) -> None:
        """Like unplugging the adapter: the port's reads fail from now on. Idempotent (the
        descriptors may already belong to someone else)."""
        if not self._running:
            return
        self._running = False
        self._thread.join(2)
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


def test_loop_url_round_trips_bytes():
    with SerialLink("loop://") as link:
        link.write(b"\x03\x01\x01\x00")
        assert link.read(0.2) == b"\x03\x01\x01\x00"
        assert link.read(0.01) == b""


def test_missing_port_is_one_clear_link_error():
    with pytest.raises(LinkError) as e:
        SerialLink("/dev/ttyNOPE-proleg")
    text = str(e.value)
    assert text.startswith("cannot open serial port /dev/ttyNOPE-proleg:")
    assert "\n" not in text


def test_client_talks_to_firmware_on_a_pty():
    server = PtyBoard()
    try:
        with RobotClient(SerialLink(server.path)) as client:
            info = client.connect()
            assert info.robot_name == "paper-r1"
            client.start(0, "+x")
            frames = list(client.telemetry(count=10))
            assert frames[-1].flags & 1  # RUNNING
            assert client.stats.lost == 0
    finally:
        server.close()


def test_a_second_session_on_a_port_in_use_is_refused_naming_it():
    """Two consoles (or a console and a run) on one port both opened it, and the board's bytes
    were split between them: gaps and CRC errors in each, and either could START what the other
    stopped. The second is now refused with one line; the first goes on; the port is free again
    once the first closes."""
    server = PtyBoard()
    try:
        with RobotClient(SerialLink(server.path)) as client:
            client.connect()
            with pytest.raises(LinkError) as e:
                SerialLink(server.path)
            assert str(e.value) == (f"cannot open serial port {server.path}: another program has it open (a proleg "
                                    "console, run, learn or calibrate?); close it first")
            frames = list(client.telemetry(count=10))
            assert client.stats.lost == 0 and len(frames) == 10
        SerialLink(server.path).close()  # free again
    finally:
        server.close()


class _BackloggedPort:
    """A port that held old frames when it was opened, and hands over more old bytes still in
    flight after a flush (a pty's flip buffer) before the board's fresh ones."""

    def __init__(self):
        self.buffer = bytearray(b"OLD" * 1000)
        self.in_flight = [b"OLD" * 10, b"OLD" * 10]
        self.timeout = 0.0

    @property
    def in_waiting(self) -> int:
        return len(self.buffer)

    def reset_input_buffer(self) -> None:
        self.buffer.clear()

    def read(self, n: int = 1) -> bytes:
        if not self.buffer and self.in_flight:
            self.buffer += self.in_flight.pop(0)
        out, self.buffer[:] = bytes(self.buffer[:n]), self.buffer[n:]
        return out

    def close(self) -> None:
        pass


def test_what_a_port_held_before_it_was_opened_is_not_part_of_the_session():
    """A board idle behind a pty (or a USB adapter's buffer) handed proleg run --port seconds of
    old TELEMETRY: a 1 s run counted 624 frames, the first ones 11 s before its START, and
    recorded them. Flushed at open, and what was still in flight read away."""
    port = _BackloggedPort()
    link = SerialLink("/dev/ttyACM0", opener=lambda url, **kw: port)
    port.buffer += b"NEW"  # what the board says once we are there
    assert link.read(0.0) == b"NEW"


def test_timeout_names_the_command_and_the_port():
    server = PtyBoard(FakeBoard(silent=True))
    try:
        with RobotClient(SerialLink(server.path), timeout=0.2) as client:
            with pytest.raises(LinkError) as e:
                client.ping()
            assert str(e.value) == f"no reply to PING within 0.2 s on {server.path}"
    finally:
        server.close()


def test_client_reconnects_when_the_usb_device_comes_back_under_the_same_name(tmp_path: Path):
    by_id = tmp_path / "usb-proleg-robot"  # like /dev/serial/by-id/...
    first = PtyBoard()
    by_id.symlink_to(first.path)
    second = None
    try:
        client = RobotClient(SerialLink(str(by_id)), reconnect_timeout=5.0)
        client.connect()
        list(client.telemetry(count=3))
        first.close()  # unplugged
        by_id.unlink()

        def plug_back() -> None:
            nonlocal second
            time.sleep(0.3)
            second = PtyBoard(FakeBoard(build_id=0xBEEF))
            by_id.symlink_to(second.path)

        threading.Thread(target=plug_back).start()
        list(client.telemetry(count=3, timeout=6.0))
        assert client.stats.reconnects == 1
        client.ping()
        assert client.info is not None and client.info.build_id == 0xBEEF  # INFO refreshed
        client.close()
    finally:
        first.close()
        if second is not None:
            second.close()


class FlakyPort:
    """A fake pyserial port: reads raise SerialException while ``unplugged``."""

    def __init__(self, state: dict):
        self.state = state
        self.timeout = 0.0
        self.written = bytearray()

    @property
    def in_waiting(self) -> int:
        return 0

    def read(self, n: int) -> bytes:
        if self.state["unplugged"]:
            raise serial.SerialException("device reports readiness to read but returned no data")
        time.sleep(min(self.timeout or 0.0, 0.01))
        return b""

    def write(self, data: bytes) -> int:
        self.written += data
        return len(data)

    def close(self) -> None:
        pass


def test_serial_link_reports_disconnect_and_reopens_when_the_port_is_back():
    state = {"unplugged": False, "opens": 0, "fail_opens": 0}

    def opener(url, **kw):
        state["opens"] += 1
        if state["fail_opens"]:
            state["fail_opens"] -= 1
            raise serial.SerialException(f"[Errno 2] could not open port {url}")
        return FlakyPort(state)

    link = SerialLink("/dev/ttyUSB0", opener=opener)
    state["unplugged"] = True
    with pytest.raises(LinkDisconnected, match="/dev/ttyUSB0: device disconnected"):
        link.read(0.01)
    state["unplugged"] = False
    state["fail_opens"] = 2
    client = RobotClient(link, reconnect_timeout=3.0)
    assert client.recv(0.05) is None  # the client reopens (two failures, then success)
    assert client.stats.reconnects == 1 and state["opens"] == 4
    assert b"\x00" in bytes(link._port.written)  # and asks for INFO again


def test_reconnect_gives_up_with_one_line_after_its_timeout():
    def opener(url, **kw):
        raise serial.SerialException(f"[Errno 2] could not open port {url}")

    state = {"unplugged": True}
    link = SerialLink("/dev/ttyUSB9", opener=lambda url, **kw: FlakyPort(state))
    link._opener = opener
    client = RobotClient(link, reconnect_timeout=0.3)
    with pytest.raises(LinkError, match="device disconnected and not back within 0.3 s"):
        client.recv(0.05)


def test_after_giving_up_the_leaving_stop_and_estop_do_not_wait_for_the_device_again():
    """A console whose cable was pulled waited the reconnect timeout three times (the session,
    then its STOP, then its ESTOP): 30 s before it said anything. After the first wait the
    STOP and ESTOP try to reopen the port once each; a port that is back is used again."""
    from proleg.link.leave import stop_robot

    state = {"unplugged": True, "back": False}

    def opener(url, **kw):
        if not state["back"]:
            raise serial.SerialException(f"[Errno 2] could not open port {url}")
        state["unplugged"] = False
        return FlakyPort(state)

    link = SerialLink("/dev/ttyUSB9", opener=lambda url, **kw: FlakyPort(state))
    link._opener = opener
    client = RobotClient(link, reconnect_timeout=1.0, timeout=0.05)
    t0 = time.monotonic()
    with pytest.raises(LinkError, match="device disconnected and not back within 1 s"):
        client.recv(0.05)
    assert 0.9 < time.monotonic() - t0 < 2.0
    t0 = time.monotonic()
    said = stop_robot(client)
    assert time.monotonic() - t0 < 1.0, said
    assert said.startswith("could not stop the robot: /dev/ttyUSB9: device disconnected and not back within 1 s")
    state["back"] = True  # plugged in again: the next reopen finds it
    client.recv(0.05)
    assert client.stats.reconnects == 1


def test_a_recording_on_a_serial_port_counts_t_host_s_from_when_the_link_opened(tmp_path: Path):
    # docs/data.md: "0 ≈ when the link opened"; a pty recording started at 75763.48 s (the raw
    # monotonic clock)
    import csv

    from proleg.record import Logger, RecordingMeta

    server = PtyBoard()
    try:
        with RobotClient(SerialLink(server.path)) as client:
            info = client.connect()
            rec = Logger(tmp_path / "pty.csv", RecordingMeta.for_robot(info=info, link=client.link))
            client.start(0, "+x")
            for _ in range(200):
                rx = client.recv_received(0.5)
                if rx is not None:
                    rec.on_message(rx)
                if rec.records >= 10:
                    break
            rec.stop()
    finally:
        server.close()
    with open(tmp_path / "pty.csv", newline="") as fh:
        t = [float(row["t_host_s"]) for row in csv.DictReader(fh)]
    assert len(t) >= 5 and 0.0 <= min(t) and max(t) < 10.0, t[:3]


class _WrongBaudPort:
    """A board at another baud rate: bytes arrive, none of them a frame (a 0 now and then)."""

    def __init__(self):
        import random

        self.rng = random.Random(3)
        self.timeout = 0.0
        self.in_waiting = 0

    def reset_input_buffer(self) -> None:
        pass

    def read(self, n: int = 1) -> bytes:
        time.sleep(min(self.timeout or 0.0, 0.01))
        return bytes(self.rng.randrange(256) for _ in range(64))

    def write(self, data: bytes) -> int:
        return len(data)

    def close(self) -> None:
        pass


def test_garbage_on_the_line_suggests_the_baud_rate_instead_of_silence():
    """A Nano flashed at 57600 opened at 115200 said 'no reply to GET_INFO within 3 s', as a
    pulled cable does: the error now says bytes came, none valid, and names --baudrate."""
    link = SerialLink("/dev/ttyUSB0", opener=lambda url, **kw: _WrongBaudPort())
    with RobotClient(link) as client, pytest.raises(LinkError) as e:
        client.connect(within_s=0.3)
    text = str(e.value)
    assert text.startswith("no reply to GET_INFO within 0.3 s (")
    assert text.endswith(" garbled frames came, none valid: a board at another baud rate than 115200 (--baudrate), "
                         "or not proleg firmware?)"), text
