"""Leaving a robot stops it: STOP, and ESTOP when the STOP is not acknowledged.

A lab runs this tool next to hot wires: whatever ends a session (the console's q, Ctrl-C, the
terminal window closed, the link lost; ``proleg run``'s end; a learning piece's end or pause),
the coils must not keep cycling because the software went away. The signals that end a session
become exceptions in ``proleg.interrupts.hangup_as_exception``. The console's and run's
``--leave-running`` skips it on purpose. When even the ESTOP gets no answer (the link is gone),
the firmware's link watchdog stops the gait on its own after ``link_watchdog_ms``.
"""

from __future__ import annotations

from ..errors import LinkError
from .client import RobotClient

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
