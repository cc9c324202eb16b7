"""Checking a robot file's fields: every reader raises RobotFileError naming the file and the
field (``Fields``), and files are read with a size limit (``read_text``). Shared by the robot
file's sections (``proleg.robot``, ``proleg.robot_limbs``, ``proleg.robot_settings``,
``proleg.robot_transitions``)."""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Any

from .errors import RobotFileError


def toml_text(value: Any) -> str:
    """A value read from a robot file as it was written in TOML (``true``, ``[1, true]``,
    ``{left = 3}``), for error messages: Python's ``True`` or ``{'left': 3}`` is not what the
    user typed. Strings keep their quotes ('abc' is a TOML literal string too)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_text(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (str, int, float)):
        return repr(value)
    return str(value)  # a TOML date or time


class Fields:
    """Reads one TOML table, checking types and refusing keys it does not know."""

    def __init__(self, path: Path, where: str, table: Any, known: set[str], sep: str = "."):
        self.path, self.where, self.sep = path, where, sep
        if not isinstance(table, dict):
            self.fail("", "a table")
        unknown = sorted(set(table) - known)
        if unknown:  # a near miss gets a suggestion, as [plant] keys do; else the whole list
            near = difflib.get_close_matches(str(unknown[0]), sorted(known), n=1)
            hint = f"did you mean {near[0]!r}?" if near else f"expected one of: {', '.join(sorted(known))}"
            raise RobotFileError(f"{path}: {where}: unknown key {unknown[0]!r} ({hint})")
        self.table = table

    def fail(self, key: str, expected: str, got: Any = None, note: str = "") -> None:
        """``note``: said after what was got (`` (64 characters)``)."""
        name = f"{self.where}{self.sep}{key}" if key else self.where
        shown = "" if got is None else f", got {toml_text(got)}"
        raise RobotFileError(f"{self.path}: {name}: expected {expected}{shown}{note}")

    def has(self, key: str) -> bool:
        return key in self.table

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.table:
            if default is None:
                self.fail(key, "a string (required)")
            return default
        v = self.table[key]
        if not isinstance(v, str):
            self.fail(key, "a string", v)
        return v

    def integer(self, key: str, default: int, lo: int, hi: int) -> int:
        v = self.table.get(key, default)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            self.fail(key, f"an integer in {lo}..{hi}", v)
        return v

    def number(self, key: str, default: float | None, lo: float, hi: float, *, open_lo: bool = False) -> float:
        if key not in self.table and default is None:
            self.fail(key, "a number (required)")
        v = self.table.get(key, default)
        span = f" in {'(' if open_lo else '['}{lo}, {hi}]" if math.isfinite(lo) and math.isfinite(hi) else ""
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(key, "a number", v)
        if not math.isfinite(v):  # TOML's nan and inf are floats: "expected a number, got nan" read as nonsense
            self.fail(key, f"a finite number{span}", v)
        if (v <= lo if open_lo else v < lo) or v > hi:
            self.fail(key, f"a number{span}", v)
        return float(v)


def read_text(path: Path, limit: int, what: str) -> str:
    try:
        size = path.stat().st_size
        if size > limit:
            raise RobotFileError(f"{path}: {what} of {size:,} bytes, expected at most {limit:,}")
        with path.open("rb") as fh:
            data = fh.read(limit + 1)  # the file may have grown since stat
        if len(data) > limit:
            raise RobotFileError(f"{path}: {what} larger than {limit:,} bytes")
    except FileNotFoundError:
        raise RobotFileError(f"{path}: no such {what}{_bundled_hint(path) if what == 'robot file' else ''}") from None
    except OSError as e:
        raise RobotFileError(f"{path}: cannot read: {e.strerror or e}") from None
    return decode_utf8(data, path)


def _bundled_hint(path: Path) -> str:
    """For a bare name that is no bundled robot: the closest bundled name, and where they are listed."""
    from .paths import bundled_robots

    if path.suffix or len(path.parts) != 1:
        return ""
    close = difflib.get_close_matches(path.name.lower(), bundled_robots(), n=1, cutoff=0.6)
    like = f" did you mean {close[0]}?" if close else ""
    return f" (nor a bundled robot:{like} `proleg robots` lists them)"


def decode_utf8(data: bytes, path: Path) -> str:
    """``data`` as UTF-8 text, a leading BOM (Notepad, Excel) dropped; bytes that are not
    UTF-8 are a RobotFileError naming the line."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise RobotFileError(f"{path}: line {line}: not UTF-8 text (byte 0x{data[e.start]:02x}: {e.reason}); "
                             "save it as UTF-8") from None
