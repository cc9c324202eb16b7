"""A START whose ACK is lost on the way back, with R1's host-sim firmware in closed loop.

The client sends the same frame again; the board, running the gait the first try started,
refuses it (NOT_ALLOWED: a restart would restart the step, docs/safety.md). The client tells
that refusal from a real one by the TELEMETRY before and after: nothing ran before the first
try, and now the gait asked for runs the way asked for. ``proleg sim --inject link-drop:0.1``
reported every such run as "START failed" while the robot walked."""

from __future__ import annotations

import pytest

from proleg.link import CommandRefused
from proleg.protocol import BY_NAME
from proleg.protocol.codec import decode_frame
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.paths import robots_dir
from proleg.sim.closed_loop import SimulatedRobot


def _session_losing_acks(n: int = 1) -> SimSession:
    """R1's session whose link drops the first ``n`` ACKs of START on their way to the host."""
    session = SimSession(SimulatedRobot(load_robot(robots_dir() / "paper-r1.toml"), plant="table"))
    link = session.link
    read = link.read
    left = [n]
    pending = bytearray()

    def lossy(timeout: float) -> bytes:
        pending.extend(read(timeout))
        *frames, rest = bytes(pending).split(b"\0")
        pending[:] = rest
        out = bytearray()
        for f in frames:
            m = decode_frame(f + b"\0")
            if left[0] and m.name == "ACK" and m.cmd == BY_NAME["START"].id:
                left[0] -= 1
                continue
            out += f + b"\0"
        return bytes(out)

    link.read = lossy  # type: ignore[method-assign]
    session.advance(0.5)
    return session


def test_a_start_whose_ack_was_lost_is_confirmed_by_telemetry_and_the_gait_runs():
    session = _session_losing_acks()
    run = session.run_gait("+x", 0, 6.0)
    assert run.errors == []
    assert session.client.stats.lost_acks == 1 and session.client.stats.retries >= 1
    assert run.started_s is not None and len(run.states_reached) >= 2


def test_a_start_refused_while_another_gait_runs_stays_refused():
    session = _session_losing_acks(0)
    session.request("START", gait=0, direction=0)
    session.advance(0.3)
    with pytest.raises(CommandRefused, match="a gait is running"):
        session.client.request("START", gait=1, direction=1, retries=2)
    assert session.client.stats.lost_acks == 0


def test_a_lost_ack_for_a_start_that_did_not_start_this_gait_is_not_confirmed():
    """The board already ran a gait before the first try: the refusal may be that gait's."""
    session = _session_losing_acks(1)
    session.client.request("START", gait=0, direction=0, retries=3)  # its ACK lost: confirmed
    session.advance(0.3)
    with pytest.raises(CommandRefused, match="a gait is running") as e:
        session.client.request("START", gait=0, direction=0, retries=0)
    assert "try" not in str(e.value)  # the first try: nothing lost to explain
    assert session.client.stats.lost_acks == 1
