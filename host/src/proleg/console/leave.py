"""Leaving a console stops the robot: STOP, and ESTOP when the STOP is not acknowledged.

A lab runs this tool next to hot wires: whatever ends the session (q, Ctrl-C, the terminal
window closed, the link lost), the coils must not keep cycling because the software went
away. ``--leave-running`` skips it on purpose. When even the ESTOP gets no answer (the link is
gone), the firmware's link watchdog stops the gait on its own after ``link_watchdog_ms``.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType

from ..errors import LinkError
from ..link.client import RobotClient

#: sends of STOP (and then ESTOP) before giving up; each waits the client's timeout
LEAVE_RETRIES = 2


def stop_robot(client: RobotClient, *, retries: int = LEAVE_RETRIES) -> str:
    """STOP (ESTOP if the STOP gets no ACK); one line saying what happened. A second Ctrl-C (or a
    SIGTERM) while the STOP waits goes on to the ESTOP, as in ``proleg run``: before, it ended the
    console there, exit 0, with no ESTOP sent and nothing said about the coils."""
    try:
        client.request("STOP", retries=retries)
        return "robot stopped"
    except (LinkError, KeyboardInterrupt) as stop_error:
        why = "interrupted while waiting for it" if isinstance(stop_error, KeyboardInterrupt) else stop_error
        try:
            client.request("ESTOP", retries=retries)
            return f"STOP not acknowledged ({why}); robot E-stopped"
        except LinkError as e:
            return (f"could not stop the robot: {e}; its link watchdog stops a running gait "
                    "once the link stays silent")


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
