"""The bluepill firmware image of a robot, built once per rendered project and cached."""

from __future__ import annotations

import fcntl
import hashlib
from pathlib import Path

from ...firmware.boards import load_board
from ...robot import Robot
from ...paths import cache_dir

BOARD = "bluepill-f103"


def bluepill_elf(robot: Robot, *, objective: str = "total", max_transitions: int | None = None,
                 board: str = BOARD) -> Path:
    """``firmware.elf`` that ``proleg build ROBOT --board bluepill-f103`` links (or another
    bluepill variant, e.g. bluepill-can), cached under ``$PROLEG_CACHE/emu-arm/``, keyed by
    the rendered project (templates and HAL included)."""
    from ...firmware.build import build, firmware_gaits, render_project

    board = load_board(board)
    files = render_project(robot, board, firmware_gaits(robot, objective, max_transitions))
    digest = hashlib.sha256()
    for rel in sorted(files):
        digest.update(rel.encode() + b"\0" + files[rel].encode() + b"\0")
    out = cache_dir("emu-arm") / f"{robot.name}-{digest.hexdigest()[:16]}"
    elf = out / "firmware.elf"
    if elf.exists():
        return elf
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out.parent / f".{out.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one builder per project (xdist workers); the others wait and reuse it
        if not elf.exists():
            build(robot, board, out, objective=objective, max_transitions=max_transitions)
    return elf
