"""The live console, headless (textual's pilot), and the plain line mode."""

from __future__ import annotations

import asyncio
import io

from proleg.link import RobotClient
from proleg.cli.link_commands import console_main
from proleg.console import ConsoleApp, LimbView, run_plain
from fake_board import FakeBoard
from proleg.link.sim_link import SimLink


def _client(board: FakeBoard) -> RobotClient:
    client = RobotClient(SimLink(board, speed=4.0, description="sim fake"))
    client.connect()
    return client


async def _wait_for(pilot, predicate, timeout: float = 5.0) -> None:
    for _ in range(int(timeout / 0.05)):
        await pilot.pause(0.05)
        if predicate():
            return
    raise AssertionError("condition not reached")


def test_console_keys_drive_the_robot_and_widgets_show_its_state():
    board = FakeBoard()
    client = _client(board)
    app = ConsoleApp(client, limbs=[LimbView("left", (20.0,)), LimbView("right", (20.0,))], levels=(2, 2))

    async def scenario() -> None:
        async with app.run_test(size=(110, 32)) as pilot:
            await pilot.press("d")  # direction -x
            await pilot.press("s")
            await _wait_for(pilot, lambda: any(m.name == "START" for m in board.received))
            start = next(m for m in board.received if m.name == "START")
            assert (start.gait, start.direction) == (0, 1)
            await _wait_for(pilot, lambda: board.duty != [0, 0] and app.model.telemetry is not None
                            and any(app.model.telemetry["duty"]))
            app.refresh_view()
            limbs = str(app.query_one("#limbs").content)
            assert "left" in limbs and "ψ* 20.00°" in limbs
            psi0 = app.model.telemetry["psi"][0] / 100
            assert f"{psi0:7.2f}°" in limbs
            state = str(app.query_one("#state").content)
            assert "gait 0 -x" in state and "running" in state and "displacement" in state
            assert "SMA 0" in str(app.query_one("#duty").content)
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
