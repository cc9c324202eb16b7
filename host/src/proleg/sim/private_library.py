"""Load a shared library as a private copy, so each loader gets its own C globals.

``ctypes.CDLL`` of the same path twice returns the same loaded image: two simulated boards
would share one firmware's globals. Copying the file to a unique temporary name first gives
each its own image; the copy is deleted at once (the loaded image stays mapped), so nothing
is left on disk. Used by host-sim (``board.SimBoard``) and the emulators' helper libraries.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
from pathlib import Path

from ..errors import SimError


def load_private_copy(library: Path, *, prefix: str, what: str) -> ctypes.CDLL:
    """``library`` loaded from a fresh copy (``RTLD_LOCAL``); ``SimError("<library>: cannot
    load <what>: ...")`` when it cannot be copied or loaded."""
    fd, copy = tempfile.mkstemp(prefix=prefix, suffix=".so")
    os.close(fd)
    try:
        shutil.copyfile(library, copy)
        return ctypes.CDLL(copy, mode=os.RTLD_LOCAL)
    except OSError as e:
        raise SimError(f"{library}: cannot load {what}: {e}") from None
    finally:
        os.unlink(copy)  # the loaded image stays mapped; nothing is left on disk
