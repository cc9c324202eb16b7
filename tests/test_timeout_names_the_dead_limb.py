"""Which limb STATE_TIMEOUT names when two limbs are off their level (docs/safety.md, "The
timeout's detail"), in closed loop: the host-sim firmware with the physical plant.

The robot is inchworm-3 with the tail and head allowed to rise together
(tests/fixtures/inchworm-3-pair.toml). The host loads the user gait 000 -> 101 and starts it
at rest, so the step raises the tail (limb 0, sma-tail) and the head (limb 2, sma-head) at
once. One of the two coils is dead (the plant's ``dead-actuator``: it never heats); the other
is healthy or slow (``power_scale`` 0.6). What the firmware does, and so what it must report:

- Both coils are driven; the live one gets ahead, and from then on waits at the hold duty for
  the dead one (ctl.c: rising together, a limb more than CTL_SYNC_CDEG ahead of the farthest
  waits). So the step never completes and *both* limbs are still off their level when it
  times out: the case where "the last limb off its level" (the head) and "the limb whose coil
  heated longest without progress" (the dead one) can differ.
- The fault is STATE_TIMEOUT, not SMA_ON_LIMIT: the dead coil hits its on-time limit
  (max_on_ms 3 s: reported, not latched), cools 0.8 s and is then switched off by the stall
  detector (CTL_STALL_MS 5 s without progress), so it cannot make the third hit that
  on_limit_latch (3) needs before state_timeout_ms (8 s) of demand is up.
- The detail names the dead coil's limb, and the SUSPECT event its coil, whichever end it is
  on: the live coil heated only until it got ahead (then held at or below the hold ceiling,
  which is not on-time), the dead one for seconds. A firmware naming the last limb off its
  level would name the head in both cases and fail the dead-tail ones.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.link.client import RobotClient
from proleg.link.sim_link import SimLink
from proleg.protocol.definition import EventKind, FaultCode
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.states import limb_levels

ROBOT = Path(__file__).resolve().parent / "fixtures" / "inchworm-3-pair.toml"
LIMBS = {"sma-tail": 0, "sma-head": 2}  # the coil and the limb it raises (same index on inchworm-3)
RISE = 0b101  # state index of 101: tail and head up, middle down (states are in binary order)


def _run(dead: str | None, conditions: list[str]):
    """Start 000 -> 101 with coil ``dead`` dead (if any) and the plant's ``conditions``; return
    the events and the last telemetry frame before the first latched fault."""
    robot = load_robot(ROBOT)
    sim = SimulatedRobot(robot, conditions=conditions)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
    client.connect()
    if dead:
        sim.inject(f"dead-actuator:{dead}")
    client.load_gait([0, RISE])
    client.start("user", "+x")
    events, telemetry, before_fault = [], None, None
    end = client.link.clock() + 12.0
    while client.link.clock() < end:
        m = client.recv(0.5)
        if m is None:
            continue
        if m.name == "TELEMETRY":
            telemetry = m
        elif m.name == "EVENT":
            events.append(m)
            if m.kind == EventKind.GAIT_STOPPED and before_fault is None:
                before_fault = telemetry
            if m.kind == EventKind.SUSPECT:
                break
    client.close()
    return robot, events, before_fault


def _show(events):
    return [(EventKind(m.kind).name, m.code, m.detail, m.time_ms) for m in events]


@pytest.mark.parametrize("other_slow", [False, True], ids=["other-healthy", "other-slow"])
@pytest.mark.parametrize("dead, other", [("sma-tail", "sma-head"), ("sma-head", "sma-tail")],
                         ids=["dead-tail", "dead-head"])
def test_state_timeout_names_the_dead_coils_limb_not_the_other_one_off_its_level(dead, other, other_slow):
    robot, events, tele = _run(dead, [f"power_scale={other}:0.6"] if other_slow else [])
    faults = [m for m in events if m.kind == EventKind.FAULT]
    latched = next((m for m in events if m.kind == EventKind.GAIT_STOPPED), None)
    assert latched is not None, _show(events)
    fault = [m for m in faults if m.time_ms == latched.time_ms]
    assert [m.code for m in fault] == [FaultCode.STATE_TIMEOUT], _show(events)
    # The dead coil did heat: its on-time limit was reported (not latched) before, and on no other coil.
    hits = [m for m in faults if m.code == FaultCode.SMA_ON_LIMIT]
    assert hits and {m.detail for m in hits} == {LIMBS[dead]}, _show(events)
    assert all(m.time_ms < latched.time_ms for m in hits)
    # 8 s of demand of 101 (from the first demand, after 000 is reached and held).
    started = next(m for m in events if m.kind == EventKind.GAIT_STARTED)
    assert 8000 <= latched.time_ms - started.time_ms <= 8400, _show(events)
    # Both limbs off their level when it timed out: the firmware's own (debounced) view.
    assert tele is not None and tele.target == RISE and limb_levels(RISE, robot.levels) == (1, 0, 1)
    measured = limb_levels(tele.measured, robot.levels)
    assert measured[LIMBS[dead]] == 0 and measured[LIMBS[other]] == 0, (measured, tele.psi)
    # The detail names the dead coil's limb; the suspect is its coil.
    assert fault[0].detail == LIMBS[dead], _show(events)
    suspect = [m for m in events if m.kind == EventKind.SUSPECT]
    assert suspect and suspect[0].code == LIMBS[dead], _show(events)


def test_with_no_coil_heated_the_timeout_names_the_last_limb_off_its_level_not_limb_0():
    """At 70 °C ambient no coil cools below its transformation: the robot reaches 101, and in
    the step back to 000 neither the tail nor the head falls. Neither coil heats in that step
    (a falling limb's coil is off), so the guard suspects no coil, and the detail is the rule's
    other half, the last limb off its level: the head. The firmware named the tail: the guard's
    suspect was coil 0 whenever no coil had any time, and limb_off_target preferred coil 0's limb
    whenever it was off its level (now GUARD_NO_SUSPECT, safety.h). Which coil is then suspected
    is not evidence of anything (docs/safety.md); it no longer depends on the coils' numbering."""
    robot, events, tele = _run(None, ["ambient_c=70"])
    reached = [m.detail for m in events if m.kind == EventKind.STATE_REACHED]
    assert RISE in reached, _show(events)
    latched = next((m for m in events if m.kind == EventKind.GAIT_STOPPED), None)
    assert latched is not None, _show(events)
    fault = [m for m in events if m.kind == EventKind.FAULT and m.time_ms == latched.time_ms]
    assert [m.code for m in fault] == [FaultCode.STATE_TIMEOUT], _show(events)
    assert not [m for m in events if m.kind == EventKind.FAULT and m.code == FaultCode.SMA_ON_LIMIT]
    # Both still up, both wanted down, neither coil driven.
    assert tele is not None and tele.target == 0 and limb_levels(tele.measured, robot.levels) == (1, 0, 1)
    assert tele.duty[0] == 0 and tele.duty[2] == 0, tele.duty
    assert fault[0].detail == 2, _show(events)
