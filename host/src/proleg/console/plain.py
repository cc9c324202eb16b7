"""The console without its UI: one line per telemetry frame (``proleg console --plain``, for
pipes), and the line saying whether the console replans after a limb loss."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from typing import TextIO

from ..link.client import RobotClient
from ..link.listeners import Listener, Notifier, Printer


def replan_state(replan: bool, have_robot: bool) -> str:
    """One line: does the console replan after a limb loss, and if not, why not."""
    if not replan:
        return "replan: off (--no-replan)"
    if not have_robot:
        return "replan: off (needs --robot)"
    return "replan on limb loss: on"


def run_plain(client: RobotClient, *, listeners: Sequence[Listener] = (), out: TextIO | None = None,
              duration_s: float | None = None, labels: Callable[[int], str] | None = None,
              quiet: bool = False, keep_open: Sequence[Listener] = ()) -> None:
    """Print one line per telemetry frame (``quiet``: none; the listeners print) until
    interrupted (or ``duration_s`` wall seconds); a link failure ends it with ``LinkError``."""
    printers = [] if quiet else [Printer(out or sys.stdout, telemetry_only=True, labels=labels)]
    notifier = Notifier(client, [*printers, *listeners])
    t_end = None if duration_s is None else time.monotonic() + duration_s
    try:
        while notifier.running and (t_end is None or time.monotonic() < t_end):
            time.sleep(0.05)
    finally:
        notifier.stop(keep=keep_open)  # those the caller closes itself
    if notifier.error is not None:
        raise notifier.error
