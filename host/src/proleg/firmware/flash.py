"""Flash a built firmware with the board's flash tool (avrdude, openocd, pyocd, stm32flash).

The commands come from the board file's ``[[flash]]`` tables. One adjustment is made
here: a pseudo-terminal (an emulated board's serial port, ``proleg.emu``) cannot carry
parity — Linux's pty driver clears PARENB on every termios change (drivers/tty/pty.c,
``pty_set_termios``) — so stm32flash's default 8E1, which the STM32 ROM bootloader needs
on a real USART, fails stm32flash's own read-back check on a pty ("Failed to set terminal
flags"). On a pty stm32flash is given ``-m 8n1``; the emulated bootloader needs no parity.

A tool that writes through a serial port (avrdude, stm32flash) takes no lock on it: ``flash``
holds proleg's own (``proleg.ports``, the one a console or run holds) while the tool runs,
and refuses, before building, a port a console, run, learn or calibrate has open.
"""

from __future__ import annotations

import logging
import os
import shutil
import signal
import stat
import subprocess
from pathlib import Path

from ..errors import BuildError, Interrupted, LinkError
from ..ports import hold_port, refuse_if_held
from .boards import Board, FlashMethod


def choose_method(board: Board, tool: str | None = None, port: str | None = None) -> FlashMethod:
    """The board's flash method ``tool`` (default its first). A ``port`` given to a tool that
    takes none is refused: it was dropped, and bluepill's default openocd flashed over the
    ST-Link whatever serial port was named (a board on a USB-serial adapter meant stm32flash)."""
    if not board.flash_methods:
        raise BuildError(f"board {board.name} is not flashed: the simulator loads it (proleg sim)")
    method = next((m for m in board.flash_methods if m.tool == tool), None) if tool else board.flash_methods[0]
    if method is None:
        raise BuildError(
            f"board {board.name} has no flash tool {tool!r} (expected one of: "
            f"{', '.join(m.tool for m in board.flash_methods)})"
        )
    if port and not method.needs_port:
        serial = [m.tool for m in board.flash_methods if m.needs_port]
        hint = f"; --tool {' or '.join(serial)} flashes through a serial port" if serial else ""
        raise BuildError(f"--port {port}: {method.tool} takes no serial port{hint}; or leave --port out")
    return method


log = logging.getLogger("proleg")

#: options a tool needs on a pseudo-terminal (see the module docstring), placed after its name
PTY_OPTIONS: dict[str, tuple[str, ...]] = {"stm32flash": ("-m", "8n1")}
#: Linux device majors of Unix98 pty slaves (/dev/pts/N): UNIX98_PTY_SLAVE_MAJOR .. + 7
_PTY_MAJORS = range(136, 144)


def is_pseudo_terminal(port: str | None) -> bool:
    """Whether ``port`` (possibly a symlink) is the slave side of a pseudo-terminal."""
    if not port:
        return False
    try:
        st = os.stat(port)
    except OSError:
        return False
    return stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) in _PTY_MAJORS


#: tools whose arguments are scripts in their own language, where a path written into a longer
#: argument is split at its spaces (openocd's ``-c 'program {artifact} ...'`` is Tcl): the path is
#: escaped for that language there (an argument that is the path alone is passed as it is)
SCRIPT_QUOTING = {"openocd": "tcl"}


def tcl_word(text: str) -> str:
    r"""``text`` as one Tcl word: each character Tcl gives a meaning (white space, ``; $ [ ] { }
    " \``) escaped with a backslash, so ``program build/my robot/firmware.bin`` does not hand
    openocd's ``program`` the file ``build/my`` and an address ``robot/firmware.bin``, and a
    Windows path keeps its backslashes."""
    return "".join("\\" + c if c in ' \t;$[]{}"\\' else ("\\n" if c == "\n" else c) for c in text)


def flash_command(method: FlashMethod, artifact: Path, port: str | None) -> list[str]:
    if method.needs_port and not port:
        raise BuildError(f"{method.tool} needs the board's serial port: give --port (e.g. /dev/ttyUSB0)")
    program = Path(method.command[0]).name if method.command else method.tool
    tcl = "tcl" in (SCRIPT_QUOTING.get(method.tool), SCRIPT_QUOTING.get(program))
    quoted = tcl_word(str(artifact)) if tcl else str(artifact)
    cmd = [str(artifact) if part == "{artifact}" else part.replace("{artifact}", quoted).replace("{port}", port or "")
           for part in method.command]
    extra = PTY_OPTIONS.get(method.tool, ())
    if extra and method.needs_port and is_pseudo_terminal(port):
        log.info("%s is a pseudo-terminal (no parity): %s gets %s", port, method.tool, " ".join(extra))
        cmd[1:1] = extra
    return cmd


def check_tool(method: FlashMethod, port: str | None) -> None:
    """``BuildError`` for a flash tool that is not installed or a serial port that is not there
    (``proleg flash`` asks before building: it built the firmware, then said the tool was missing)."""
    cmd = flash_command(method, Path("firmware"), port)
    if shutil.which(cmd[0]) is None:
        hint = f" (Debian package: {' '.join(method.packages)})" if method.packages else " (pip install pyocd)"
        raise BuildError(f"{cmd[0]} not found: install it to flash{hint}")
    if method.needs_port and port and port.startswith("/") and not os.path.exists(port):
        raise BuildError(f"{port}: no such serial port (is the board plugged in?)")
    if method.needs_port and port:
        refuse_if_held(port, doing="flash through")  # a console on the port: said before building, unopened


def flash(method: FlashMethod, artifact: Path, port: str | None) -> None:
    """Run the flash tool; a missing tool, port or artifact is one clear BuildError (usage),
    a tool that fails (no sync, verify error) a LinkError."""
    cmd = flash_command(method, artifact, port)
    if not Path(artifact).exists():
        raise BuildError(f"{artifact}: no firmware to flash (build it first)")
    check_tool(method, port)
    # The port is locked (proleg.ports, the console's own lock) while the tool writes: a console,
    # run or record started meanwhile is refused instead of reading the bootloader's replies.
    with hold_port(port if method.needs_port else None, doing="flash through"):
        try:
            proc = subprocess.run(cmd)  # on Ctrl-C: a moment for the tool to end on its own, then killed
        except KeyboardInterrupt:  # Ctrl-C, SIGTERM: "interrupted" alone hid that the board may hold half a firmware
            raise Interrupted(f"interrupted while {cmd[0]} was flashing {artifact}: the board's flash may hold part "
                              "of it (flash it again before using the board)") from None
    if proc.returncode < 0:  # killed by a signal (-9): "exit status -9" named no signal
        raise LinkError(f"{cmd[0]} was killed by {_signal_name(-proc.returncode)} (its messages are above); the "
                        "board's flash may hold part of the firmware: flash it again")
    if proc.returncode != 0:  # the board did not answer or refused: a failure (exit 1), not a usage error
        raise LinkError(f"{cmd[0]} failed with exit status {proc.returncode} (its messages are above)")


def _signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"
