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

from proleg.link.listeners import CallbackListener
from proleg.paths import robots_dir
from proleg.protocol.definition import EventKind, FaultCode, ParamId
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.physics.materials import NITI_OVERHEAT_C

GAIT_USER = 0xFF
SAMPLE_S = 0.01  # the coils' temperatures are read this often (their time constant: seconds)


class Host:
    """The project's own client on the firmware and the physical plant, with every EVENT kept
    and the coils' temperatures sampled."""

    def __init__(self, robot):
        self.sim = SimulatedRobot(robot, plant="physical")
        self.events: list = []
        self.session = SimSession(self.sim, listeners=[CallbackListener(self._keep)])
        self.hot_s = [0.0] * len(robot.actuators)  # time above NITI_OVERHEAT_C
        self.peak_c = [0.0] * len(robot.actuators)

    def _keep(self, rx) -> None:
        if rx.message.name == "EVENT":
            self.events.append(rx.message)

    def run(self, seconds: float) -> None:
        for _ in range(max(1, round(seconds / SAMPLE_S))):
            self.session.advance(SAMPLE_S)
            for j, t in enumerate(self.sim.plant.temperature_c):
                self.peak_c[j] = max(self.peak_c[j], float(t))
                if t > NITI_OVERHEAT_C:
                    self.hot_s[j] += SAMPLE_S

    def set_param(self, param: ParamId, value: int) -> None:
        self.session.request("SET_PARAM", param=int(param), index=0, value=value)  # NACK raises

    def of(self, kind: EventKind) -> list:
        return [m for m in self.events if m.kind == kind]


@pytest.fixture(scope="module")
def r1():
    return load_robot(robots_dir() / "paper-r1.toml")


def test_a_threshold_flickered_out_of_reach_of_a_held_coil_latches_before_it_overheats(r1):
    assert r1.safety.max_mean_duty == 0.45  # the default this test is about (robot_settings.Safety)
    host = Host(r1)
    host.run(0.3)
    host.set_param(ParamId.HOLD_MS, 600_000)
    host.session.request("LOAD_GAIT", states=(3, 2))  # 11 -> 10: both rise, then the right one falls
    host.session.request("START", gait=GAIT_USER, direction=0)
    while not host.of(EventKind.STATE_REACHED):
        host.run(0.1)
        assert host.sim.time_s < 20, "11 never reached"
    host.run(1.0)
    host.set_param(ParamId.DEBOUNCE_TICKS, 1000)
    start = host.sim.time_s
    while host.sim.time_s - start < 120 and not host.of(EventKind.GAIT_STOPPED):
        for _ in range(3):
            host.set_param(ParamId.PSI_STAR_CDEG, 8000)  # the left limb's hold edge out of reach
            host.run(0.9)
            host.set_param(ParamId.PSI_STAR_CDEG, 2000)  # back at its level: the debounce restarts
            host.run(0.01)
        host.run(1.1)
    faults = [FaultCode(m.code).name for m in host.of(EventKind.FAULT)]
    assert host.of(EventKind.GAIT_STOPPED), f"no fault stopped the hold in 120 s: left coil above " \
        f"{NITI_OVERHEAT_C:.0f} °C {host.hot_s[0]:.1f} s, peak {host.peak_c[0]:.0f} °C, faults {faults}"
    assert "SMA_ON_LIMIT" in faults, faults  # the held coil's window refusals, as hits
    assert host.sim.time_s - start < 30, (host.sim.time_s - start, faults)
    # the bursts before the latch: a few seconds past the line, not a minute
    assert host.hot_s[0] < 10.0, host.hot_s
