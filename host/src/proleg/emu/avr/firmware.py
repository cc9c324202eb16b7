"""The exact arduino-nano firmware of a robot, built once per rendered project and cached
under ``$PROLEG_CACHE/avr-emu/`` (what ``proleg build ROBOT --board arduino-nano``
links: the project directory keeps ``firmware.elf`` next to the ``.hex``)."""

from __future__ import annotations

import fcntl
import hashlib
from pathlib import Path

from ...firmware.boards import Board, load_board
from ...robot import Robot
from .library import cache_root

ELF = "firmware.elf"


def nano_build_dir(
    robot: Robot,
    *,
    board: Board | None = None,
    objective: str = "total",
    max_transitions: int | None = None,
) -> Path:
    """The cached build directory of ``robot`` for ``board`` (default arduino-nano)."""
    from ...firmware.build import build, check_tick_budget, firmware_gaits, render_project

    board = board or load_board("arduino-nano")
    check_tick_budget(robot, board)  # a cached build skips build()'s checks: this one depends on the board file
    files = render_project(robot, board, firmware_gaits(robot, objective, max_transitions))
    digest = hashlib.sha256()
    for rel in sorted(files):
        digest.update(rel.encode() + b"\0" + files[rel].encode() + b"\0")
    for flag in (*board.cflags, "|", *board.ldflags):
        digest.update(flag.encode() + b"\0")
    out = cache_root() / "firmware" / f"{robot.name}-{board.name}-{digest.hexdigest()[:16]}"
    if (out / ELF).exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out.parent / f".{out.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one builder per project; the others wait and reuse it
        if not (out / ELF).exists():
            build(robot, board, out, objective=objective, max_transitions=max_transitions)
    return out


def nano_elf(robot: Robot, **kwargs) -> Path:
    """``firmware.elf`` of ``robot`` for the arduino-nano (built now if not cached)."""
    return nano_build_dir(robot, **kwargs) / ELF
