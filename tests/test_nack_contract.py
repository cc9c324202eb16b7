"""Every refusal the firmware sends is the one the protocol documents (definition.py's command
texts, enums.ErrorCode, link/replies.py), whichever refusals apply at once, and no interleaving
of the host's commands gets a coil around the safety envelope (docs/safety.md).

The whole firmware core on the simulated board (``test_firmware_on_sim_board.Rig``, r1-fast:
max_on 50 ms, min_cooldown 20 ms, max_duty 0.8, hold ceiling 0.3, state timeout 200 ms),
stepped one control tick at a time and talked to through the one client.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule
import test_firmware_on_sim_board as on_sim_board
from test_firmware_on_sim_board import CC, Rig

from proleg.link import CommandRefused
from proleg.protocol import definition as d

pytestmark = pytest.mark.skipif(CC is None, reason="no host C compiler")
rendered, sim_so = on_sim_board.rendered, on_sim_board.sim_so  # its fixtures: the firmware on the sim board

E = d.ErrorCode
MAX_DUTY_PM, HOLD_MAX_PM = 8000, 3000  # r1-fast's [safety] max_duty; the default hold ceiling
MAX_ON_MS, MIN_COOLDOWN_MS = 50, 20  # r1-fast's [safety]


def _rig(sim_so, config="r1-fast", limbs=2, channels=2) -> Rig:
    b = Rig(sim_so(config), limbs, channels)
    for limb in range(limbs):
        b.set_psi(limb, 0.0)
    b.reset()
    assert b.client.wait_known_state()
    b.run(0)
    return b


@pytest.fixture
def board(sim_so):
    return _rig(sim_so)


def _refusal(board: Rig, name: str, **fields) -> tuple[E, int] | tuple[E, int, str]:
    """The NACK's (error, detail); with a third item, the refusal the host has no words for
    (replies.py explains every refusal the firmware sends)."""
    r = board.refused(name, **fields)
    return (r.error, r.detail) if r.why else (r.error, r.detail, "no words for it")


def _events(board: Rig, kind) -> list:
    return [m for m in board.log if m.spec.name == "EVENT" and m.kind == kind]


# ---------------------------------------------------------------- LOAD_GAIT


@pytest.mark.parametrize(
    "states, step",
    [
        ((2, 2), 0),  # 10 → 10: a self-transition, closed or not
        ((2,), 0),  # one state: it follows itself
        ((2, 2, 2), 0),
        ((0, 2, 2, 1), 1),
        ((0, 2, 3, 3), 2),
    ],
)
def test_a_step_that_is_not_an_allowed_transition_is_forbidden_transition_naming_the_step(board, states, step):
    """definition.py: LOAD_GAIT "NACK FORBIDDEN_TRANSITION, detail = step index"; replies.py
    names "a state that follows itself". (2, 2) and (2,) used to be OUT_OF_RANGE (detail 2, 1):
    seq_load closed (2, 2) to the single state 2 and refused it as too short."""
    assert _refusal(board, "LOAD_GAIT", states=states) == (E.FORBIDDEN_TRANSITION, step)
    assert not d.Flag.USER_GAIT & board.run(25)[-1].flags  # nothing stored


def test_load_gait_refusals_other_than_a_transition(board):
    assert _refusal(board, "LOAD_GAIT", states=(0, 4)) == (E.OUT_OF_RANGE, 1)  # no state 4: its step
    assert _refusal(board, "LOAD_GAIT", states=(0, 2, 0x102)) == (E.OUT_OF_RANGE, 2)  # not narrowed to 2
    assert _refusal(board, "LOAD_GAIT", states=()) == (E.OUT_OF_RANGE, 0)  # no steps
    board.client.start(0, "+x")
    assert _refusal(board, "LOAD_GAIT", states=(0, 2)) == (E.NOT_ALLOWED, 0)
    assert _refusal(board, "LOAD_GAIT", states=(2, 2)) == (E.NOT_ALLOWED, 0)  # the mode first


# ---------------------------------------------------------------- START


def test_start_refusals_and_which_wins(board):
    assert _refusal(board, "START", gait=5, direction=0) == (E.NO_GAIT, 5)
    assert _refusal(board, "START", gait=0, direction=1) == (E.NO_GAIT, 0)  # r1-fast has no -x gait
    assert _refusal(board, "START", gait=d.GAIT_USER, direction=0) == (E.NO_GAIT, d.GAIT_USER)
    assert _refusal(board, "START", gait=5, direction=7) == (E.OUT_OF_RANGE, 2)
    board.client.start(0, "+x")
    assert _refusal(board, "START", gait=0, direction=0) == (E.NOT_ALLOWED, 1)
    assert _refusal(board, "START", gait=5, direction=7) == (E.NOT_ALLOWED, 1)  # the mode first
    board.client.estop()
    assert _refusal(board, "START", gait=0, direction=0) == (E.ESTOP_LATCHED, 0)
    board.client.clear(d.ClearWhat.ESTOP)
    board.client.start(0, "+x")


def test_start_of_no_such_gait_while_the_fallback_has_given_up_a_coil_is_no_gait(sim_so):
    """The fallback gave up the right coil (its limb never rose): START of a built-in gait is
    NOT_ALLOWED detail 3 (definition.py), but a gait the board does not have is NO_GAIT, as at
    any other time; it used to be NOT_ALLOWED 3, which sent the operator to take a coil back
    only to be told then that there is no such gait."""
    board = _rig(sim_so)
    board.client.start(0, "+x")  # 00 → 10 → 11 ...
    board.run(20)
    board.set_psi(0, 25.0)  # the left limb rises; the right never does
    for _ in range(100):
        board.run(10)
        if _events(board, d.EventKind.FALLBACK):
            break
    assert [m.code for m in _events(board, d.EventKind.FALLBACK)] == [1]
    board.client.stop()
    assert board.client.request("GET_ACTUATOR_MAP").lost == 1
    before = [m for m in board.run(40) if m.spec.name == "TELEMETRY"][-1]
    assert _refusal(board, "START", gait=0, direction=0) == (E.NOT_ALLOWED, 3)
    after = [m for m in board.run(40) if m.spec.name == "TELEMETRY"][-1]  # refused before the sequencer:
    assert (after.gait, after.step, after.target) == (before.gait, before.step, before.target)  # as it stopped
    assert _refusal(board, "START", gait=77, direction=0) == (E.NO_GAIT, 77)
    assert _refusal(board, "START", gait=1, direction=1) == (E.NO_GAIT, 1)
    assert _refusal(board, "START", gait=77, direction=9) == (E.OUT_OF_RANGE, 2)
    tel = board.run(25)[-1]
    assert not d.Flag.RUNNING & tel.flags and not any(tel.duty)  # a refused START runs nothing
    board.client.start("user", "+x")  # the fallback gait still runs
    board.client.stop()


# ---------------------------------------------------------------- the other commands


def test_set_param_refusals_name_the_parameter(board):
    p = d.ParamId
    cases = [
        (p.DRIVE_DUTY, 8001, E.SAFETY_LIMIT),
        (p.HOLD_DUTY, 8001, E.SAFETY_LIMIT),
        (p.MAX_ON_MS, 51, E.SAFETY_LIMIT),
        (p.MIN_COOLDOWN_MS, 19, E.SAFETY_LIMIT),
        (p.STATE_TIMEOUT_MS, 201, E.SAFETY_LIMIT),
        (p.LINK_WATCHDOG_MS, 0, E.SAFETY_LIMIT),  # r1-fast has a 2 s watchdog: it stays on
        (p.LINK_WATCHDOG_MS, 2001, E.SAFETY_LIMIT),
        (p.MAX_ON_MS, 0, E.OUT_OF_RANGE),
        (p.DEBOUNCE_TICKS, 0, E.OUT_OF_RANGE),
        (p.HYSTERESIS_CDEG, 2001, E.OUT_OF_RANGE),
    ]
    for param, value, error in cases:
        assert _refusal(board, "SET_PARAM", param=int(param), index=0, value=value) == (error, int(param)), param
    for param in (0, 11, 255):
        assert board.refused("SET_PARAM", param=param, index=0, value=1).error == E.OUT_OF_RANGE


def test_actuator_map_level_and_telemetry_refusals(board):
    assert _refusal(board, "SET_ACTUATOR_MAP", actuators=(0, 2)) == (E.OUT_OF_RANGE, 1)
    assert _refusal(board, "SET_ACTUATOR_MAP", actuators=(0,)) == (E.OUT_OF_RANGE, 0xFFFF)
    # more entries than limbs: refused by the receiver (the array's count), which the protocol text
    # did not say and the host had no words for ("TOO_LONG (detail 0)")
    assert _refusal(board, "SET_ACTUATOR_MAP", actuators=(0, 0, 0)) == (E.TOO_LONG, 0)
    assert "TOO_LONG" in d.BY_NAME["SET_ACTUATOR_MAP"].doc
    assert _refusal(board, "CALIBRATE_LEVEL", ground=2) == (E.OUT_OF_RANGE, 1)
    assert _refusal(board, "SET_TELEMETRY_RATE", hz=181) == (E.OUT_OF_RANGE, 0)
    board.client.start(0, "+x")
    assert _refusal(board, "SET_ACTUATOR_MAP", actuators=()) == (E.NOT_ALLOWED, 0)
    assert _refusal(board, "CALIBRATE_LEVEL", ground=0) == (E.NOT_ALLOWED, 1)
    assert _refusal(board, "CLEAR_LEVEL") == (E.NOT_ALLOWED, 0)


def test_the_protocol_text_names_every_refusal_detail_the_host_explains():
    """definition.py is the protocol's one description: each command whose NOT_ALLOWED details
    replies.py explains names NOT_ALLOWED, and CALIBRATE_LEVEL each of its details (LOAD_GAIT named
    none; CALIBRATE_LEVEL left out 6, not at rest since a gait)."""
    from proleg.link.replies import _NOT_ALLOWED

    for command, details in _NOT_ALLOWED.items():
        doc = d.BY_NAME[command].doc
        assert "NOT_ALLOWED" in doc, command
        if command == "CALIBRATE_LEVEL":
            assert all(f"({k})" in doc or f"(detail {k})" in doc for k in details), doc


# ---------------------------------------------------------------- interleavings vs the envelope


class Interleavings(RuleBasedStateMachine):
    """A host sending any mix of the mode commands and envelope parameters while the limbs
    move (or do not). Every control tick (those that pass while a command waits for its reply
    included), each coil's duty is checked against the build's envelope, with an on-time debt
    oracle on the build's max_on / min_cooldown (SET_PARAM can only narrow them)."""

    so = None

    @initialize()
    def boot(self):
        self.b = Rig(self.so, 2, 2)
        self.debt_ms = [0.0, 0.0]
        self.estopped = False  # an ESTOP was acknowledged and no CLEAR(ESTOP) sent since
        self.may_heat = False  # a START was sent since the last acknowledged STOP / ESTOP
        run_ticks = self.b.board.run_ticks

        def tick_by_tick(n):
            for _ in range(n):
                run_ticks(1)
                self.observe()

        self.b.board.run_ticks = tick_by_tick
        self.b.set_psi(0, 0.0)
        self.b.set_psi(1, 0.0)
        self.b.reset()
        assert self.b.client.wait_known_state()

    def observe(self):
        for ch in (0, 1):
            duty = self.b.duty(ch)
            assert duty <= MAX_DUTY_PM
            if self.estopped or not self.may_heat:
                assert duty == 0, (ch, duty, self.estopped)
            if duty > HOLD_MAX_PM:
                self.debt_ms[ch] += 1.0
            else:
                self.debt_ms[ch] = max(0.0, self.debt_ms[ch] - MAX_ON_MS / MIN_COOLDOWN_MS)
            assert self.debt_ms[ch] <= MAX_ON_MS + 1.0, (ch, self.debt_ms)

    def send(self, name, **fields):
        try:
            self.b.client.request(name, **fields)
        except CommandRefused:
            return False
        return True

    @rule(gait=st.sampled_from([0, 0, 1, 2, d.GAIT_USER]), direction=st.sampled_from([0, 0, 0, 1, d.DIR_UNSTATED]),
          then=st.integers(0, 200))
    def start(self, gait, direction, then):
        heat = self.may_heat
        self.may_heat = True
        if self.send("START", gait=gait, direction=direction):
            assert not self.estopped
        else:
            self.may_heat = heat
        self.b.run(then)

    @rule()
    def stop(self):
        assert self.send("STOP")
        self.may_heat = False

    @rule()
    def estop(self):
        assert self.send("ESTOP")
        self.estopped, self.may_heat = True, False

    @rule(what=st.integers(0, 7))
    def clear(self, what):
        if what & d.ClearWhat.ESTOP:
            self.estopped = False
        assert self.send("CLEAR", what=what)

    @rule(states=st.lists(st.integers(0, 3), min_size=0, max_size=5))
    def load_gait(self, states):
        self.send("LOAD_GAIT", states=tuple(states))

    @rule(actuators=st.sampled_from([(), (0, 0), (1, 1), (1, 0), (0, 1)]))
    def actuator_map(self, actuators):
        self.send("SET_ACTUATOR_MAP", actuators=actuators)

    @rule(ground=st.integers(0, 1))
    def calibrate(self, ground):
        self.send("CALIBRATE_LEVEL", ground=ground)

    @rule(param=st.sampled_from(list(d.ParamId)), value=st.integers(-100, 9000), index=st.integers(0, 2))
    def set_param(self, param, value, index):
        self.send("SET_PARAM", param=int(param), index=index, value=value)

    @rule(limb=st.integers(0, 1), deg=st.sampled_from([0.0, 18.0, 21.0, 25.0]))
    def move(self, limb, deg):
        self.b.set_psi(limb, deg)

    @rule(ticks=st.integers(1, 150))
    def run(self, ticks):
        self.b.run(ticks)

    @invariant()
    def nothing_heats_while_estopped(self):
        if getattr(self, "estopped", False):
            assert not any(self.b.duty(ch) for ch in (0, 1))


def test_no_interleaving_of_commands_gets_around_the_envelope(sim_so):
    Interleavings.so = sim_so("r1-fast")
    run = Interleavings.TestCase
    run.settings = settings(max_examples=100, stateful_step_count=50, deadline=None,
                            suppress_health_check=list(HealthCheck))
    run().runTest()

