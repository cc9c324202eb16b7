"""Writing a file the user named as an output (``dbc -o``, ``learn --out``).

``refuse_inputs`` stops an output that is one of the command's own inputs (the same path,
a symlink or a hard link to it): writing it would destroy what the command reads, so it is
a usage error (exit 2) named before anything is read or written. ``write_text_atomic``
writes through a temporary file in the same directory renamed over the output: a failed
write (a full disk, a directory in the way) leaves the old file as it was and no partial
one, and its error names the output (exit 1). ``check_writable`` says that error before a
command's minutes of work, not after it.

``replacing`` is that temporary file for every output proleg renames into place (DBC,
``learn --out``, plots). The rename lands on what the path *means*, never on the path's
own directory entry: a symlink is followed and its target replaced (the link stays a
link), and an existing file that is not a regular file (a FIFO, ``/dev/stdout``,
``/dev/null``, a terminal) is opened and written directly, as a shell redirection would,
so a device node or a pipe is never replaced by a regular file; so is the file standard
output already is (``-o /dev/stdout > x``). ``note_stream`` sends the "wrote PATH" note to
standard error when the output is standard output.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

from .errors import LinkError, UsageError
from .paths import as_if_created


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether ``a`` and ``b`` name one file (after symlinks; hard links when both exist)."""
    a, b = Path(a), Path(b)
    if a.resolve() == b.resolve():
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist yet
        return False


def refuse_inputs(what: str, option: str, out: str | Path, inputs: Mapping[str, str | Path | None]) -> None:
    """``UsageError`` when the output ``out`` (given as ``option``) is one of ``inputs``
    (option or argument name → path; None: not given)."""
    for name, path in inputs.items():
        if path is not None and same_file(out, path):
            raise UsageError(f"{what}: {option} {out} is the {name} file this command reads; "
                             "write the output to another path")


def output_target(path: str | Path) -> tuple[Path, bool]:
    """Where an output named ``path`` lands, and whether it is written in place.

    In place (the path itself, opened as a shell redirection would): an existing file that
    is not a regular file (FIFO, character or block device, socket; ``/dev/stdout`` on a
    pipe or a terminal), or the file this process's standard output is (``-o /dev/stdout >
    out.dbc``). Otherwise the path with every symlink followed (a dangling link: the file it
    points to), to be replaced by a rename."""
    try:
        st = os.stat(path)  # follows symlinks, /proc's fd links to pipes too
    except OSError:  # not there yet (or unreadable: the write says why)
        st = None
    if st is not None and (not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)) or _is_stdout(st)):
        return Path(path), True
    return Path(os.path.realpath(path)), False


def _is_stdout(st: os.stat_result) -> bool:
    try:
        out = os.fstat(sys.stdout.fileno())
    except (AttributeError, OSError, ValueError):  # replaced, closed or not a real file
        return False
    return (out.st_dev, out.st_ino) == (st.st_dev, st.st_ino)


def note_stream(path: str | Path) -> TextIO:
    """Where to say "wrote PATH": standard error when PATH is standard output itself
    (``-o /dev/stdout``), so the note does not land in the output; else standard output."""
    try:
        return sys.stderr if _is_stdout(os.stat(path)) else sys.stdout
    except OSError:
        return sys.stdout


@contextmanager
def replacing(path: str | Path, suffix: str = ".tmp") -> Iterator[Path]:
    """A path to write the output ``path`` to. On a clean exit a temporary file in the
    target's directory is renamed over the target (``output_target``: symlinks followed);
    on an error it is removed and the target left as it was. For a FIFO or device the
    target itself is given, to be written in place. ``OSError`` propagates."""
    target, in_place = output_target(path)
    if in_place:
        yield target
        return
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix, dir=target.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        as_if_created(tmp)
        os.replace(tmp, target)
    finally:
        Path(tmp).unlink(missing_ok=True)


def check_writable(path: str | Path, what: str) -> None:
    """``LinkError`` (exit 1) when the output ``path`` could not be written, in the words its
    write would fail with: a directory in its place, or a folder the temporary file cannot be
    made in. For a command that works for minutes before it writes (``learn --out``, ``sim
    --measure-matrix --out``): they measured first and failed after, the work lost."""
    target, in_place = output_target(path)
    if target.is_dir():
        raise LinkError(f"{what}: cannot write {path}: Is a directory")
    if not in_place and target.parent.is_dir() and not os.access(target.parent, os.W_OK | os.X_OK):
        raise LinkError(f"{what}: cannot write {path}: Permission denied")


def write_text_atomic(path: str | Path, text: str, what: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (``replacing``: temp file + rename, a symlink's
    target replaced, a FIFO or device written in place); ``LinkError`` naming the file when
    it cannot be written (``what``: the command, as the message's prefix); ``UsageError``
    for a directory that does not exist (a bad argument, exit 2, as plot and learn --out say)."""
    out = Path(path)
    for directory in (out.parent, output_target(out)[0].parent):  # "." for a bare file name
        if not directory.is_dir():
            raise UsageError(f"{what}: directory {directory} does not exist")
    try:
        with replacing(out) as tmp, open(tmp, "w", encoding=encoding, newline="\n") as f:
            f.write(text)
    except OSError as e:
        raise LinkError(f"{what}: cannot write {out}: {e.strerror or e}") from None
    return out
