"""host-sim mirrors a board's link (issue 11): its UART ring sizes and byte rate come from the
board file, so a burst of replies queues and drops on host-sim as on the MCU. Here host-sim is
built with the arduino-nano's ``[uart]`` (``[board] extends = "host-sim"``, the Nano's baud and
buffers) and fed the same requests as the exact Nano image on avr-emu: GET_INFO every 2 ms
asks for far more than 115,200 baud carries, and both boards answer the same requests and drop
the same number of messages (a message goes out whole or not at all)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proleg.firmware.boards import load_board
from proleg.paths import robots_dir
from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.robot import load_robot

pytestmark = pytest.mark.skipif(
    not Path("/usr/include/simavr/sim_avr.h").exists() or shutil.which("avr-gcc") is None,
    reason="needs simavr/libsimavr-dev and avr-gcc (make toolchains installs them)",
)

REQUESTS, EVERY_S = 30, 0.002


def burst(board) -> tuple[list[int], int, int]:
    """GET_INFO every 2 ms, then GET_STATS: (tokens of the INFO replies that arrived whole,
    STATS.tx_dropped, STATS.tx_frames)."""
    board.advance(0.05)
    board.read()
    for k in range(REQUESTS):
        board.write(encode(Message.new("GET_INFO", token=k + 1)))
        board.advance(EVERY_S)
    board.advance(0.2)  # the ring drains
    board.write(encode(Message.new("GET_STATS", token=200)))
    board.advance(0.05)
    msgs = FrameDecoder().feed(board.read())
    stats = [m for m in msgs if m.name == "STATS"]
    assert len(stats) == 1
    return [m.token for m in msgs if m.name == "INFO"], stats[0].tx_dropped, stats[0].tx_frames


def test_host_sim_with_the_nanos_uart_drops_a_burst_of_replies_as_the_nano_does(tmp_path):
    from proleg.emu.avr import AvrEmuBoard, nano_elf
    from proleg.sim.board import SimBoard
    from proleg.sim.closed_loop import sim_library

    nano = load_board("arduino-nano")
    board_file = tmp_path / "host-sim-nano-uart.toml"
    board_file.write_text(
        '[board]\nextends = "host-sim"\n\n'
        f'[uart]\nport = "sim"\nbaud = {nano.uart_baud}\n'
        f"rx_buffer = {nano.uart_rx_buffer}\ntx_buffer = {nano.uart_tx_buffer}\n"
    )
    r1 = load_robot(robots_dir() / "paper-r1.toml")
    on_sim = burst(SimBoard(sim_library(r1, board=str(board_file))))
    on_nano = burst(AvrEmuBoard(nano_elf(r1)))
    infos, dropped, _ = on_nano
    assert 0 < len(infos) < REQUESTS and dropped >= REQUESTS - len(infos)  # the burst does overflow
    assert on_sim == on_nano

    # with its own board file (2 Mbaud, 256 B) host-sim answers every request
    roomy = burst(SimBoard(sim_library(r1)))
    assert roomy[0] == list(range(1, REQUESTS + 1)) and roomy[1] == 0
