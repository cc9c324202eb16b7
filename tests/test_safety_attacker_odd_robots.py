"""The attacker of ``test_safety_attacker`` against robots unlike R1, the one it plays against:
three limbs with a three-level middle pad and no written matrix (only LOAD_GAIT gaits), at a
200 Hz tick, a 40 ms ``max_on_ms`` with 125× that of cool-down, ``max_duty`` 1.0 and the coil
heat ceiling; four limbs on two shared coils at 250 Hz with a 10 ms ``max_on_ms``, a
cool-down of 255 on-times, ``on_limit_latch`` 2 and the fallback. The host-sim firmware in
closed loop with the table plant, every tick checked by the same ``EnvelopeMonitor``
(docs/safety.md's rules, the window and the ceiling); commands in bursts within one tick
and across ticks, SET_PARAM at, past and under each build value and on every index, walks of
one-level steps and junk states, maps that share or name no coil, dead coils and bad IMUs.

Besides the envelope: every command gets exactly one reply with its token, and a refusal is one
of the codes the protocol documents for that command (definition.py)."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, rule
from test_safety_attacker import GAIT_USER, Rig

from proleg.protocol.definition import ErrorCode, ParamId
from proleg.robot import load_robot

E = ErrorCode
#: what each command may be refused with (definition.py's command texts); absent: never refused
REFUSALS = {
    "START": {E.ESTOP_LATCHED, E.NOT_ALLOWED, E.OUT_OF_RANGE, E.NO_GAIT, E.TOO_STEEP},
    "LOAD_GAIT": {E.FORBIDDEN_TRANSITION, E.NOT_ALLOWED, E.OUT_OF_RANGE, E.TOO_LONG},
    "SET_PARAM": {E.SAFETY_LIMIT, E.OUT_OF_RANGE},
    "SET_ACTUATOR_MAP": {E.NOT_ALLOWED, E.OUT_OF_RANGE, E.TOO_LONG},
    "CALIBRATE_LEVEL": {E.NOT_ALLOWED, E.OUT_OF_RANGE},
    "CLEAR_LEVEL": {E.NOT_ALLOWED},
}
REPLY = {"GET_STATS": "STATS", "GET_LEVEL": "LEVEL", "GET_ACTUATOR_MAP": "ACTUATOR_MAP", "GET_INFO": "INFO"}

TRI = """
[robot]
name = "tri-odd"
[[limb]]
name = "a"
psi_star_deg = [20.0]
actuator = "ca"
friction = "D1"
[[limb]]
name = "b"
levels = 3
psi_star_deg = [10.0, 22.0]
actuator = "cb"
friction = ["soft", "hard", "soft"]
[[limb]]
name = "c"
psi_star_deg = [20.0]
actuator = "cc"
friction = "D1"
[[actuator]]
name = "ca"
[[actuator]]
name = "cb"
[[actuator]]
name = "cc"
[transitions]
matrix = "unmeasured"
allow = "one-level"
[safety]
max_on_ms = 40
min_cooldown_ms = 5000
max_duty = 1.0
hold_max_duty = 0.2
max_mean_duty = 0.3
coil_heat_ceiling = true
state_timeout_ms = 3000
link_watchdog_ms = 300
[control]
tick_hz = 200
drive_duty = 0.9
hold_duty = 0.1
"""

FOUR_SAFETY = """
[safety]
max_on_ms = 10
min_cooldown_ms = 2550
max_duty = 1.0
hold_max_duty = 0.3
max_mean_duty = 0.3
state_timeout_ms = 2000
on_limit_latch = 2
coil_heat_ceiling = true
"""

EXAMPLES = int(os.environ.get("PROLEG_ATTACK_EXAMPLES", "6"))
STEPS = int(os.environ.get("PROLEG_ATTACK_STEPS", "20"))


def _robot_file(tmp_path, name: str) -> str:
    if name == "tri-odd":
        text = TRI
    else:
        from pathlib import Path

        text = (Path(__file__).parent / "fixtures" / "four-shared.toml").read_text(encoding="utf-8")
        assert "[control]\ntick_hz = 250" in text
        text = text.replace("[control]\ntick_hz = 250", FOUR_SAFETY + "[control]\ntick_hz = 250\nfallback = true")
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


def _attacker(rig: Rig) -> type[RuleBasedStateMachine]:
    robot = rig.robot
    levels, s = robot.levels, robot.safety
    n_states = robot.transitions.n_states
    n_limbs, n_acts = len(levels), len(robot.actuators)
    n_thresholds = sum(k - 1 for k in levels)

    def state(lv: list[int]) -> int:
        x = 0
        for k, v in zip(levels, lv):
            x = x * k + v
        return x

    @st.composite
    def walk(draw) -> tuple[int, ...]:
        """A closed walk of one-level steps from rest (the steps the firmware allows), or junk."""
        if draw(st.booleans()):
            return tuple(draw(st.lists(st.integers(0, n_states), max_size=24)))
        lv, out = [0] * n_limbs, [0]
        for i in draw(st.lists(st.integers(0, n_limbs - 1), min_size=1, max_size=10)):
            lv[i] += 1 if lv[i] == 0 or (lv[i] < levels[i] - 1 and draw(st.booleans())) else -1
            out.append(state(lv))
        while any(lv):
            i = next(k for k in range(n_limbs) if lv[k])
            lv[i] -= 1
            out.append(state(lv))
        return tuple(out[:-1]) if len(out) > 2 else (0, state([1] + [0] * (n_limbs - 1)))

    duty = round(s.max_duty * 10000)
    values = {
        ParamId.DRIVE_DUTY: [0, 1, 5000, duty, duty + 1], ParamId.HOLD_DUTY: [0, 1999, 2000, 3001, duty],
        ParamId.HOLD_MS: [0, 1, 600000, 600001], ParamId.DEBOUNCE_TICKS: [0, 1, 1000, 1001],
        ParamId.STATE_TIMEOUT_MS: [0, 1, s.state_timeout_ms, s.state_timeout_ms + 1],
        ParamId.PSI_STAR_CDEG: [-9000, -8999, 0, 1500, 8999, 9000], ParamId.HYSTERESIS_CDEG: [0, 1, 2000, 2001],
        ParamId.MAX_ON_MS: [0, 1, s.max_on_ms // 2, s.max_on_ms, s.max_on_ms + 1],
        ParamId.MIN_COOLDOWN_MS: [0, s.min_cooldown_ms - 1, s.min_cooldown_ms, 256 * s.max_on_ms, 600001],
        ParamId.LINK_WATCHDOG_MS: [0, 1, 100, s.link_watchdog_ms, s.link_watchdog_ms + 1],
    }
    command = st.one_of(
        st.builds(lambda g, d: ("START", {"gait": g, "direction": d}), st.sampled_from([0, 1, GAIT_USER]),
                  st.sampled_from([0, 1, 2, 0xFF])),
        st.sampled_from([("STOP", {}), ("ESTOP", {}), ("PING", {}), ("GET_STATS", {}), ("GET_LEVEL", {}),
                         ("GET_ACTUATOR_MAP", {}), ("CLEAR_LEVEL", {})]),
        st.builds(lambda w: ("CLEAR", {"what": w}), st.sampled_from([0, 1, 2, 3, 4, 7])),
        st.builds(lambda w: ("LOAD_GAIT", {"states": w}), walk()),
        st.integers(0, 11).flatmap(lambda p: st.builds(
            lambda v, i: ("SET_PARAM", {"param": p, "index": i, "value": v}),
            st.sampled_from(values.get(p, [0, 1])), st.sampled_from([0, n_thresholds - 1, n_thresholds, n_limbs]))),
        st.builds(lambda a: ("SET_ACTUATOR_MAP", {"actuators": tuple(a)}),
                  st.one_of(st.just([]), st.lists(st.integers(0, n_acts), min_size=n_limbs, max_size=n_limbs),
                            st.lists(st.integers(0, n_acts - 1), max_size=n_limbs + 1))),
        st.builds(lambda g: ("CALIBRATE_LEVEL", {"ground": g}), st.sampled_from([0, 1, 2])),
    )

    class OddAttacker(RuleBasedStateMachine):
        def __init__(self):
            super().__init__()
            rig.reset()
            rig.ticks(60)
            self.sent: list[tuple[int, str, int]] = []  # (token, command, index in the log when sent)

        def _send(self, name: str, fields: dict) -> None:
            self.sent.append((rig.send(name, **fields), name, len(rig.log)))

        @rule(burst=st.lists(command, min_size=1, max_size=4))
        def commands_in_one_tick(self, burst):
            for name, fields in burst:
                self._send(name, fields)
            rig.ticks(1)

        @rule(n=st.sampled_from([1, 2, 7, 40, 200, 1000, 3000]))
        def wait(self, n):
            rig.ticks(n)

        @rule(cause=st.sampled_from(["external", "brown-out", "watchdog"]))
        def board_resets(self, cause):
            rig.restart(cause)  # the plant and the monitor go on: what the coils spent is kept
            rig.ticks(60)

        @rule(act=st.sampled_from([a.name for a in robot.actuators]))
        def dead_coil(self, act):
            rig.sim.inject(f"dead-actuator:{act}")  # the envelope's rules hold whatever lifts its limbs

        @rule(limb=st.sampled_from([limb.name for limb in robot.limbs]),
              mode=st.sampled_from(["imu-stuck", "imu-silent", "imu-garbage"]))
        def imu_fault(self, limb, mode):
            rig.sim.inject(f"{mode}:{limb}")

        @invariant()
        def every_command_answered_as_documented(self):
            rig.ticks(3)  # the monitor asserts on every tick
            for token, name, at in self.sent:
                replies = [m for m in rig.log[at:] if getattr(m, "token", None) == token
                           and m.spec.name in ("ACK", "NACK", "STATS", "LEVEL", "ACTUATOR_MAP", "INFO")]
                assert len(replies) == 1, (name, token, replies)
                m = replies[0]
                if m.spec.name == "NACK":
                    assert m.error in REFUSALS.get(name, set()), f"{name} refused with {E(m.error).name}"
                else:
                    assert m.spec.name == REPLY.get(name, "ACK"), (name, m)
            self.sent.clear()

    return OddAttacker


@pytest.mark.parametrize("name", ["tri-odd", "four-shared-odd"])
def test_an_attacker_cannot_get_around_the_envelope_of_an_odd_robot(tmp_path, name):
    rig = Rig(load_robot(_robot_file(tmp_path, name)))
    machine = _attacker(rig)
    machine.TestCase.settings = settings(
        max_examples=EXAMPLES, stateful_step_count=STEPS, deadline=None, suppress_health_check=list(HealthCheck)
    )
    machine.TestCase().runTest()
