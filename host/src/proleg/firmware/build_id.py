"""The firmware's build id: INFO's ``build_id``, what the console's "right firmware" check
compares (docs/safety.md, "The right firmware on the board"), and the seed of the mark by which
core/sma.c trusts the RAM a reset left (docs/safety.md, "A reset").

Contract. ``build_id(robot_sha, board_name, family, pins, gait_hash)`` is ``0x`` and eight hex
digits, the first 32 bits of a SHA-256 over the proleg version, the robot file's bytes (its
SHA-256), the board, its family and PWM pins, the gait table's hash, and
``firmware_sources_sha256()``: every file under the firmware templates. Without the sources, an
image another proleg of the same version number built for the same robot file had the same id,
so flashed over a running board it trusted the old image's RAM whatever its layout.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Sequence
from pathlib import Path

from .. import __version__
from ..paths import templates_dir


def build_id(robot_sha: str, board_name: str, family: str, pins: Sequence[str], gait_hash: str) -> str:
    bh = hashlib.sha256(
        f"proleg {__version__}|{robot_sha}|{board_name}|{family}|{','.join(pins)}|"
        f"{gait_hash[2:].lower()}|{firmware_sources_sha256()}".encode()
    )
    return f"0x{int.from_bytes(bh.digest()[:4], 'big'):08X}"


@functools.cache
def firmware_sources_sha256(root: Path | None = None) -> str:
    """SHA-256 over every file under the firmware templates (core, every HAL, the templates),
    each by its path relative to ``root`` and its bytes, in path order."""
    root = root or templates_dir()
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        rel = path.relative_to(root).as_posix().encode()
        h.update(len(rel).to_bytes(4, "big") + rel)
        data = path.read_bytes()
        h.update(len(data).to_bytes(8, "big") + data)
    return h.hexdigest()
