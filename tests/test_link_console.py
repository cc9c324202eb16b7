"""The live console, headless (textual's pilot), and the plain line mode."""

from __future__ import annotations

import asyncio
import io

from proleg.link import RobotClient
from proleg.cli.link_commands import console_main
from proleg.console import ConsoleApp, LimbView, RobotNames, describe_event, run_plain
from build_checks import exit_status_within
from fake_board import FakeBoard
from proleg.link.sim_link import SimLink


NAMES = RobotNames(("left", "right"), ("sma-left", "sma-right"))


def _client(board: FakeBoard) -> RobotClient:
    client = RobotClient(SimLink(board, speed=4.0, description="sim fake"))
    client.connect()
    return client


async def _wait_for(pilot, predicate, timeout: float = 20.0) -> None:
    """Until ``predicate()`` holds (at once when it does): the timeout is only how long a
    condition that never comes is waited for. 5 s ran out on a machine loaded 2.5 times over
    its cores (the full-disk warning's test, 2026-12-01)."""
    for _ in range(int(timeout / 0.05)):
        await pilot.pause(0.05)
        if predicate():
            return
    raise AssertionError("condition not reached")


def test_console_keys_drive_the_robot_and_widgets_show_its_state():
    board = FakeBoard()
    client = _client(board)
    app = ConsoleApp(client, limbs=[LimbView("left", (20.0,)), LimbView("right", (20.0,))], levels=(2, 2),
                     names=NAMES)

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("d")  # direction -x
            await pilot.press("s")
            await _wait_for(pilot, lambda: any(m.name == "START" for m in board.received))
            start = next(m for m in board.received if m.name == "START")
            assert (start.gait, start.direction) == (0, 1)
            await _wait_for(pilot, lambda: board.duty != [0, 0] and app.model.telemetry is not None
                            and any(app.model.telemetry["duty"]))
            for _ in range(5):  # telemetry keeps arriving on the link's thread: one frame may come mid-render
                before = app.model.telemetry["psi"][0] / 100
                app.refresh_view()
                limbs = str(app.query_one("#limbs").content)
                if app.model.telemetry["psi"][0] / 100 == before:
                    break
            assert "left" in limbs and "ψ* 20.00°" in limbs
            assert f"ψ{before:7.2f}°" in limbs, (before, limbs)
            state = str(app.query_one("#state").content)
            assert "gait 0 -x" in state and "running" in state and "displacement" in state
            assert "sma-left" in str(app.query_one("#duty").content)
            assert "telemetry" in str(app.query_one("#counters").content)

            await pilot.press("e")
            await _wait_for(pilot, lambda: any(m.name == "ESTOP" for m in board.received))
            await _wait_for(pilot, lambda: app.model.telemetry["flags"] & 8)
            app.refresh_view()
            assert "estop" in str(app.query_one("#state").content)
            assert board.duty == [0, 0]

            await pilot.press("c")
            await _wait_for(pilot, lambda: any(m.name == "CLEAR" for m in board.received))
            await pilot.press("x")
            await _wait_for(pilot, lambda: any(m.name == "STOP" for m in board.received))
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()


def test_refused_command_shows_its_error_in_the_status_line():
    board = FakeBoard()
    client = _client(board)
    client.estop()
    app = ConsoleApp(client)

    async def scenario() -> None:
        async with app.run_test(size=(110, 32)) as pilot:
            await pilot.press("s")
            await _wait_for(pilot, lambda: "ESTOP_LATCHED" in app.status)
            app.refresh_view()
            assert "ESTOP_LATCHED" in str(app.query_one("#status").content)

    asyncio.run(scenario())
    client.close()


def test_plain_mode_prints_one_line_per_telemetry_frame():
    board = FakeBoard(telemetry_hz=100)
    client = _client(board)
    out = io.StringIO()
    run_plain(client, out=out, duration_s=0.5, labels=lambda s: format(s, "02b"))
    lines = out.getvalue().splitlines()
    assert len(lines) >= 20
    assert all(" seq=" in line and "psi=[" in line and "duty%=[" in line for line in lines)
    assert "state=00" in lines[0]
    client.close()


def test_console_main_plain_with_record_on_a_serial_url(tmp_path):
    # loop:// echoes our own GET_INFO back: not a robot, so the handshake (3 s of tries) times out cleanly
    import pytest

    from proleg.errors import LinkError

    with pytest.raises(LinkError, match=r"no reply to GET_INFO within 3 s \(\d+ tries\) on loop://"):
        console_main(port="loop://", plain=True, record=str(tmp_path / "r.csv"), timeout=0.2, out=io.StringIO())
    assert not (tmp_path / "r.csv").exists()


# --------------------------------------------------------------------------- 80×24, gaits, names
def _unclipped(app: ConsoleApp) -> list[str]:
    """Every widget inside the 80×24 screen; every panel's text fits its content area."""
    from rich.cells import cell_len
    from textual.widgets import Footer, Static

    problems = []
    screen = app.screen.region
    for w in [*app.query(Static), app.query_one(Footer)]:
        r = w.region
        if r.width <= 0 or r.height <= 0 or r.right > screen.right or r.bottom > screen.bottom:
            problems.append(f"{w.id or type(w).__name__} at {r} outside {screen}")
            continue
        if isinstance(w, Static) and not isinstance(w, Footer) and w.id:
            lines = str(w.content).split("\n")
            box = w.content_region
            if len(lines) > box.height:
                problems.append(f"#{w.id}: {len(lines)} lines in {box.height} rows")
            problems += [f"#{w.id}: {line!r} wider than {box.width}" for line in lines if cell_len(line) > box.width]
    return problems


def test_every_panel_fits_an_80x24_terminal_with_four_limbs_and_a_fault():
    board = FakeBoard(limbs=4, gaits={0: ((0, 1),), 1: ((0, 2),)})
    client = _client(board)
    names = RobotNames(("front-left", "front-right", "rear-left", "rear-right"),
                       ("sma-front-left", "sma-front-right", "sma-rear-left", "sma-rear-right"))
    app = ConsoleApp(client, limbs=[LimbView(n, (20.0,)) for n in names.limbs], levels=(2,) * 4, names=names)

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("s")
            await _wait_for(pilot, lambda: app.model.telemetry is not None and any(app.model.telemetry["duty"]))
            for k in range(12):  # more events than the panel has rows
                app.model.on_message(_event(2, 1 + k % 5, k % 4))
            await pilot.pause(0.3)
            app.refresh_view()
            assert _unclipped(app) == []
            assert "rear-right" in str(app.query_one("#limbs").content)
            assert "sma-rear-right" in str(app.query_one("#duty").content)
            assert "FAULT" in str(app.query_one("#events").content)
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()


def _event(kind: int, code: int, detail: int):
    from proleg.link.client import Received
    from proleg.protocol.codec import Message

    return Received(Message("EVENT", {"time_ms": 1234, "kind": kind, "code": code, "detail": detail}), 0.0)


def test_a_few_events_are_all_shown():
    board = FakeBoard()
    client = _client(board)
    app = ConsoleApp(client, names=NAMES)

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            for code in (0, 1, 2):
                app.model.on_message(_event(1, code, code))  # STATE_REACHED, step = code
            await pilot.pause(0.2)
            app.refresh_view()
            text = str(app.query_one("#events").content)
            assert all(f"step {k + 1} reached" in text for k in (0, 1, 2)), text  # shown from 1
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()


def test_g_cycles_through_the_gaits_info_reports_and_no_others():
    board = FakeBoard(gaits={0: ((0, 2, 3, 1), (0, 1, 3, 2), (0, 2, 3, 1)), 1: ((0, 1, 3, 2),)})
    client = _client(board)
    assert client.info.gaits == 3
    app = ConsoleApp(client)
    seen = []

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            for _ in range(7):
                await pilot.press("g")
                seen.append(app.gait)
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()
    assert seen == [1, 2, 0, 1, 2, 0, 1]


def test_the_loaded_gait_starts_with_its_way_unstated_until_d_states_it():
    """The console does not know which way a loaded sequence walks: selecting it leaves the
    way unstated (no climb guard), and d cycles +x, -x, unstated for it."""
    from proleg.protocol.definition import DIR_UNSTATED, GAIT_USER

    board = FakeBoard(gaits={0: ((0, 2, 3, 1),), 1: ()})
    client = _client(board)
    client.load_gait([0, 2, 1])
    app = ConsoleApp(client)
    ways = []

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause(0.3)  # telemetry says a user gait is loaded
            while app.gait != GAIT_USER:
                await pilot.press("g")
            ways.append(app.direction)
            await pilot.press("s")
            await pilot.pause(0.3)
            await pilot.press("x")
            for _ in range(3):
                await pilot.press("d")
                ways.append(app.direction)
            await pilot.press("g")  # back to gait 0: a built-in gait has a way
            ways.append(app.direction)
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()
    assert ways == [DIR_UNSTATED, 0, 1, DIR_UNSTATED, 0]
    start = next(m for m in board.received if m.name == "START")
    assert (start.gait, start.direction) == (GAIT_USER, DIR_UNSTATED)


def test_a_firmware_without_gaits_offers_none_and_starts_nothing():
    board = FakeBoard(gaits={0: (), 1: ()})
    client = _client(board)
    app = ConsoleApp(client)

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.press("g")
            await pilot.press("s")
            await pilot.pause(0.3)
            assert "no gait" in app.status
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()
    assert not any(m.name == "START" for m in board.received)


def test_events_name_kinds_faults_reasons_limbs_and_actuators_never_raw_codes():
    from proleg.protocol.definition import EventKind, FaultCode, StopReason

    def text(kind, code, detail):
        return describe_event(_event(int(kind), int(code), detail).message.fields, NAMES, lambda s: format(s, "02b"))

    assert text(EventKind.FAULT, FaultCode.IMU_NO_ACK, 1).endswith("FAULT IMU_NO_ACK on right")
    assert text(EventKind.FAULT, FaultCode.STATE_TIMEOUT, 0).endswith("FAULT STATE_TIMEOUT on left")
    assert text(EventKind.FAULT, FaultCode.SMA_ON_LIMIT, 1).endswith("FAULT SMA_ON_LIMIT on sma-right")
    assert text(EventKind.FAULT, FaultCode.LINK_WATCHDOG, 0).endswith("FAULT LINK_WATCHDOG")
    assert text(EventKind.GAIT_STOPPED, StopReason.WATCHDOG, 3).endswith("gait stopped: WATCHDOG after 3 cycles")
    assert text(EventKind.STATE_REACHED, 2, 3).endswith("step 3 reached state 11")  # steps shown from 1
    assert text(EventKind.STATE_REACHED, 255, 1).endswith("entry path reached state 01")
    assert text(EventKind.GAIT_STARTED, 255, 1).endswith("gait user started -x")
    assert text(EventKind.FAULT_CLEARED, 3, 0).endswith("cleared faults estop")
    assert "IMU_NO_ACK on limb #8" in describe_event(_event(2, 2, 7).message.fields)  # no robot file: counted from 1
    assert text(EventKind.LEVEL_DONE, 1, 0b10).endswith("level calibration refused: TOO_TILTED (right)")
    assert text(EventKind.LEVEL_DONE, 0, 3).endswith("level calibration done")
    assert text(EventKind.BOOT, 4, 0).endswith("boot (reset cause WATCHDOG)")
    assert text(EventKind.BOOT, 2, 1).endswith("boot (reset cause EXTERNAL; the envelope kept what the coils spent)")
    assert "unknown 99" in describe_event(_event(2, 99, 0).message.fields)


# --------------------------------------------------------------------------- leaving stops the robot
class _StopDeaf(FakeBoard):
    """Answers everything but STOP (a STOP lost on the wire)."""

    def _command(self, msg):
        if msg.name != "STOP":
            super()._command(msg)


def _fake_links(board: FakeBoard):
    from proleg.link.factory import LINKS, register_link

    register_link("fake", lambda url, rest, query, options: SimLink(board, speed=4.0, description="fake board"))
    return LINKS


def _console_on(board: FakeBoard, **kwargs) -> tuple[str, list[str]]:
    links = _fake_links(board)
    err = io.StringIO()
    try:
        console_main(port="fake://r1", plain=True, duration_s=0.3, out=io.StringIO(), err=err, **kwargs)
    finally:
        links.pop("fake")
    return err.getvalue(), [m.name for m in board.received]


def test_leaving_the_console_sends_stop_and_waits_for_its_ack():
    board = FakeBoard()
    board.running, board.sequence = True, (0, 2, 3, 1)  # left running by an earlier session
    err, sent = _console_on(board)
    assert sent[-1] == "STOP" and "ESTOP" not in sent
    assert "robot stopped" in err
    assert not board.running and board.duty == [0, 0]


def test_an_unacknowledged_stop_on_leaving_becomes_an_estop():
    board = _StopDeaf()
    board.running, board.sequence = True, (0, 2, 3, 1)
    err, sent = _console_on(board, timeout=0.05)
    assert sent.count("STOP") == 3 and sent[-1] == "ESTOP"
    assert "STOP not acknowledged" in err and "E-stopped" in err
    assert board.estop and board.duty == [0, 0]


def test_leave_running_leaves_the_robot_alone():
    board = FakeBoard()
    board.running, board.sequence = True, (0, 2, 3, 1)
    err, sent = _console_on(board, leave_running=True)
    assert "STOP" not in sent and "ESTOP" not in sent
    assert board.running
    # and it says for how long: the link watchdog stops a gait nobody pings (without a robot file
    # the console cannot know the period; the gait ran on for 2 s and stopped, unannounced)
    assert err == ("proleg: left running on fake board: the firmware's link watchdog stops it its link_watchdog_ms "
                   "(2000 unless its robot file says otherwise) after the last frame from a host (a run to detach "
                   "from needs firmware built with [safety] link_watchdog_ms = 0)\n")


def test_a_closed_terminal_window_runs_the_leaving_code():
    import os
    import signal

    from proleg.interrupts import hangup_as_exception

    before = signal.getsignal(signal.SIGHUP)  # SIG_IGN when the tests run under nohup
    called = []
    with hangup_as_exception(lambda: called.append("exit")):
        os.kill(os.getpid(), signal.SIGHUP)
    assert called == ["exit"]
    finally_ran = []
    with hangup_as_exception():
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            raise AssertionError("SIGTERM did not interrupt")  # pragma: no cover
        finally:
            finally_ran.append(True)
    assert finally_ran == [True]
    assert signal.getsignal(signal.SIGHUP) == before  # given back as it was


def test_an_idle_console_keeps_the_link_watchdog_fed():
    board = FakeBoard()
    client = _client(board)
    run_plain(client, out=io.StringIO(), duration_s=2.0, quiet=True)  # ~8 s of the board's time at speed 4
    pings = [m for m in board.received if m.name == "PING"]
    times = client.heartbeats
    client.close()
    assert times >= 10 and len(pings) == times


def test_duration_ends_the_ui_session_too():
    """--duration was only read by the plain mode: the UI ran on past it (docs: "--duration over"
    is a way the console leaves)."""
    board = FakeBoard()
    client = _client(board)
    app = ConsoleApp(client, levels=(2, 2), names=NAMES, duration_s=0.5)

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await _wait_for(pilot, lambda: not app.is_running, timeout=5.0)

    asyncio.run(scenario())
    client.close()


def test_a_second_ctrl_c_while_the_leaving_stop_waits_goes_on_to_the_estop(monkeypatch):
    """Ctrl-C, then Ctrl-C again while the STOP waited for its ACK (a slow or deaf board): the
    second one ended the console there, exit 0, no ESTOP sent and nothing said about the coils."""
    board = _StopDeaf()
    board.running, board.sequence = True, (0, 2, 3, 1)
    real = RobotClient.request

    def request(self, name, *args, **kwargs):
        if name == "STOP":
            self.link.write(b"")  # the STOP went out; the user presses Ctrl-C again while it waits
            raise KeyboardInterrupt
        return real(self, name, *args, **kwargs)

    monkeypatch.setattr(RobotClient, "request", request)
    err, sent = _console_on(board, timeout=0.05)
    assert sent[-1] == "ESTOP"
    assert "STOP not acknowledged (interrupted while waiting for it); robot E-stopped" in err
    assert board.estop and board.duty == [0, 0]


def test_closing_the_consoles_terminal_stops_the_robot_and_exits_129(tmp_path):
    """The UI console in a terminal that is closed (SIGHUP, the tty gone). The signal handler
    called app.exit() inside textual's own output code: under load the console hung for ever,
    its heartbeat keeping the gait running; otherwise its last lines failed on the dead terminal
    (EIO) and it exited 1 instead of 129. Now: STOP sent (the board says stopped, not by its
    link watchdog), the recording whole, 129."""
    import os
    import pty
    import select
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    from proleg.link.serial_link import SerialLink
    from proleg.protocol.definition import Flag
    from proleg.record import read_recording

    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": str(root / "host" / "src"), "TERM": "xterm-256color"}
    server = subprocess.Popen([sys.executable, "-m", "proleg", "sim", "paper-r1", "--pty"], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True, env=env)
    record = tmp_path / "session.mcap"
    pid = None
    try:
        port = server.stdout.readline().split(" on ")[1].split(" ")[0]
        pid, fd = pty.fork()
        if pid == 0:  # pragma: no cover (the child)
            os.execve(sys.executable, [sys.executable, "-m", "proleg", "console", "--port", port,
                                       "--record", str(record)], env)

        def pump(seconds: float) -> None:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                if select.select([fd], [], [], 0.05)[0]:
                    try:
                        os.read(fd, 65536)
                    except OSError:
                        return

        pump(6.0)  # the UI is up
        os.write(fd, b"s")  # start the gait
        pump(3.0)
        os.close(fd)  # the terminal window is closed
        status = exit_status_within(pid)
        if status is not None:
            pid = None  # reaped
        assert status == 129
        with RobotClient(SerialLink(port)) as client:  # within the watchdog's 2 s: it is the STOP that stopped it
            frame = next(iter(client.telemetry(count=1)))
        assert not frame.flags & (Flag.RUNNING | Flag.LINK_WATCHDOG), Flag(frame.flags)
        assert len(read_recording(record).time_s) > 0
    finally:
        if pid is not None:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        server.kill()
        server.wait()


def test_a_warning_said_while_a_command_runs_stays_where_its_ok_would_go(monkeypatch):
    """The START a key sent ran on a worker; when it came back it wrote "start …: ok" over the
    status line, so a warning the host said meanwhile (a recording that hit a full disk) was
    replaced as soon as it showed (the full-disk test failed so, once, in CI). A command's "ok"
    now replaces only its own "…" line; with nothing said meanwhile it still shows."""
    import threading

    board = FakeBoard()
    client = _client(board)
    app = ConsoleApp(client, limbs=[LimbView("left", (20.0,)), LimbView("right", (20.0,))], levels=(2, 2),
                     names=NAMES)
    said, real = threading.Event(), client.start
    returned = []

    def start_after_the_warning(*args, **kw):
        said.wait(10.0)
        out = real(*args, **kw)
        returned.append(True)
        return out

    monkeypatch.setattr(client, "start", start_after_the_warning)
    warning = "cannot write record file run.csv: No space left on device"

    async def scenario() -> None:
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.press("s")
            await _wait_for(pilot, lambda: app.status.endswith("…"))
            app.host_says(warning)
            said.set()
            await _wait_for(pilot, lambda: bool(returned))
            await pilot.pause(0.2)
            assert app.status == warning
            await pilot.press("x")  # STOP: nothing said meanwhile, so its ok shows
            await _wait_for(pilot, lambda: app.status == "stop: ok")
            await pilot.press("q")

    asyncio.run(scenario())


def test_a_full_disk_warning_shows_in_the_ui_not_over_it(tmp_path, monkeypatch):
    """A recording that hit ENOSPC said its warning through the CLI's stderr handler, written
    to the terminal under textual's screen (it scribbled over the UI until the next redraw).
    While the UI is up it is in the status line, the events panel and a notification, nothing
    goes to stderr; once the UI has left, it is said on stderr too (not lost with the screen)."""
    import logging

    from pathlib import Path

    from proleg.record import Logger, RecordingMeta, base
    from proleg.robot import load_robot
    from test_record import _DiskFillsAt

    robot = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")
    monkeypatch.setattr(base, "open", _DiskFillsAt(3000), raising=False)
    stderr = io.StringIO()  # the CLI's handler (cli.main._setup_logging), on a terminal's stderr
    handler = logging.StreamHandler(stderr)
    handler.setFormatter(logging.Formatter("proleg: %(message)s"))
    logger = logging.getLogger("proleg")
    monkeypatch.setattr(logger, "handlers", [handler])
    monkeypatch.setattr(logger, "propagate", False)
    monkeypatch.setattr(logger, "level", logging.INFO)
    board = FakeBoard()
    client = _client(board)
    path = tmp_path / "run.csv"
    recorder = Logger(path, RecordingMeta.for_robot(info=client.info, robot=robot, link=client.link))
    app = ConsoleApp(client, listeners=[recorder], names=NAMES)
    said = "cannot write record file"

    async def scenario() -> None:
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.press("s")
            await _wait_for(pilot, lambda: recorder.error is not None)
            await _wait_for(pilot, lambda: said in app.status)
            app.refresh_view()
            assert said in str(app.query_one("#status").content)  # (the events panel has it too, soon scrolled)
            assert any(said in str(n.message) for n in app._notifications)
            assert stderr.getvalue() == ""  # nothing written under the screen
            await pilot.press("q")

    asyncio.run(scenario())
    assert stderr.getvalue() == ""
    app.ui_log.replay()  # what ConsoleApp.run does once textual has left the terminal
    assert logger.handlers == [handler]
    lines = stderr.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"proleg: warning: {said} {path}: No space left on device")
    assert "No space left on device" in str(recorder.error)
    client.close()
