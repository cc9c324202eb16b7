"""Flash a built firmware with the board's flash tool (avrdude, openocd, pyocd)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from ..errors import BuildError
from .boards import Board, FlashMethod


def choose_method(board: Board, tool: str | None = None) -> FlashMethod:
    if not board.flash_methods:
        raise BuildError(f"board {board.name} is not flashed: the simulator loads it (proleg sim)")
    if tool is None:
        return board.flash_methods[0]
    for m in board.flash_methods:
        if m.tool == tool:
            return m
    raise BuildError(
        f"board {board.name} has no flash tool {tool!r} (expected one of: "
        f"{', '.join(m.tool for m in board.flash_methods)})"
    )


def flash_command(method: FlashMethod, artifact: Path, port: str | None) -> list[str]:
    if method.needs_port and not port:
        raise BuildError(f"{method.tool} needs the board's serial port: give --port (e.g. /dev/ttyUSB0)")
    return [part.replace("{artifact}", str(artifact)).replace("{port}", port or "") for part in method.command]


def flash(method: FlashMethod, artifact: Path, port: str | None) -> None:
    """Run the flash tool; a missing tool, port or artifact is one clear BuildError."""
    cmd = flash_command(method, artifact, port)
    if not Path(artifact).exists():
        raise BuildError(f"{artifact}: no firmware to flash (build it first)")
    if shutil.which(cmd[0]) is None:
        hint = f" (Debian package: {' '.join(method.packages)})" if method.packages else " (pip install pyocd)"
        raise BuildError(f"{cmd[0]} not found: install it to flash{hint}")
    if method.needs_port and port and port.startswith("/") and not os.path.exists(port):
        raise BuildError(f"{port}: no such serial port (is the board plugged in?)")
    proc = subprocess.run(cmd)
    if proc.returncode != 0:
        raise BuildError(f"{cmd[0]} failed with exit status {proc.returncode}")
