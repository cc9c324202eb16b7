"""Writing a file the user named as an output (``dbc -o``, ``learn --out``).

``refuse_inputs`` stops an output that is one of the command's own inputs (the same path,
a symlink or a hard link to it): writing it would destroy what the command reads, so it is
a usage error (exit 2) named before anything is read or written. ``write_text_atomic``
writes through a temporary file in the same directory renamed over the output: a failed
write (a full disk, a directory in the way) leaves the old file as it was and no partial
one, and its error names the output (exit 1).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

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


def write_text_atomic(path: str | Path, text: str, what: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (temp file + rename); ``LinkError`` naming the
    file when it cannot be written (``what``: the command, as the message's prefix)."""
    out = Path(path)
    directory = out.parent  # "." for a bare file name
    if not directory.is_dir():
        raise LinkError(f"{what}: directory {directory} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding=encoding, newline="\n") as f:
            f.write(text)
        as_if_created(tmp)
        os.replace(tmp, out)
    except OSError as e:
        Path(tmp).unlink(missing_ok=True)
        raise LinkError(f"{what}: cannot write {out}: {e.strerror or e}") from None
    return out
