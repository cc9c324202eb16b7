"""Ctrl-C held off for the length of a write that must not be torn.

A SIGINT becomes ``KeyboardInterrupt`` at whatever Python line the main thread is on. Inside
a recording writer that can be halfway through an MCAP chunk: the footer then follows a torn
chunk, and a recording reported "complete up to there" reads back without its telemetry.

While anyone has called ``hold()`` (a writer, for as long as its file is open), SIGINT goes
to a handler of ours that raises ``KeyboardInterrupt`` at once, as Python's does, except
inside a ``deferred()`` block on the main thread: there it is raised when the block ends,
once. ``release()`` puts Python's handler back after the last holder. Nothing changes off
the main thread (signals are handled only there) or when SIGINT is not Python's default
handler (ignored in a background job, or another handler installed). Per-row cost: a flag,
not a ``signal.signal`` call (those took 18 µs a row).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_holders = 0
_inside = False
_caught = False


def _on_sigint(signum: int, frame: object) -> None:
    global _caught
    if _inside:
        _caught = True
    else:
        raise KeyboardInterrupt


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def hold() -> None:
    """Start deferring Ctrl-C in ``deferred()`` blocks (pair with ``release``)."""
    global _holders
    if not _main_thread():
        return
    if _holders == 0:
        if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
            return  # ignored, or someone else's: left alone (and not counted)
        signal.signal(signal.SIGINT, _on_sigint)
    _holders += 1


def release() -> None:
    """The last holder gone: Python's own SIGINT handler again."""
    global _holders
    if not _main_thread() or _holders == 0:
        return
    _holders -= 1
    if _holders == 0 and signal.getsignal(signal.SIGINT) is _on_sigint:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextmanager
def deferred() -> Iterator[None]:
    """A Ctrl-C during the block is raised after it (also when the block failed: the user's
    Ctrl-C is not lost to its error)."""
    global _inside, _caught
    if _holders == 0 or _inside or not _main_thread():
        yield
        return
    _inside = True
    try:
        yield
    finally:
        _inside = False
        if _caught:
            _caught = False
            raise KeyboardInterrupt
