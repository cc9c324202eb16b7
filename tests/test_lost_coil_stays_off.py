"""A coil the fallback gave up is not heated again until the operator takes it back.

docs/safety.md: after a STATE_TIMEOUT or SMA_ON_LIMIT that names a coil, the firmware's
fallback gives that coil up and runs the fallback gait without it; the coil stays given up
until SET_ACTUATOR_MAP with no entries (the operator's word) or a reset. On R1 the fallback
remaps the lost coil's limb onto the other coil, so the map no longer names it. On inchworm-3,
caterpillar-4 and planar-4 the fallback is "dead": the lost coil's limb stays down and stays on
the lost coil in the map. A host (a lab script, or a hostile one) that STOPped the fallback gait,
loaded a gait raising that limb and STARTed it heated the given-up coil again, 4.2 s above the
hold ceiling before the state timeout latched, without any CLEAR or SET_ACTUATOR_MAP. Now the
firmware holds a given-up coil off itself in builds whose fallback keeps it in the map
(CFG_FALLBACK_KEEPS_LOST).

The firmware built for host-sim in closed loop with the physical plant, stepped one control
tick at a time: after the FALLBACK event, until SET_ACTUATOR_MAP with no entries is ACKed
(or the board is reset), the lost coil's PWM must be 0 on every tick.
"""

from __future__ import annotations

import os
from itertools import product

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, rule

from proleg.paths import robots_dir
from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.protocol.definition import ClearWhat, EventKind, ParamId
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot, make_plant

GAIT_USER = 0xFF
NONE = 0xFF


class LostCoilRig:
    """inchworm-3 on host-sim and the physical plant, one tick at a time; its tail coil dies
    and the fallback gives it up. ``given_up``: the coil given up, as the host last learnt it
    (FALLBACK; SET_ACTUATOR_MAP with no entries ACKed, or a reset, takes it back)."""

    def __init__(self, robot: str = "inchworm-3") -> None:
        self.robot = load_robot(robots_dir() / f"{robot}.toml")
        self.sim = SimulatedRobot(self.robot, plant="physical")
        self.decoder = FrameDecoder(len(self.robot.limbs), len(self.robot.actuators))
        self.hold_max_pm = 3000
        self.token = 0
        self.restore_tokens: set[int] = set()
        self.reset()

    def reset(self) -> None:
        self.sim.plant = make_plant(self.robot, "physical", seed=1)  # a fresh plant: every coil alive
        self.sim.board.reset(1)
        self.sim._push_truth()
        self.log: list[Message] = []
        self.given_up = NONE
        self.heated_after_given_up = 0  # ticks the given-up coil carried a duty
        self._acc = [0.0] * len(self.sim.channels)
        self._n = 0

    def send(self, name: str, **fields) -> int:
        self.token = self.token % 255 + 1
        self.sim.write(encode(Message.new(name, token=self.token, **fields)))
        if name == "SET_ACTUATOR_MAP" and not fields.get("actuators"):
            self.restore_tokens.add(self.token)
        return self.token

    def ticks(self, n: int) -> None:
        sim, board = self.sim, self.sim.board
        for _ in range(n):
            board.run_ticks(1)
            for m in self.decoder.feed(sim.read()):
                self.log.append(m)
                if m.name == "EVENT" and m.kind == EventKind.FALLBACK:
                    self.given_up = m.code
                elif m.name == "ACK" and m.token in self.restore_tokens:
                    self.given_up = NONE
            if self.given_up != NONE:
                if board.pwm_permyriad(self.robot.actuators[self.given_up].channel) > 0:
                    self.heated_after_given_up += 1
            for k, c in enumerate(sim.channels):
                self._acc[k] += board.pwm(c)
            self._n += 1
            if self._n == sim.ticks_per_step:
                sim.plant.step(sim.plant_dt_s, [a / self._n for a in self._acc])
                sim._push_truth()
                self._acc = [0.0] * len(sim.channels)
                self._n = 0

    def seconds(self, s: float, ping_s: float = 0.5) -> None:
        """Run ``s`` seconds, a PING every ``ping_s`` (the link watchdog stays fed)."""
        per = round(ping_s * 1000)
        left = round(s * 1000)
        while left > 0:
            self.ticks(min(per, left))
            left -= per
            self.send("PING")

    def events(self, kind: int) -> list[Message]:
        return [m for m in self.log if m.name == "EVENT" and m.kind == kind]

    def fall_back_without(self, dead: str) -> None:
        """Coil ``dead`` dies while gait 0 walks: the fallback gives it up (within 30 s)."""
        self.sim.inject(f"dead-actuator:{dead}")
        self.ticks(300)
        self.send("START", gait=0, direction=0)
        for _ in range(60):
            if self.given_up != NONE:
                break
            self.seconds(0.5)
        lost = next(i for i, a in enumerate(self.robot.actuators) if a.name == dead)
        assert self.given_up == lost, f"{self.robot.name} falls back without its dead coil {dead}"


def _walks(robot, longest: int = 4) -> list[tuple[int, ...]]:
    """Every closed walk of 2..longest states over the robot's allowed transitions (open form)."""
    t = robot.transitions
    allowed = set(zip(t.src.tolist(), t.dst.tolist()))
    out = []
    for n in range(2, longest + 1):
        for walk in product(range(t.n_states), repeat=n):
            if all((walk[i], walk[(i + 1) % n]) in allowed for i in range(n)):
                out.append(walk)
    return out


@pytest.fixture(scope="module")
def rig() -> LostCoilRig:
    return LostCoilRig()


def test_a_loaded_gait_raising_the_given_up_coils_limb_does_not_heat_it(rig):
    """STOP the fallback gait, LOAD_GAIT 000 -> 100 (the tail up), START it: the given-up tail
    coil was heated 4.2 s above the hold ceiling before STATE_TIMEOUT latched."""
    rig.reset()
    rig.fall_back_without("sma-tail")
    rig.send("STOP")
    rig.seconds(3)
    rig.send("LOAD_GAIT", states=(0, 4))
    rig.ticks(5)
    rig.send("START", gait=GAIT_USER, direction=0)
    rig.seconds(12)
    assert rig.heated_after_given_up == 0, f"the given-up tail coil heated {rig.heated_after_given_up} ticks"
    assert rig.events(EventKind.GAIT_STOPPED)[-1].code == 1  # the loaded gait times out instead (a second loss)


@pytest.mark.parametrize("robot, dead, amap, walk", [
    ("paper-r1", "sma-right", (0, 1), (0, 1)),   # remap fallback: both limbs on the left coil
    ("paper-r1", "sma-right", (1, 1), (0, 1)),
    ("inchworm-3", "sma-tail", (0, 1, 2), (0, 4)),  # dead fallback: held off by drive.c as well
])
def test_a_map_naming_the_given_up_coil_is_refused(robot, dead, amap, walk):
    """On R1 the fallback remaps the lost coil's limb, and the firmware held a given-up coil off
    only in builds whose fallback keeps it in the map: STOP, SET_ACTUATOR_MAP [0, 1] (the build's
    own map, not empty: `lost` stayed set), LOAD_GAIT 00 -> 01 and START heated R1's given-up
    right coil 4.2 s above the hold ceiling until the state timeout, no operator's word. The
    host's replanner sent such a map itself after a second loss. Now a non-empty map that names
    the given-up coil is refused (OUT_OF_RANGE, detail = the limb); only the empty map takes it
    back."""
    from proleg.protocol.definition import ErrorCode

    rig = LostCoilRig(robot)
    rig.fall_back_without(dead)
    rig.send("STOP")
    rig.seconds(1)
    token = rig.send("SET_ACTUATOR_MAP", actuators=amap)
    rig.ticks(5)
    m = next(m for m in reversed(rig.log) if m.name in ("ACK", "NACK") and m.token == token)
    assert m.name == "NACK" and m.error == ErrorCode.OUT_OF_RANGE and amap[m.detail] == rig.given_up, m
    rig.send("LOAD_GAIT", states=walk)
    rig.ticks(5)
    rig.send("START", gait=GAIT_USER, direction=0)
    rig.seconds(12)
    assert rig.heated_after_given_up == 0, f"the given-up coil heated {rig.heated_after_given_up} ticks"


EXAMPLES = int(os.environ.get("PROLEG_ATTACK_EXAMPLES", "6"))
STEPS = int(os.environ.get("PROLEG_ATTACK_STEPS", "12"))


class AfterTheFallback(RuleBasedStateMachine):
    """A host after the fallback: any interleaving of STOP, LOAD_GAIT of any allowed walk,
    START (loaded or built-in, either way), CLEAR, SET_PARAM and non-empty SET_ACTUATOR_MAPs.
    None of these takes the coil back; the given-up coil never carries a duty."""

    rig: LostCoilRig
    walks: list[tuple[int, ...]]

    def __init__(self) -> None:
        super().__init__()
        self.rig.reset()
        self.rig.fall_back_without("sma-tail")

    @rule(walk=st.integers(0, 10_000))
    def load(self, walk):
        self.rig.send("LOAD_GAIT", states=self.walks[walk % len(self.walks)])
        self.rig.ticks(2)

    @rule(gait=st.sampled_from([0, 1, GAIT_USER]), direction=st.sampled_from([0, 1]))
    def start(self, gait, direction):
        self.rig.send("START", gait=gait, direction=direction)
        self.rig.ticks(2)

    @rule(walk=st.integers(0, 10_000), direction=st.sampled_from([0, 1]))
    def restart_with_another_gait(self, walk, direction):
        """STOP, LOAD_GAIT and START in one tick: the host's own gait instead of the fallback's."""
        self.rig.send("STOP")
        self.rig.send("LOAD_GAIT", states=self.walks[walk % len(self.walks)])
        self.rig.send("START", gait=GAIT_USER, direction=direction)
        self.rig.ticks(2)

    @rule()
    def stop(self):
        self.rig.send("STOP")
        self.rig.ticks(2)

    @rule(what=st.sampled_from([int(ClearWhat.FAULTS), 7]))
    def clear(self, what):
        self.rig.send("CLEAR", what=what)
        self.rig.ticks(2)

    @rule(amap=st.lists(st.integers(0, 2), min_size=3, max_size=3))
    def remap(self, amap):
        self.rig.send("SET_ACTUATOR_MAP", actuators=tuple(amap))
        self.rig.ticks(2)

    @rule(param=st.sampled_from([ParamId.DRIVE_DUTY, ParamId.HOLD_DUTY, ParamId.HOLD_MS]),
          value=st.sampled_from([100, 3000, 8000]))
    def set_param(self, param, value):
        self.rig.send("SET_PARAM", param=int(param), index=0, value=value)
        self.rig.ticks(2)

    @rule(s=st.sampled_from([0.5, 2.0, 9.0]))
    def wait(self, s):
        self.rig.seconds(s)

    @invariant()
    def the_given_up_coil_stays_off(self):
        assert self.rig.heated_after_given_up == 0, (
            f"the given-up coil carried a duty for {self.rig.heated_after_given_up} ticks")


def test_no_host_sequence_after_the_fallback_heats_the_given_up_coil(rig):
    AfterTheFallback.rig = rig
    AfterTheFallback.walks = _walks(rig.robot)
    AfterTheFallback.TestCase.settings = settings(
        max_examples=EXAMPLES, stateful_step_count=STEPS, deadline=None, suppress_health_check=list(HealthCheck)
    )
    AfterTheFallback.TestCase().runTest()
