"""Ctrl-C held off for the length of a write that must not be torn.

A SIGINT becomes ``KeyboardInterrupt`` at whatever Python line the main thread is on. Inside
a recording writer that can be halfway through an MCAP chunk: the footer then follows a torn
chunk, and a recording reported "complete up to there" reads back without its telemetry.

While anyone holds (``hold()``, a writer for as long as its file is open), SIGINT goes to a
handler of ours that raises ``KeyboardInterrupt`` at once, as Python's does, except inside a
``deferred()`` block on the main thread: there the first Ctrl-C is raised when the block
ends. A second one inside the same block raises at once, so a write that blocks (a stalled
pipe, a hung mount) never keeps the user from stopping the robot. ``release()`` puts
Python's handler back after the last holder. Nothing is deferred off the main thread
(signals are handled only there), and an ignored SIGINT (a background job) or another
handler is left alone; in a background job SIGTERM and SIGHUP still come as a Ctrl-C
(``take_terminations``, ``terminate``) and are deferred the same way. Per row: a flag, not a ``signal.signal`` call (those took 18 µs).

A pool's worker process leaves Ctrl-C to its parent (``quiet_worker``); ``in_workers`` runs
a command's work in such workers and says so when one dies instead of waiting for it.

A session with a robot (console, run) ends on SIGHUP or SIGTERM as on a Ctrl-C:
``hangup_as_exception`` turns them into an exception (or a callback to the UI), so the
``finally`` that stops the robot (``proleg.link.leave``) runs instead of the process dying.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from types import FrameType

_lock = threading.Lock()
_holders = 0
_inside = False
_caught = False
#: SIGTERM/SIGHUP come as a Ctrl-C (``terminate``) while SIGINT itself is ignored (a background job)
_terminations = False


def _on_sigint(signum: int, frame: object) -> None:
    global _caught
    if _holders and _inside and not _caught:
        _caught = True  # raised when the block ends
    else:
        raise KeyboardInterrupt  # outside a block, a second Ctrl-C, or nobody holds any more


def take_terminations() -> None:
    """SIGTERM and SIGHUP will call ``terminate``, though SIGINT is ignored (``proleg run … &``
    in a script: a shell's background job ignores Ctrl-C, not ``kill``): writers hold and defer
    for them as for a Ctrl-C."""
    global _terminations
    _terminations = True


def terminate(signum: int, frame: object) -> None:
    """A SIGTERM/SIGHUP handler raising ``KeyboardInterrupt`` as a Ctrl-C would, deferred
    inside a ``deferred()`` block (for a process whose SIGINT is ignored)."""
    _on_sigint(signum, frame)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def hold() -> bool:
    """Start deferring Ctrl-C in ``deferred()`` blocks. True when counted: the caller then
    owes one ``release()``; False (nothing to release) off the main thread or when SIGINT is
    ignored or someone else's."""
    global _holders
    if not _main_thread():
        return False
    with _lock:
        current = signal.getsignal(signal.SIGINT)
        if current is not _on_sigint:
            if current is signal.SIG_IGN and _terminations:
                pass  # Ctrl-C stays ignored; SIGTERM/SIGHUP reach _on_sigint through terminate
            elif current is not signal.default_int_handler:
                return False
            else:
                signal.signal(signal.SIGINT, _on_sigint)
        _holders += 1
        return True


def release() -> None:
    """One holder fewer (from any thread); after the last, Python's own handler again (on the
    main thread; off it, ours stays and acts as Python's until ``settle()`` or a hold)."""
    global _holders
    with _lock:
        _holders = max(0, _holders - 1)
    settle()


def settle() -> None:
    """On the main thread with nobody holding: Python's own handler back, if ours is still in."""
    with _lock:
        if _holders == 0 and _main_thread() and signal.getsignal(signal.SIGINT) is _on_sigint:
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


@contextmanager
def whole() -> Iterator[None]:
    """Hold and defer for the length of the block: a Ctrl-C in it is raised after it. For
    opening a writer and handing it to whoever will close it (``listeners.append(Logger(…))``):
    a Ctrl-C between the two would leave a recording nobody closes (an MCAP without its
    footer)."""
    counted = hold()
    try:
        with deferred():
            yield
    finally:
        if counted:
            release()


class _Hangup(Exception):
    """SIGHUP/SIGTERM arrived: the terminal went away or someone asked us to end."""


@contextmanager
def hangup_as_exception(on_signal: Callable[[], None] | None = None) -> Iterator[list[int]]:
    """On SIGHUP (the terminal window closed) or SIGTERM, call ``on_signal`` (e.g. ask the UI to
    exit) or raise in the main thread, so the caller's ``finally`` (which stops the robot)
    runs instead of the process just dying. Yields the list of the signals that arrived: the
    caller's exit status is 128 + the first (143, 129), as every command's is; before, the
    console took them for a ``q`` and exited 0, so a CI job's timeout looked like a clean end."""
    ended_by: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield ended_by
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        ended_by.append(signum)
        if on_signal is not None:
            on_signal()
        else:
            raise _Hangup(signal.Signals(signum).name)

    old = {}
    for sig in (getattr(signal, "SIGHUP", None), signal.SIGTERM):
        if sig is not None:
            old[sig] = signal.signal(sig, handler)
    try:
        yield ended_by
    except (_Hangup, KeyboardInterrupt):
        pass  # the caller's finally has stopped the robot; end quietly
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def quiet_worker() -> None:
    """A worker process's setup: no plant advice per row (the rows say what happened); Ctrl-C
    is the parent's to handle, and SIGTERM (how the parent's pool ends its workers) ends a
    worker, whatever handler the forked parent had for it (``proleg`` turns SIGTERM into a
    Ctrl-C, which a worker ignores). For ``multiprocessing`` pools: ``proleg check``'s rows,
    ``--measure-matrix --hold-range``'s margins (``sim.physical.measure``), the sweep bench."""
    import logging

    logging.disable(logging.WARNING)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)


def worker_pool(n_jobs: int):
    """A ``ProcessPoolExecutor`` of ``n_jobs`` forked workers set up by ``quiet_worker``. Unlike
    ``multiprocessing.Pool``, whose lost task a killed worker leaves to be waited for ever (a
    lab's CI hung), its futures fail with ``BrokenProcessPool`` when a worker dies: callers
    turn that into ``WorkerLost`` (``lost_worker``) and leave through ``end_workers``."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(n_jobs, mp_context=multiprocessing.get_context("fork"), initializer=quiet_worker)


def end_workers(pool) -> None:
    """Leave ``worker_pool``'s pool: nothing queued starts, and a worker still at work is ended
    (SIGTERM; after a Ctrl-C or an error no worker goes on for nobody)."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5.0)


def lost_worker(what: str):
    """The ``WorkerLost`` for a worker that died while doing ``what``."""
    from .errors import WorkerLost

    return WorkerLost(f"a worker process died while {what} (killed by the system, out of memory, or by a signal); "
                      "nothing it was doing is reported: run again, or with --jobs 1 to keep it in this process")


def in_workers(fn: Callable, items: Iterable, n_jobs: int, what: str = "working") -> Iterator:
    """``fn(item)`` for each of ``items`` in up to ``n_jobs`` workers (``worker_pool``), yielded
    in order as each is done; ``WorkerLost`` when a worker dies (``what``: what they were doing,
    for the message). Leaving early (Ctrl-C, an error, the caller stops) ends the workers."""
    from concurrent.futures.process import BrokenProcessPool

    pool = worker_pool(n_jobs)
    try:
        futures = [pool.submit(fn, item) for item in items]
        for future in futures:
            try:
                yield future.result()
            except BrokenProcessPool:
                raise lost_worker(what) from None
    finally:
        end_workers(pool)

