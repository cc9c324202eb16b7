"""One lock on a serial device for every proleg tool (``proleg.ports``): ``proleg flash``
ran avrdude on a port a console held (avrdude takes no lock), and both broke; a console started
during a flash opened the port under the flash tool. Each now refuses the other's port, in one
line naming the port, who holds it and what to do, before it touches the port."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from build_checks import R1, board_variant, cli, one_line
from proleg.errors import LinkError
from proleg.firmware.boards import load_board
from proleg.firmware.flash import choose_method, flash
from proleg.ports import PortBusy, PortLock, busy_message
from proleg.link.serial_link import SerialLink
from test_link_serial import PtyBoard

ROOT = Path(__file__).resolve().parents[1]


def _env() -> dict[str, str]:
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "host" / "src"), env.get("PYTHONPATH", "")])
    return env


def _wait_for(predicate, timeout_s: float = 20.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.05)
    return False


def _held(path: str) -> bool:
    try:
        PortLock(path).release()
    except PortBusy:
        return True
    return False


@pytest.fixture
def board():
    server = PtyBoard()
    yield server
    server.close()


def _tool(tmp_path: Path, body: str) -> Path:
    tool = tmp_path / "fake-avrdude"
    tool.write_text("#!/bin/sh\n" + body + "\n")
    tool.chmod(0o755)
    return tool


def test_flash_refuses_a_port_a_console_holds_naming_it(tmp_path, capsys, board):
    ran = tmp_path / "tool-ran"
    tool = _tool(tmp_path, f"touch {ran}")
    variant = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', f'command = ["{tool}"'))
    console = subprocess.Popen([sys.executable, "-m", "proleg", "console", "--port", board.path, "--plain"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())
    try:
        assert _wait_for(lambda: _held(board.path) or console.poll() is not None), "the console never opened the port"
        assert console.poll() is None, console.stderr.read().decode()  # type: ignore[union-attr]
        expected = (f"cannot flash through {board.path}: a proleg console has it open (pid {console.pid}); "
                    "close the console first")
        hexfile = tmp_path / "firmware.hex"
        hexfile.write_text(":00000001FF\n")
        with pytest.raises(LinkError) as e:
            flash(choose_method(load_board(variant)), hexfile, board.path)
        assert str(e.value) == expected
        out = tmp_path / "fw"
        code, _, err = cli(capsys, "flash", R1, "--board", variant, "--port", board.path, "-o", out)
        assert code == 1 and one_line(err) == f"proleg: error: {expected}"
        assert not ran.exists()  # the flash tool never started
        assert not out.exists()  # said before building
        assert console.poll() is None  # the console goes on
    finally:
        console.terminate()
        console.wait(10)
    # the console gone, the port is free: the same flash runs the tool
    flash(choose_method(load_board(variant)), hexfile, board.path)
    assert ran.exists()


def test_a_console_or_run_is_refused_a_port_a_flash_writes(tmp_path, board):
    started = tmp_path / "tool-started"
    release = tmp_path / "tool-may-end"
    tool = _tool(tmp_path, f"touch {started}\nwhile [ ! -e {release} ]; do sleep 0.05; done")
    variant = board_variant(tmp_path, "arduino-nano", (r'^command = \["avrdude"', f'command = ["{tool}"'))
    flashing = subprocess.Popen([sys.executable, "-m", "proleg", "flash", str(R1), "--board", str(variant),
                                 "--port", board.path, "-o", str(tmp_path / "fw")],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    try:
        assert _wait_for(lambda: started.exists() or flashing.poll() is not None, 60), "the flash tool never started"
        assert flashing.poll() is None, flashing.stderr.read().decode()  # type: ignore[union-attr]
        expected = (f"cannot open serial port {board.path}: proleg flash is writing firmware through it "
                    f"(pid {flashing.pid}); wait for the flash to end")
        with pytest.raises(LinkError) as e:
            SerialLink(board.path)
        assert str(e.value) == expected
        console = subprocess.run([sys.executable, "-m", "proleg", "console", "--port", board.path, "--plain",
                                  "--duration", "1"], capture_output=True, text=True, env=_env(), timeout=60)
        assert console.returncode == 1 and console.stderr == f"proleg: error: {expected}\n"
    finally:
        release.touch()
        out, err = flashing.communicate(timeout=60)
    assert flashing.returncode == 0, err
    assert b"flashed" in out
    SerialLink(board.path).close()  # the flash over, the port is free again


def test_a_port_held_by_another_program_is_named_so():
    """Held by a program that is not proleg: its name; nothing readable: a generic line."""
    master, slave = os.openpty()
    path = os.ttyname(slave)
    holder = subprocess.Popen([sys.executable, "-c", "import fcntl, os, sys, time\n"
                               f"fd = os.open({path!r}, os.O_RDWR | os.O_NOCTTY)\n"
                               "fcntl.flock(fd, fcntl.LOCK_EX)\nprint('locked', flush=True)\ntime.sleep(60)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "locked\n"  # type: ignore[union-attr]
        with pytest.raises(PortBusy) as e:
            SerialLink(path)
        program = os.path.basename(sys.executable)
        assert str(e.value) == (f"cannot open serial port {path}: another program has it open ({program}, pid "
                                f"{holder.pid}); close it first")
    finally:
        holder.kill()
        holder.wait()
        os.close(master)
        os.close(slave)


def test_without_proc_locks_the_line_is_generic(monkeypatch):
    from proleg import ports as port_lock

    monkeypatch.setattr(port_lock, "lock_holder", lambda port: None)
    assert busy_message("/dev/ttyUSB0", "flash through") == (
        "cannot flash through /dev/ttyUSB0: another program has it open (a proleg console, run, learn or calibrate?); "
        "close it first")


def test_what_is_no_terminal_is_not_locked(tmp_path):
    """/dev/null, a missing path, a pyserial URL: nothing to lock (the opener reports what is wrong)."""
    for port in ("/dev/null", str(tmp_path / "nope"), "loop://", "socket://localhost:1"):
        with PortLock(port) as a, PortLock(port) as b:
            assert not a.held and not b.held
