"""Levelling at rest (core/level.c, docs/calibration.md "On a slope"), attacked with command
sequences on the host-sim board and the physical plant: STARTs and STOPs at random moments,
the robot put down on other slopes, flat calibrations and erasures in between.

What must hold whatever the order:
- the ground in use changes only at a START, a calibration or an erase, never while a gait
  runs or the robot rests;
- a START less than 2 s after the previous START or STOP (limbs still coming down) keeps the
  ground in use;
- with no flat record the ground is 0 (nothing to measure it against);
- a START after a long rest on a slope of θ levels each end to ±θ (within 0.5°);
- the ground in use never passes the 20° a calibration accepts;
- START is refused (TOO_STEEP) exactly when the ground in use rises more than R1's
  max_climb_deg in the gait's direction, and then nothing starts.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule

from proleg.link.client import CommandRefused, RobotClient
from proleg.link.level import calibrate_level, clear_level, get_level
from proleg.link.sim_link import SimLink
from proleg.paths import resolve_robot
from proleg.protocol.definition import ErrorCode, LevelStatus
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot, make_plant

R1 = load_robot(resolve_robot("paper-r1"))
MOUNT = ["imu_offset_deg=left:5", "imu_offset_deg=right:-3"]
REST_S = 2.0          # LEVEL_REST_TICKS at R1's 1 kHz
LEVEL_MAX_CDEG = 2000
MAX_CLIMB_CDEG = round(R1.control.max_climb_deg.plus_x * 100)  # the same both ways


def _plant(incline: int):
    return make_plant(R1, "physical", MOUNT + [f"incline_deg={incline}"])


class LevellingAtRest(RuleBasedStateMachine):
    def __init__(self) -> None:
        super().__init__()
        self.sim = SimulatedRobot(R1, conditions=MOUNT)
        self.client = RobotClient(SimLink(self.sim, step_s=self.sim.plant_dt_s))
        self.client.connect()
        self.incline = 0
        self.running = False
        self.last_motion = self.client.link.clock()  # the last START or STOP
        self.rested_since = self.client.link.clock()  # on this ground, every coil cold, no gait since
        self.ground = get_level(self.client).ground_cdeg

    @initialize(record=st.booleans())
    def maybe_calibrated(self, record: bool) -> None:
        """Half the runs start with a flat record (what levelling needs), half without."""
        if record:
            self._wait(0.3)
            assert calibrate_level(self.client).ok
            self.rested_since = self._now()
            self.ground = self._reading().ground_cdeg

    def teardown(self) -> None:
        self.client.close()

    def _now(self) -> float:
        return self.client.link.clock()

    def _wait(self, seconds: float) -> None:
        end = self._now() + seconds
        while self._now() < end:
            self.client.recv(0.05)

    def _reading(self):
        return get_level(self.client)

    @rule(seconds=st.sampled_from([0.1, 0.4, 1.0, 1.7, 3.0, 6.0]))
    def wait(self, seconds: float) -> None:
        self._wait(seconds)
        assert self._reading().ground_cdeg == self.ground  # nothing levels between commands

    @rule(direction=st.sampled_from(["+x", "-x"]))
    def start(self, direction: str) -> None:
        if self.running:
            return
        soon = self._now() - self.last_motion < REST_S
        long_rest = self._now() - self.rested_since > 8.0
        self.client.clear()
        try:
            self.client.start(0, direction)
            refused = None
        except CommandRefused as e:
            refused = e
        reading = self._reading()
        if soon or reading.status != LevelStatus.STORED:
            assert reading.ground_cdeg == self.ground, "levelled without 2 s of rest or a flat record"
        elif long_rest:
            first, last = reading.ground_cdeg
            assert abs(first - 100 * self.incline) < 50 and abs(last + 100 * self.incline) < 50, reading
        self.ground = reading.ground_cdeg
        # R1's climb guard ([control] max_climb_deg, docs/calibration.md) on the ground just levelled:
        # refused exactly when that ground rises more than the limit in the gait's direction
        first, last = reading.ground_cdeg
        climb2 = (first - last) * (1 if direction == "+x" else -1)  # twice the climb, 0.01°
        steep = reading.status == LevelStatus.STORED and climb2 > 2 * MAX_CLIMB_CDEG
        assert (refused is not None) == steep, (reading, direction, refused)
        if refused is not None:
            assert refused.error == ErrorCode.TOO_STEEP and refused.detail == climb2 // 2
            return  # nothing started: no motion, the robot still rests
        self.running = True
        self.last_motion = self._now()

    @precondition(lambda self: self.running)
    @rule()
    def stop(self) -> None:
        self.client.stop()
        self.running = False
        self.last_motion = self._now()
        self.rested_since = self._now() + 1e9  # its limbs come down and cool: not a known rest
        assert self._reading().ground_cdeg == self.ground

    @precondition(lambda self: not self.running)
    @rule(incline=st.sampled_from([-10, -5, 0, 5, 10]))
    def put_down(self, incline: int) -> None:
        """Picked up (cold, as it had cooled) and put down on another slope."""
        self.sim.plant = _plant(incline)
        self.incline = incline
        self.rested_since = self._now()
        assert self._reading().ground_cdeg == self.ground

    @precondition(lambda self: self.running)
    @rule(pause=st.sampled_from([0.0, 0.5, 1.5, 1.9]), incline=st.sampled_from([None, -10, 0, 10]))
    def stop_and_restart(self, pause: float, incline: int | None) -> None:
        """Stopped, perhaps moved, started again before 2 s: the ground in use stays."""
        self.stop()
        if incline is not None:
            self.put_down(incline)
        self._wait(pause)
        self.start("-x")

    @precondition(lambda self: not self.running)
    @rule(incline=st.sampled_from([-10, -5, 5, 10]), rest=st.sampled_from([8.5, 10.0]))
    def put_down_rest_and_start(self, incline: int, rest: float) -> None:
        """The workflow levelling is for: put down on a slope, left a while, started."""
        self.put_down(incline)
        self.wait(rest)
        self.start("+x")

    @precondition(lambda self: not self.running and self.incline == 0)
    @rule()
    def calibrate_flat(self) -> None:
        self.sim.plant = _plant(0)  # at rest on the flat: coils cold
        self.rested_since = self._now()
        self._wait(0.3)
        assert calibrate_level(self.client).ok
        reading = self._reading()
        assert reading.ground_cdeg == (0, 0)  # a flat calibration sets the ground back
        self.ground = reading.ground_cdeg

    @precondition(lambda self: not self.running)
    @rule()
    def clear(self) -> None:
        reading = clear_level(self.client)
        assert reading.status == LevelStatus.NONE and reading.ground_cdeg == (0, 0)
        self.ground = reading.ground_cdeg

    @invariant()
    def bounded_and_only_with_a_record(self) -> None:
        reading = self._reading()
        assert all(abs(g) <= LEVEL_MAX_CDEG for g in reading.ground_cdeg)
        if reading.status != LevelStatus.STORED:
            assert reading.ground_cdeg == (0, 0)


#: CI runs a fixed set of sequences (derandomize); PROLEG_LEVEL_EXAMPLES=N (with
#: PROLEG_LEVEL_RANDOM=1 for fresh ones) runs more.
LevellingAtRest.TestCase.settings = settings(
    max_examples=int(os.environ.get("PROLEG_LEVEL_EXAMPLES", "12")), stateful_step_count=12, deadline=None,
    derandomize=os.environ.get("PROLEG_LEVEL_RANDOM") != "1",
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
TestLevellingAtRest = LevellingAtRest.TestCase
