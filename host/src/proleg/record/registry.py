"""Writers and readers chosen by the file's suffix, as python-can's ``can.Logger`` and
``can.LogReader`` do: ``Logger(path, meta)`` → the format's ``Writer``; ``LogReader(path)`` →
its ``Reader``; ``read_recording(path)`` → a ``Recording``. One class per format; adding a
format = a module with a writer and a reader + one line in each table below.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import LinkError, UsageError
from .base import Reader, Recording, Writer
from .csv_format import CsvReader, CsvWriter
from .fields import RecordingMeta
from .jsonl_format import JsonlReader, JsonlWriter
from .mcap_format import McapReader, McapWriter

WRITERS: dict[str, type[Writer]] = {s: w for w in (CsvWriter, JsonlWriter, McapWriter) for s in w.suffixes}
READERS: dict[str, type[Reader]] = {s: r for r in (CsvReader, JsonlReader, McapReader) for s in r.suffixes}


def _lookup(path: str | Path, table: dict) -> type:
    suffix = Path(path).suffix.lower()
    try:
        return table[suffix]
    except KeyError:
        known = ", ".join(sorted(table))
        raise UsageError(f"{path}: unknown record format {suffix or '(none)'!r}; use {known}") from None


def check_suffix(path: str | Path) -> None:
    """Refuse, before connecting to anything, a file name no writer takes or a folder that
    does not exist (exit 2, as every command's output directory), or a place the file cannot
    be written (exit 1, the message a failed open would give): a directory, or a folder that
    is not writable. The robot is never started only to be stopped because its recording
    could not begin."""
    for p in _lookup(path, WRITERS).files(Path(path)):  # a CSV recording is three files
        _check_writable(p)


def _check_writable(p: Path) -> None:
    folder = p.parent  # "." for a bare file name
    why = ("Is a directory" if p.is_dir() else
           "No such file or directory" if not folder.is_dir() else
           "Permission denied" if not os.access(folder, os.W_OK | os.X_OK)
           or (p.exists() and not os.access(p, os.W_OK)) else "")
    if why:
        raise (UsageError if not folder.is_dir() else LinkError)(f"cannot write record file {p}: {why}")


def Logger(path: str | Path, meta: RecordingMeta) -> Writer:  # noqa: N802 (python-can's name)
    """The writer for ``path``'s suffix, opened (metadata written)."""
    return _lookup(path, WRITERS)(path, meta)


def LogReader(path: str | Path) -> Reader:  # noqa: N802
    return _lookup(path, READERS)(path)


def read_recording(path: str | Path) -> Recording:
    """Read any recording back; ``RecordingError`` names the file (and line) when it is bad."""
    return LogReader(path).read()
