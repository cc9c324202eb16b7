"""A host that keeps a held limb's hold edge out of reach cannot keep its coil hot.

The attack (found by an adversarial review, docs/safety.md "Keys"): R1 holds 11 with a long
hold; the host sets ``debounce_ticks`` 1000 so the limb keeps reading its level, then moves
the left threshold to 80° (its hold edge out of reach: the bang-bang hold heats the coil at
the drive duty) for 0.9 s at a time, and back to 20° for a few ticks (the debounce starts
again), with a 1.1 s rest after every three bursts to pay the on-time debt back. Every burst
is shorter than ``max_on_ms``, so only the mean-duty window bounds the heating. With the old
default ``max_mean_duty`` 0.5 the window never refused: the left coil was above 120 °C for
48 s of 122 s (peak 136 °C) with no fault. At the default 0.45 the window
refuses a held coil that asks for more, which is an on-limit hit; the third latches
SMA_ON_LIMIT 23 s into the attack, after 6 s above 120 °C.

The physical plant's coil temperature is the judge.
"""

from __future__ import annotations

import pytest

from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.protocol.definition import EventKind, FaultCode, ParamId
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.sim.physical.materials import NITI_OVERHEAT_C

GAIT_USER = 0xFF


class Host:
    """The firmware and the physical plant, with the coils' temperatures recorded."""

    def __init__(self, robot):
        self.sim = SimulatedRobot(robot, plant="physical")
        self.decoder = FrameDecoder(len(robot.limbs), len(robot.actuators))
        self.log: list = []
        self.token = 0
        self.hot_s = [0.0] * len(robot.actuators)  # time above NITI_OVERHEAT_C
        self.peak_c = [0.0] * len(robot.actuators)

    def run(self, seconds: float) -> None:
        sim = self.sim
        for k in range(max(1, round(seconds / sim.plant_dt_s))):
            sim.step()
            for j, t in enumerate(sim.plant.temperature_c):
                self.peak_c[j] = max(self.peak_c[j], float(t))
                if t > NITI_OVERHEAT_C:
                    self.hot_s[j] += sim.plant_dt_s
            if k % 100 == 99:
                self.send("PING")  # the link watchdog
        self.log += self.decoder.feed(sim.read())

    def send(self, name: str, **fields) -> int:
        self.token = self.token % 255 + 1
        self.sim.write(encode(Message.new(name, token=self.token, **fields)))
        return self.token

    def ok(self, name: str, **fields) -> None:
        token = self.send(name, **fields)
        self.run(0.02)
        reply = next(m for m in reversed(self.log) if m.spec.name in ("ACK", "NACK") and m.token == token)
        assert reply.spec.name == "ACK", (name, fields, reply)

    def set_param(self, param: ParamId, value: int, index: int = 0) -> None:
        self.send("SET_PARAM", param=int(param), index=index, value=value)  # acked, not awaited

    def events(self, kind: EventKind) -> list:
        return [m for m in self.log if m.spec.name == "EVENT" and m.kind == kind]

    def latched(self) -> bool:
        return any(m.spec.name == "EVENT" and m.kind == EventKind.GAIT_STOPPED for m in self.log)


@pytest.fixture(scope="module")
def r1():
    return load_robot(robots_dir() / "paper-r1.toml")


def test_a_threshold_flickered_out_of_reach_of_a_held_coil_latches_before_it_overheats(r1):
    assert r1.safety.max_mean_duty == 0.45  # the default this test is about (robot_settings.Safety)
    host = Host(r1)
    host.run(0.3)
    host.ok("SET_PARAM", param=int(ParamId.HOLD_MS), index=0, value=600_000)
    host.ok("LOAD_GAIT", states=(3, 2))  # 11 -> 10: both rise, then the right one falls
    host.ok("START", gait=GAIT_USER, direction=0)
    while not host.events(EventKind.STATE_REACHED):
        host.run(0.1)
        assert host.sim.time_s < 20, "11 never reached"
    host.run(1.0)
    host.ok("SET_PARAM", param=int(ParamId.DEBOUNCE_TICKS), index=0, value=1000)
    start = host.sim.time_s
    while host.sim.time_s - start < 120 and not host.latched():
        for _ in range(3):
            host.set_param(ParamId.PSI_STAR_CDEG, 8000)  # the left limb's hold edge out of reach
            host.run(0.9)
            host.set_param(ParamId.PSI_STAR_CDEG, 2000)  # back at its level: the debounce restarts
            host.run(0.01)
        host.run(1.1)
    faults = [FaultCode(m.code).name for m in host.events(EventKind.FAULT)]
    assert host.latched(), f"no fault stopped the hold in 120 s: left coil above {NITI_OVERHEAT_C:.0f} °C " \
                           f"{host.hot_s[0]:.1f} s, peak {host.peak_c[0]:.0f} °C, faults {faults}"
    assert "SMA_ON_LIMIT" in faults, faults  # the held coil's window refusals, as hits
    assert host.sim.time_s - start < 30, (host.sim.time_s - start, faults)
    # the bursts before the latch: a few seconds past the line, not a minute
    assert host.hot_s[0] < 10.0, host.hot_s
