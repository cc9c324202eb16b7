"""An attacker against the firmware's safety envelope (issue 12), on the host-sim board.

The firmware built for host-sim runs in closed loop with the plant, one control tick at a
time. After every tick an ``EnvelopeMonitor`` checks the PWM each coil carries against the
envelope's rules on the virtual clock, and the plant's true coil temperature against a
stated ceiling:

- duty ≤ max_duty;
- an on-period (duty above the hold ceiling) lasts at most max_on + one tick;
- cool-down in proportion to every on-period: the on-time not yet paid back by cool-down
  (each µs not on pays back max_on / min_cooldown µs) never exceeds max_on + one tick, so
  an on-period of L owes L × min_cooldown / max_on before the full max_on is back;
- the duty integrated over any window of duty_window_ms is at most max_mean_duty × window
  (plus one tick at max_duty);
- every coil stays below the steady-state temperature of max_duty plus 5 K;
- a dead coil (one that cannot lift its limb) is heated above the hold ceiling for at most
  state_timeout_ms (+ two ticks) in all between two latched faults, whatever the host does
  in between (STOP, START, LOAD_GAIT ...): no target it heats towards is ever reached, so
  each coil's own step time (docs/safety.md) must latch a fault first.

The three bypasses found in issue 12 are explicit regression tests; a hypothesis
``RuleBasedStateMachine`` then interleaves STOP/START/ESTOP/CLEAR/LOAD_GAIT/SET_PARAM/SET_ACTUATOR_MAP
within one tick and across ticks with dead coils, stuck or silent IMUs and dropped and
replayed frames. ``PROLEG_ATTACK_EXAMPLES`` (``make fuzz`` sets it) runs it longer.
"""

from __future__ import annotations

import os
from collections import deque
from dataclasses import dataclass, field

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from proleg.firmware.render import thermal_budget
from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.protocol.definition import ClearWhat, ErrorCode, EventKind, FaultCode, ParamId, StopReason
from proleg.robot import Robot, load_robot
from proleg.sim.plant import Plant, plant_params_from_robot, true_rewards_from_robot
from proleg.sim.board import RESTART_CAUSES
from proleg.sim.closed_loop import SimulatedRobot

from proleg.paths import robots_dir

GAIT_USER = 0xFF


@dataclass(frozen=True)
class Envelope:
    """The envelope a robot file asks for, in µs and permyriad (docs/safety.md)."""

    tick_us: int
    max_duty_pm: int
    hold_max_pm: int
    max_on_us: int
    cooldown_us: int
    mean_pm: int
    window_us: int
    ceiling_c: float

    @classmethod
    def of(cls, robot: Robot, plant: Plant) -> "Envelope":
        s = robot.safety
        b = thermal_budget(robot.name, s, robot.control)
        acts = plant.params.actuators
        hottest = max(a.full_power_w / a.conductance_w_per_k for a in acts)
        return cls(
            tick_us=round(1_000_000 / robot.control.tick_hz),
            max_duty_pm=round(s.max_duty * 10000),
            hold_max_pm=b["hold_max_duty_pm"],
            max_on_us=s.max_on_ms * 1000,
            cooldown_us=s.min_cooldown_ms * 1000,
            mean_pm=b["mean_duty_pm"],
            window_us=b["duty_window_ms"] * 1000,
            ceiling_c=plant.params.ambient_c + s.max_duty * hottest + 5.0,
        )


@dataclass
class _Channel:
    on_us: int = 0
    debt_us: float = 0.0  # on-time not yet paid back by cool-down
    window: deque = field(default_factory=deque)
    window_sum: int = 0
    longest_on_us: int = 0


class EnvelopeMonitor:
    """Checks, after every tick, what the coils carried against the envelope (see module doc)."""

    def __init__(self, env: Envelope, channels: tuple[int, ...]):
        self.env = env
        self.ch = {c: _Channel() for c in channels}
        self.window_ticks = env.window_us // env.tick_us

    def after_tick(self, now_us: int, duties: dict[int, int], temps_c) -> None:
        env = self.env
        for c, duty in duties.items():
            s = self.ch[c]
            assert duty <= env.max_duty_pm, f"t={now_us} µs: channel {c} at {duty} ‱ > max_duty {env.max_duty_pm}"
            if duty > env.hold_max_pm:
                s.on_us += env.tick_us  # this duty holds until the next tick
                s.debt_us += env.tick_us
                s.longest_on_us = max(s.longest_on_us, s.on_us)
                assert s.on_us <= env.max_on_us + env.tick_us, (
                    f"t={now_us} µs: channel {c} on for {s.on_us} µs > max_on {env.max_on_us} + one tick"
                )
                assert s.debt_us <= env.max_on_us + env.tick_us, (
                    f"t={now_us} µs: channel {c} heats without its cool-down: {s.debt_us:.0f} µs of on-time "
                    f"not paid back > max_on {env.max_on_us} + one tick"
                )
            else:
                s.on_us = 0
                pay = env.tick_us * env.max_on_us / env.cooldown_us if env.cooldown_us else s.debt_us
                s.debt_us = max(0.0, s.debt_us - pay)
            s.window.append(duty)
            s.window_sum += duty
            if len(s.window) > self.window_ticks:
                s.window_sum -= s.window.popleft()
            limit = env.mean_pm * self.window_ticks + env.max_duty_pm
            assert s.window_sum <= limit, (
                f"t={now_us} µs: channel {c} mean duty {s.window_sum / self.window_ticks:.0f} ‱ over "
                f"{env.window_us // 1000} ms > {env.mean_pm} ‱"
            )
        for j, t in enumerate(temps_c):
            assert t <= env.ceiling_c, f"t={now_us} µs: coil {j} at {t:.1f} °C > ceiling {env.ceiling_c:.1f} °C"


class Rig:
    """The host-sim firmware and the plant, stepped one control tick at a time, monitored."""

    def __init__(self, robot: Robot, sim: SimulatedRobot | None = None):
        self.robot = robot
        self.sim = sim or SimulatedRobot(robot)
        self.decoder = FrameDecoder(len(robot.limbs), len(robot.actuators))
        self.reset()

    def reset(self, seed: int = 1) -> None:
        sim, robot = self.sim, self.robot
        sim.plant = Plant(plant_params_from_robot(robot), true_rewards_from_robot(robot), robot.levels, seed)
        sim.link_faults.drop = sim.link_faults.corrupt = 0.0
        for addr in sim.imu_addresses:
            sim.board.imu_fault(addr, "ok")
        sim.board.reset(seed)
        sim._push_truth()
        self.env = Envelope.of(robot, sim.plant)
        self.monitor = EnvelopeMonitor(self.env, sim.channels)
        self.dead: dict[int, int] = {}  # channel -> µs heated above the hold ceiling since it died or the last latch
        self.timeout_us = robot.safety.state_timeout_ms * 1000
        self.token = 0
        self.log: list[Message] = []
        self._acc = [0.0] * len(sim.channels)
        self._n = 0
        self._seen = 0
        self.last_frame = b""

    def restart(self, cause: str = "external") -> None:
        """The board resets without losing power (a Nano resets whenever its port is opened; a
        brown-out, the watchdog): the plant and the monitor go on, the firmware restarts. It
        forgets its latched faults, as a power cycle would, so the dead coils' count starts over;
        what it must not forget is what the coils spent (docs/safety.md, "A reset")."""
        self.sim.board.restart(cause)
        self.sim._push_truth()
        self.dead = dict.fromkeys(self.dead, 0)

    @property
    def now_us(self) -> int:
        return self.sim.board.time_us

    def kill(self, actuator: str) -> None:
        """A coil dies (the plant's ``dead-actuator``): from now it never lifts its limb."""
        self.sim.inject(f"dead-actuator:{actuator}")
        channel = next(a.channel for a in self.robot.actuators if a.name == actuator)
        self.dead.setdefault(channel, 0)

    def _dead_coils_after_tick(self, duties: dict[int, int]) -> None:
        """A latched fault restarts the count (the operator or the fallback acknowledges it)."""
        self.log += self.decoder.feed(self.sim.read())
        if any(m.spec.name == "EVENT" and m.kind == EventKind.GAIT_STOPPED and m.code == StopReason.FAULT
               for m in self.log[self._seen:]):
            self.dead = dict.fromkeys(self.dead, 0)
        self._seen = len(self.log)
        for c in self.dead:
            if duties[c] > self.env.hold_max_pm:
                self.dead[c] += self.env.tick_us
                assert self.dead[c] <= self.timeout_us + 2 * self.env.tick_us, (
                    f"t={self.now_us} µs: dead channel {c} heated {self.dead[c]} µs with no fault latched "
                    f"> state_timeout {self.timeout_us} µs")

    def ticks(self, n: int) -> None:
        sim, board = self.sim, self.sim.board
        tps = sim.ticks_per_step
        for _ in range(n):
            board.run_ticks(1)
            duties = {c: board.pwm_permyriad(c) for c in sim.channels}
            self.monitor.after_tick(board.time_us, duties, sim.plant.temperature_c)
            if self.dead:
                self._dead_coils_after_tick(duties)
            for k, c in enumerate(sim.channels):
                self._acc[k] += duties[c]
            self._n += 1
            if self._n == tps:
                sim.plant.step(sim.plant_dt_s, [a / tps / 10000.0 for a in self._acc])
                sim._push_truth()
                self._acc = [0.0] * len(sim.channels)
                self._n = 0
        self.log += self.decoder.feed(sim.read())

    def frame(self, name: str, **fields) -> bytes:
        self.token = self.token % 255 + 1
        return encode(Message.new(name, token=self.token, **fields))

    def send(self, name: str, **fields) -> int:
        """Queue one command (no tick): several sends before ``ticks`` land in one tick."""
        raw = self.frame(name, **fields)
        self.last_frame = raw
        self.sim.write(raw)
        return self.token

    def reply(self, token: int, ticks: int = 20) -> Message:
        self.ticks(ticks)
        for m in reversed(self.log):
            if m.spec.name in ("ACK", "NACK", "INFO", "STATS") and m.token == token:
                return m
        raise AssertionError(f"no reply to token {token}")

    def events(self, kind: int) -> list[Message]:
        return [m for m in self.log if m.spec.name == "EVENT" and m.kind == kind]


def _robot() -> Robot:
    return load_robot(robots_dir() / "paper-r1.toml")


@pytest.fixture(scope="module")
def rig() -> Rig:
    return Rig(_robot())


def _dead_left_on_a_two_state_user_gait(rig: Rig) -> None:
    rig.reset()
    rig.kill("sma-left")
    rig.ticks(50)
    assert rig.reply(rig.send("LOAD_GAIT", states=(2, 3))).spec.name == "ACK"  # 10 <-> 11
    assert rig.reply(rig.send("START", gait=GAIT_USER, direction=0)).spec.name == "ACK"


# ------------------------------------------------------------------ the three bypasses of issue 12


@pytest.mark.parametrize("cause", ["external", "brown-out", "watchdog"])
def test_a_board_reset_and_a_start_at_once_do_not_refresh_the_envelope(rig, cause):
    """A host that resets the board every 2 s (a Nano resets whenever its port is opened) and
    STARTs again at once, with a dead coil that is demanded all the time: each reset started
    every coil cold, so the coil was heated on after 2 s of its 3 s on-time with none of its
    cool-down, and the mean-duty window forgot its last 10 s. The monitor, which sees no reset,
    checks the on-time, its cool-down and the window on every tick across them."""
    _dead_left_on_a_two_state_user_gait(rig)
    for _ in range(8):
        rig.ticks(2000)
        rig.restart(cause)
        rig.ticks(50)
        assert rig.reply(rig.send("LOAD_GAIT", states=(2, 3))).spec.name == "ACK"
        rig.send("START", gait=GAIT_USER, direction=0)
        rig.ticks(1)
    rig.ticks(4000)
    boots = rig.events(EventKind.BOOT)
    assert len(boots) >= 8 and all(m.code == RESTART_CAUSES[cause] for m in boots[-8:])
    assert [m.detail for m in boots[-8:]] == [1] * 8  # each said it kept what the coils spent
    assert rig.monitor.ch[0].longest_on_us > rig.env.max_on_us // 2  # it was heated, within its limits


def test_stop_and_start_in_one_tick_every_2_99_s_cannot_keep_a_coil_on(rig):
    """Bypass 1: STOP + START in the same tick reset the on-time counter (62.8 s at 100 %)."""
    _dead_left_on_a_two_state_user_gait(rig)
    for _ in range(7):  # 21 s
        rig.ticks(2990 - 1)
        rig.send("STOP")
        rig.send("START", gait=GAIT_USER, direction=0)
        rig.ticks(1)
    assert rig.monitor.ch[0].longest_on_us <= rig.env.max_on_us + rig.env.tick_us
    faults = [m.code for m in rig.events(EventKind.FAULT)]
    assert FaultCode.STATE_TIMEOUT in faults or faults.count(FaultCode.SMA_ON_LIMIT) >= 3
    rig.ticks(5)
    assert rig.sim.board.pwm(0) == 0 and rig.sim.board.pwm(1) == 0  # latched: START refused


def test_a_one_tick_gap_every_2999_ticks_does_not_give_full_duty(rig):
    """Bypass 2: STOP, one tick, START every 2999 ticks gave 99.96 % duty for 63 s."""
    _dead_left_on_a_two_state_user_gait(rig)
    on_ticks = total = 0
    for _ in range(7):
        for _ in range(2998):
            rig.ticks(1)
            on_ticks += rig.sim.board.pwm_permyriad(0) > rig.env.hold_max_pm
            total += 1
        rig.send("STOP")
        rig.ticks(1)
        rig.send("START", gait=GAIT_USER, direction=0)
        rig.ticks(1)
        total += 2
    # max_on / (max_on + min_cooldown) = 3 / 3.8 at most, and the fault latches anyway
    assert on_ticks / total <= rig.env.max_on_us / (rig.env.max_on_us + rig.env.cooldown_us) + 0.01


def test_start_resent_while_a_gait_runs_is_refused_and_the_state_timeout_still_fires(rig):
    """Bypass 3: a re-sent START restarted the step timer: a dead limb heated forever."""
    rig.reset()
    rig.kill("sma-left")
    rig.ticks(50)
    assert rig.reply(rig.send("START", gait=0, direction=0)).spec.name == "ACK"
    started = rig.now_us
    timeout_us = rig.robot.safety.state_timeout_ms * 1000
    refused = 0
    while not rig.events(EventKind.FAULT) or rig.events(EventKind.FAULT)[-1].code == FaultCode.SMA_ON_LIMIT:
        m = rig.reply(rig.send("START", gait=0, direction=0), ticks=1000)
        if m.spec.name == "NACK":
            refused += 1
            assert m.error == ErrorCode.NOT_ALLOWED
        assert rig.now_us - started < 3 * timeout_us, "no latched fault: the dead limb is heated forever"
    fault = rig.events(EventKind.FAULT)[-1]
    assert fault.code in (FaultCode.STATE_TIMEOUT, FaultCode.SMA_ON_LIMIT)
    assert rig.now_us - started <= timeout_us + 1_100_000  # from the first demand (+ one reply period)
    assert refused >= 5
    rig.ticks(5)
    assert all(rig.sim.board.pwm(c) == 0 for c in rig.sim.channels)


@pytest.mark.parametrize("stopped_ticks, run_ms", [(0, 7000), (1, 7000), (500, 7000), (0, 3000), (0, 4000), (0, 4500)])
def test_restarting_gait_0_past_a_dead_coil_still_latches_a_fault(rig, stopped_ticks, run_ms):
    """A host that STOPs and STARTs R1's gait 0 (00 10 11 01 00) every few seconds with the
    right coil dead: each START began at the state the robot stood in, whose REACHED reset the
    step guard, and re-reaching 10 by the healthy left coil reset the on-limit count. The right
    coil was demanded for 140 s with 20 unlatched on-limit hits and no fault latched. Now its
    hits count until it heats on the way to a target reached, and the third latches (R1 then
    falls back without it). With STOP and START in one tick (0 ticks stopped) every 3 s, the
    tick after START charged the dead coil's pre-STOP heating as heating towards 10. Restarts
    every 4-4.5 s, faster than the coil reaches its on-time limit, paid its debt back between
    runs: no hit at all, and the coil above the hold ceiling 76 % of the time; now its own time
    heated towards targets never reached passes the state timeout across the restarts."""
    rig.reset()
    rig.kill("sma-right")
    rig.ticks(200)
    first = rig.now_us
    for _ in range(12):
        if rig.events(EventKind.GAIT_STOPPED) and any(m.code == StopReason.FAULT for m in rig.events(EventKind.GAIT_STOPPED)):
            break
        if stopped_ticks:
            rig.ticks(stopped_ticks)
        rig.send("START", gait=0, direction=0)
        for _ in range(run_ms // 1000):
            rig.ticks(1000)
            rig.send("PING")
        rig.ticks(run_ms % 1000)
        rig.send("STOP")
    latched = [m for m in rig.events(EventKind.GAIT_STOPPED) if m.code == StopReason.FAULT]
    assert latched, "no latched fault: the dead coil is demanded for ever"
    # the third on-limit hit of the right coil (one a run, or fewer when a run is shorter than
    # its on-time limit and the debt is paid back in between): 20.5 s at 3 s runs
    assert latched[0].time_ms - first // 1000 <= 10 * (run_ms + stopped_ticks)
    fault = [m for m in rig.events(EventKind.FAULT) if m.time_ms == latched[0].time_ms]
    assert fault and fault[0].code in (FaultCode.STATE_TIMEOUT, FaultCode.SMA_ON_LIMIT)
    assert [m.code for m in rig.events(EventKind.SUSPECT)][:1] == [1]  # sma-right, not the healthy coil


@pytest.mark.parametrize("run_ms", [3000, 4000, 7000])
def test_restarting_with_hold_ms_0_does_not_credit_a_dead_coil_with_the_start_state(rig, run_ms):
    """With SET_PARAM hold_ms 0 a START that finds the robot in its gait's state (00: rest)
    reaches it and moves on to 10 in the same tick, and the controller heats towards 10 in that
    tick. The step guard took that tick's heating as heating on the way to the state reached, so
    every START credited the dead coil with progress: its own time and its on-limit hits started
    again. Restarted every 3 s, R1's dead right coil was above the hold ceiling 77 s of 120 s with
    no latched fault (every 4-7 s: 14-20 s before the first latch). Now only heating in the
    intervals before a reach counts for it; the coil's time latches STATE_TIMEOUT as with the
    default hold_ms."""
    rig.reset()
    rig.kill("sma-right")  # Rig.kill: at most state_timeout_ms above the hold ceiling between latches
    rig.ticks(300)
    assert rig.reply(rig.send("SET_PARAM", param=int(ParamId.HOLD_MS), index=0, value=0)).spec.name == "ACK"
    heated = 0
    for _ in range(60_000 // run_ms):
        rig.send("START", gait=0, direction=0)
        for _ in range(run_ms // 250):
            for _ in range(250):
                rig.ticks(1)
                heated += rig.sim.board.pwm_permyriad(1) > rig.env.hold_max_pm
            rig.send("PING")
        rig.send("STOP")
        rig.ticks(1)
    assert any(m.code == StopReason.FAULT for m in rig.events(EventKind.GAIT_STOPPED)), "no latched fault"
    assert heated * rig.env.tick_us <= rig.timeout_us + 2 * rig.env.tick_us, heated


class _DeadRightCoil:
    """R1 on a fresh rig with its right coil dead (the plant's ``dead-actuator``), its time
    above the hold ceiling counted here until a fault latches (``heated_us``), not bounded per
    tick by Rig.kill: the attacks below are allowed a few debounce ticks a round."""

    def __init__(self, rig: Rig) -> None:
        self.rig = rig
        self.heated_us = 0
        rig.reset()
        rig.sim.inject("dead-actuator:sma-right")
        rig.ticks(300)

    def latched(self) -> bool:
        return any(m.code == StopReason.FAULT for m in self.rig.events(EventKind.GAIT_STOPPED))

    def run(self, n: int) -> None:
        rig = self.rig
        for _ in range(n):
            rig.ticks(1)
            if not self.latched() and rig.sim.board.pwm_permyriad(1) > rig.env.hold_max_pm:
                self.heated_us += rig.env.tick_us

    def ok(self, name: str, **fields) -> None:
        """Send a command, run two ticks, and require its ACK."""
        rig = self.rig
        token = rig.send(name, **fields)
        self.run(2)
        m = next(m for m in reversed(rig.log) if m.spec.name in ("ACK", "NACK") and m.token == token)
        assert m.spec.name == "ACK", (name, fields, m)


def test_a_target_reached_and_then_lost_is_demanded_again_and_its_time_counts(rig):
    """The sequencer reports REACHED once a step, and the guard took a reached step for held
    even after its target was lost: a host that STARTs the loaded gait 01 -> 00 with the right
    threshold moved below the resting limb (01 reached at once), moves it back (01 lost), lets
    the controller heat the dead right coil for 2.9 s, STOPs and repeats, kept that coil above
    the hold ceiling 73 % of 600 s with no fault. Now the lost target's time counts and the
    fault latches once the coil has been heated the state timeout. What is not counted: the
    hold's own re-heat in the ticks before the lost level is debounced (docs/safety.md), at
    most debounce_ticks + 1 a round."""
    watch = _DeadRightCoil(rig)
    run, ok, latched = watch.run, watch.ok, watch.latched
    rounds = 0
    ok("LOAD_GAIT", states=(1, 0))
    ok("SET_PARAM", param=int(ParamId.HOLD_MS), index=0, value=600000)
    first = rig.now_us
    while rig.now_us - first < 40_000_000 and not latched():
        rounds += 1
        ok("STOP")
        ok("SET_PARAM", param=int(ParamId.PSI_STAR_CDEG), index=1, value=-700)  # the resting right limb reads up
        run(60)
        ok("START", gait=GAIT_USER, direction=0)
        run(60)
        ok("SET_PARAM", param=int(ParamId.PSI_STAR_CDEG), index=1, value=2000)  # and down again: 01 lost
        for _ in range(11):
            run(250)
            rig.send("PING")
        run(150)
        rig.send("STOP")
        run(800)
    faults = rig.events(EventKind.FAULT)
    assert latched() and faults[0].code == FaultCode.STATE_TIMEOUT, "no latched fault: the dead coil is heated for ever"
    assert rounds <= 4
    debounce = rig.robot.control.debounce_ticks
    assert watch.heated_us <= rig.timeout_us + rounds * (debounce + 1) * rig.env.tick_us, (watch.heated_us, rounds)


def test_a_threshold_moved_each_step_does_not_make_a_dead_coil_progress(rig):
    """One START, then a host alternates the right threshold: 6 s at 20° (the dead right coil
    heated towards 01), 1 s at -7° (the resting limb reads up: 01 "reached", and the coil that
    heated was credited with it). The dead coil was above the hold ceiling 75.6 s of 126 s with
    no latched fault. Now any SET_PARAM starts the progress record afresh (as START does):
    a target read through a moved threshold is no progress of what heated before it."""
    watch = _DeadRightCoil(rig)
    run, ok, latched = watch.run, watch.ok, watch.latched
    ok("LOAD_GAIT", states=(1, 0))
    ok("SET_PARAM", param=int(ParamId.HOLD_MS), index=0, value=100)
    ok("START", gait=GAIT_USER, direction=0)
    first = rig.now_us
    while rig.now_us - first < 40_000_000 and not latched():
        for value, ms in ((2000, 6000), (-700, 1000)):
            ok("SET_PARAM", param=int(ParamId.PSI_STAR_CDEG), index=1, value=value)
            for _ in range(ms // 250):
                run(250)
                rig.send("PING")
    assert latched(), "no latched fault: the dead coil is heated for ever"
    assert rig.events(EventKind.FAULT)[-1].code == FaultCode.STATE_TIMEOUT
    assert watch.heated_us <= rig.timeout_us + 8 * rig.env.tick_us, watch.heated_us


def test_a_hold_that_stops_short_is_a_hit_at_the_mean_duty_limit_and_latches(rig):
    """A held limb that reads at its level but cannot reach its hold edge: the bang-bang hold
    heats its coil at the drive duty for good. After two on-limit hits the mean-duty window
    refused the coil before its on-time reached max_on again, so there never was a third hit:
    one SET_PARAM (R1's right threshold at -3°: the dead right limb at rest reads 01, below its
    hold edge) and a long hold kept that coil above the hold ceiling 74 % of 300 s with no
    fault. Now, while a reached target is held, the window refusing a coil above the hold
    ceiling is a hit (sma_tick's ``holding``), and the third hit latches SMA_ON_LIMIT."""
    watch = _DeadRightCoil(rig)
    run, ok, latched = watch.run, watch.ok, watch.latched
    ok("SET_PARAM", param=int(ParamId.PSI_STAR_CDEG), index=1, value=-300)
    ok("SET_PARAM", param=int(ParamId.HOLD_MS), index=0, value=600000)
    ok("LOAD_GAIT", states=(1, 0))
    ok("START", gait=GAIT_USER, direction=0)
    first = rig.now_us
    while rig.now_us - first < 60_000_000 and not latched():
        run(250)
        rig.send("PING")
    assert latched(), f"no latched fault: the coil was heated {watch.heated_us / 1e6:.1f} s of 60 s"
    assert rig.events(EventKind.FAULT)[-1].code == FaultCode.SMA_ON_LIMIT
    assert watch.heated_us <= rig.robot.safety.on_limit_latch * rig.env.max_on_us + rig.env.tick_us, watch.heated_us


@pytest.mark.parametrize("run_ms", [3000, 4500])
def test_restarting_gait_0_after_the_fallback_does_not_bring_the_dead_coil_back(rig, run_ms):
    """The fallback cleared the fault itself and a START of a built-in gait went back to the
    build's map: restarted every 3-4.5 s for 120 s, R1's dead right coil was heated 58-69 s,
    each fault ending in another fallback rather than a latch. Now the coil given up stays
    given up: gait 0 is refused (NOT_ALLOWED, detail 3) and the coil is heated only until the
    first fault, the state timeout (Rig.kill's bound, checked every tick)."""
    rig.reset()
    rig.kill("sma-right")
    rig.ticks(200)
    heated = 0
    refused = []
    for _ in range(60_000 // run_ms):
        token = rig.send("START", gait=0, direction=0)
        for _ in range(run_ms // 250):
            for _ in range(250):
                rig.ticks(1)
                heated += rig.sim.board.pwm_permyriad(1) > rig.env.hold_max_pm
            rig.send("PING")
        m = next(m for m in reversed(rig.log) if m.spec.name in ("ACK", "NACK") and m.token == token)
        if m.spec.name == "NACK":
            refused.append((m.error, m.detail))
        rig.send("STOP")
        rig.ticks(1)
    assert rig.events(EventKind.FALLBACK), "R1 falls back without the right coil"
    assert refused and set(refused) == {(ErrorCode.NOT_ALLOWED, 3)}, refused
    assert heated * rig.env.tick_us <= rig.timeout_us + 2 * rig.env.tick_us


def test_holding_a_state_at_the_hold_duty_is_not_ended_by_the_envelope(rig):
    """The one-coil hold of C_L2 (10 -> 11 -> 10) must live inside the budget: a gait that
    merely holds the left limb up for far longer than max_on runs on without an on-limit."""
    rig.reset()
    rig.ticks(50)
    assert rig.reply(rig.send("LOAD_GAIT", states=(2, 3))).spec.name == "ACK"
    assert rig.reply(rig.send("START", gait=GAIT_USER, direction=0)).spec.name == "ACK"
    for _ in range(20):  # a host that stays: one PING a second keeps the link watchdog fed
        rig.ticks(1000)
        assert rig.reply(rig.send("PING")).spec.name == "ACK"
    assert not [m for m in rig.events(EventKind.FAULT)], [(m.code, m.detail) for m in rig.events(EventKind.FAULT)]
    assert len(rig.events(EventKind.STATE_REACHED)) >= 4


def test_the_link_watchdog_stops_a_gait_the_host_went_quiet_on(tmp_path):
    text = (robots_dir() / "paper-r1.toml").read_text()
    path = tmp_path / "paper-r1-watchdog.toml"
    path.write_text(text.replace("[safety]\n", "[safety]\nlink_watchdog_ms = 500\n"))
    rig = Rig(load_robot(path))
    rig.ticks(50)
    assert rig.reply(rig.send("START", gait=0, direction=0)).spec.name == "ACK"
    for _ in range(6):  # a PING every 400 ms keeps it alive
        last_frame_us = rig.now_us
        rig.reply(rig.send("PING"), ticks=400)
    assert not rig.events(EventKind.FAULT)
    rig.ticks(600)
    fault = rig.events(EventKind.FAULT)
    assert fault and fault[-1].code == FaultCode.LINK_WATCHDOG
    assert 500_000 <= fault[-1].time_ms * 1000 - last_frame_us <= 503_000
    assert all(rig.sim.board.pwm(c) == 0 for c in rig.sim.channels)


# ------------------------------------------------------------------ the attacker

_PARAMS = [int(p) for p in ParamId]
COMMAND = st.one_of(
    # +x, -x, a byte that is neither, and the loaded gait's "unstated" (on any gait)
    st.builds(lambda g, d: ("START", {"gait": g, "direction": d}), st.sampled_from([0, 1, GAIT_USER]),
              st.sampled_from([0, 1, 2, 0xFF])),
    st.just(("STOP", {})),
    st.just(("ESTOP", {})),
    st.builds(lambda w: ("CLEAR", {"what": w}), st.sampled_from([int(ClearWhat.ESTOP), int(ClearWhat.FAULTS), 7])),
    st.builds(lambda s: ("LOAD_GAIT", {"states": tuple(s)}), st.lists(st.integers(0, 3), min_size=2, max_size=4)),
    st.builds(
        lambda p, v: ("SET_PARAM", {"param": p, "index": 0, "value": v}),
        st.sampled_from(_PARAMS),
        st.sampled_from([0, 1, 50, 800, 2500, 3000, 6000, 8000, 100000, -1]),
    ),
    # the run-time limb→actuator map (issue 15): any map, also out of range, never widens the envelope
    st.builds(lambda a: ("SET_ACTUATOR_MAP", {"actuators": tuple(a)}), st.lists(st.integers(0, 2), max_size=2)),
)

EXAMPLES = int(os.environ.get("PROLEG_ATTACK_EXAMPLES", "10"))
STEPS = int(os.environ.get("PROLEG_ATTACK_STEPS", "20"))


class Attacker(RuleBasedStateMachine):
    rig: Rig  # set by the test

    def __init__(self):
        super().__init__()
        self.rig.reset()
        self.rig.ticks(30)
        self.rig.send("START", gait=0, direction=0)
        self.rig.ticks(1)

    @rule(burst=st.lists(COMMAND, min_size=1, max_size=4))
    def commands_in_one_tick(self, burst):
        for name, fields in burst:
            try:
                self.rig.send(name, **fields)
            except Exception:  # noqa: BLE001 - not encodable: the host codec refuses it
                continue
        self.rig.ticks(1)

    @rule(after=st.integers(0, 15), also=st.lists(COMMAND, max_size=2))
    def reset_then_start_before_the_imus_are_read(self, after, also):
        """The board restarts (a Nano's port opened); START comes before its first readings."""
        self.rig.reset()
        self.rig.ticks(after)
        token = self.rig.send("START", gait=0, direction=0)
        for name, fields in also:
            try:
                self.rig.send(name, **fields)
            except Exception:  # noqa: BLE001 - not encodable: the host codec refuses it
                continue
        reply = self.rig.reply(token, 3)
        assert reply.spec.name == "NACK" and reply.error == ErrorCode.NOT_ALLOWED and reply.detail == 2, reply

    @rule(cause=st.sampled_from(["external", "brown-out", "watchdog"]), after=st.sampled_from([30, 50, 300]),
          gait=st.sampled_from([0, 1]))
    def board_resets_and_the_host_starts_again(self, cause, after, gait):
        """The board resets without losing power; the plant, and the monitor, go on."""
        self.rig.restart(cause)
        self.rig.ticks(after)
        self.rig.send("START", gait=gait, direction=0)
        self.rig.ticks(1)

    @rule(n=st.sampled_from([1, 2, 50, 799, 1000, 2990, 2999, 4000]))
    def wait(self, n):
        self.rig.ticks(n)

    @rule(gait=st.sampled_from([0, 1, GAIT_USER]), period=st.sampled_from([500, 1500, 3000, 4000, 4500]),
          times=st.integers(1, 4))
    def restart_every(self, gait, period, times):
        """A host that keeps restarting a gait, faster or slower than a coil's on-time limit."""
        for _ in range(times):
            self.rig.send("STOP")
            self.rig.send("START", gait=gait, direction=0)
            self.rig.ticks(period)

    @rule(act=st.sampled_from(["sma-left", "sma-right"]))
    def dead_coil(self, act):
        self.rig.kill(act)

    @rule(limb=st.sampled_from(["left", "right"]), mode=st.sampled_from(["imu-stuck", "imu-silent"]))
    def imu_fault(self, limb, mode):
        self.rig.sim.inject(f"{mode}:{limb}")

    @precondition(lambda self: bool(self.rig.last_frame))
    @rule(n=st.integers(1, 3))
    def replay_last_frame(self, n):
        for _ in range(n):
            self.rig.sim.write(self.rig.last_frame)
        self.rig.ticks(1)

    @rule(name=st.sampled_from(["STOP", "ESTOP", "START"]), cut=st.integers(1, 6))
    def dropped_frame(self, name, cut):
        raw = self.rig.frame(name, gait=0, direction=0) if name == "START" else self.rig.frame(name)
        self.rig.sim.write(raw[: max(0, len(raw) - cut)])  # the rest of the frame is lost
        self.rig.ticks(1)

    @invariant()
    def ticks_between_rules(self):
        self.rig.ticks(3)  # the monitor asserts on every tick


def test_an_attacker_cannot_get_around_the_envelope(rig):
    Attacker.rig = rig
    Attacker.TestCase.settings = settings(
        max_examples=EXAMPLES, stateful_step_count=STEPS, deadline=None, suppress_health_check=list(HealthCheck)
    )
    Attacker.TestCase().runTest()


# ------------------------------------------------------------------ the attacker on the MCUs

EMU_EXAMPLES = int(os.environ.get("PROLEG_ATTACK_EMU_EXAMPLES", "3"))
EMU_STEPS = int(os.environ.get("PROLEG_ATTACK_EMU_STEPS", "8"))


class EmuAttacker(Attacker):
    """The attacker on the emulated MCUs, whose ticks cost far more: restarts in short runs."""

    @rule(gait=st.sampled_from([0, 1, GAIT_USER]), period=st.just(200), times=st.integers(1, 2))
    def restart_every(self, gait, period, times):
        Attacker.restart_every(self, gait, period, times)

    @rule(cause=st.just("external"), after=st.sampled_from([50, 300]), gait=st.sampled_from([0, 1]))
    def board_resets_and_the_host_starts_again(self, cause, after, gait):
        """The emulated MCUs reset by their reset pin (RAM kept, as the chips')."""
        Attacker.board_resets_and_the_host_starts_again(self, cause, after, gait)

    def reset_then_start_before_the_imus_are_read(self, after, also):  # not a rule here
        """An emulated MCU's reset runs its start-up code before the UART listens, so a frame
        sent in its first ticks is lost, not refused (the rule runs on host-sim;
        tests/test_emu_*.py start their gaits after a known state)."""


@pytest.mark.parametrize("cause", ["external", "brown-out"])
def test_an_estop_stays_latched_across_a_reset_that_is_not_a_power_on(rig, cause):
    """An operator's E-stop was released by any reset: a reconnect (a Nano resets when its port
    opens) or a brown-out, and START heated again with no CLEAR. Now only CLEAR releases it;
    a power-on starts without one."""
    rig.reset()
    rig.ticks(50)
    assert rig.reply(rig.send("ESTOP")).spec.name == "ACK"
    rig.restart(cause)
    rig.ticks(50)
    m = rig.reply(rig.send("START", gait=0, direction=0))
    assert m.spec.name == "NACK" and m.error == ErrorCode.ESTOP_LATCHED, m
    assert all(rig.sim.board.pwm(c) == 0 for c in rig.sim.channels)
    assert rig.reply(rig.send("CLEAR", what=int(ClearWhat.ESTOP))).spec.name == "ACK"
    assert rig.reply(rig.send("START", gait=0, direction=0)).spec.name == "ACK"
    rig.reset()  # a power-on: no E-stop
    rig.ticks(50)
    assert rig.reply(rig.send("START", gait=0, direction=0)).spec.name == "ACK"


@pytest.mark.parametrize("board", ["avr-emu", "arm-emu"])
def test_a_reset_pin_and_a_start_at_once_do_not_refresh_the_envelope_on_the_emulated_mcus(board):
    """The exact images keep what the coils spent across their reset pin: their RAM outlives the
    reset (.noinit), and the build checks that it set it (sma.c)."""
    from proleg.sim.simulated_boards import simulated_board, simulated_robot

    lacking = simulated_board(board).missing()
    if lacking:
        pytest.skip(lacking)
    robot = _robot()
    rig = Rig(robot, simulated_robot(board, robot))
    _dead_left_on_a_two_state_user_gait(rig)
    for _ in range(2):
        rig.ticks(2000)
        rig.restart("external")
        rig.ticks(300)
        assert rig.reply(rig.send("LOAD_GAIT", states=(2, 3))).spec.name == "ACK"
        rig.send("START", gait=GAIT_USER, direction=0)
        rig.ticks(1)
    rig.ticks(2500)
    boots = rig.events(EventKind.BOOT)[-2:]
    assert [(m.code, m.detail) for m in boots] == [(RESTART_CAUSES["external"], 1)] * 2
    assert rig.monitor.ch[0].longest_on_us > rig.env.max_on_us // 2


@pytest.mark.parametrize("board", ["avr-emu", "arm-emu"])
def test_an_attacker_cannot_get_around_the_envelope_on_the_emulated_mcus(board):
    """The same attacker and monitor against the exact MCU images: the envelope's timers run
    on each chip's own clock there (Timer0 on the ATmega328P, SysTick on the STM32F103)."""
    from proleg.sim.simulated_boards import simulated_board, simulated_robot

    lacking = simulated_board(board).missing()
    if lacking:
        pytest.skip(lacking)
    robot = _robot()
    EmuAttacker.rig = Rig(robot, simulated_robot(board, robot))
    EmuAttacker.TestCase.settings = settings(
        max_examples=EMU_EXAMPLES, stateful_step_count=EMU_STEPS, deadline=None,
        suppress_health_check=list(HealthCheck),
    )
    EmuAttacker.TestCase().runTest()
