"""How a run counts gait cycles (``report.gait_run.GaitRunListener``): from step 0 to step 0 of
one gait, with no stop between."""

from __future__ import annotations

import pytest

from proleg.link.received import Received
from proleg.protocol.codec import Message
from proleg.protocol.definition import EventKind, FaultCode, StopReason
from proleg.report.gait_run import GaitRun, GaitRunListener


def event(kind: EventKind, code: int = 0, detail: int = 0, x_mm: float = 0.0, t_ms: int = 0) -> Received:
    return Received(Message.new("EVENT", time_ms=t_ms, kind=int(kind), code=code, detail=detail), t_ms / 1000,
                    {"displacement_mm": x_mm})


def test_a_cycle_cut_by_a_fault_and_a_fallback_is_not_a_cycle():
    """A faulted, half-walked gait 0 and the fallback gait's first steps used to count as one
    cycle of -7.35 mm (the listener closed a cycle at any step 0 it saw)."""
    run = GaitRun("r", "+x", 0, 30.0)
    listen = GaitRunListener(run)
    for rx in (event(EventKind.GAIT_STARTED, t_ms=200), event(EventKind.STATE_REACHED, 0, 0, 0.0, 200),
               event(EventKind.STATE_REACHED, 1, 2, 1.0, 1200),
               event(EventKind.FAULT, int(FaultCode.STATE_TIMEOUT), 1, -6.0, 10950),
               event(EventKind.GAIT_STOPPED, int(StopReason.FAULT), 0, -6.0, 10950),
               event(EventKind.FALLBACK, 1, 2, -6.0, 10950), event(EventKind.GAIT_STARTED, 255, 0, -6.0, 10950),
               event(EventKind.STATE_REACHED, 0, 2, -7.35, 12300), event(EventKind.STATE_REACHED, 1, 3, -7.0, 13000)):
        listen.on_message(rx)
    assert run.cycle_displacements_mm == []
    listen.on_message(event(EventKind.STATE_REACHED, 0, 2, -5.35, 14000))  # the fallback's first whole cycle
    assert run.cycle_displacements_mm == pytest.approx([2.0])
    assert run.started_s == 0.2  # the first START, not the fallback's
