"""Limb loss on the host: which actuator a fault points at, the best gait of what is left,
and ``Replanner``, which carries a running gait on after the loss (``proleg run``).

The firmware reports a coil that cannot do its job as FAULT SMA_ON_LIMIT (detail: the
actuator's index, as EVENT SUSPECT's code; not its PWM channel) or STATE_TIMEOUT (detail: the limb off its target; 0xFF: none is, one would not settle), followed by EVENT SUSPECT (code:
the actuator it suspects, detail: the failed transition from × n_states + to). What the robot
can still do without that actuator, and with which limb→actuator map, is
``proleg.limbloss.fallback`` (the same model the firmware's build-time fallbacks come from:
the limbs of the lost coil either stay down, or the nearest other coil raises them too).

``Replanner`` watches the message stream of a run. When the gait stops on such a fault and
the firmware did not fall back by itself (EVENT FALLBACK: the build's fallback, [control]
fallback), it marks the transitions that need the lost actuator forbidden, recomputes the
best gait with the gait engine, and sends SET_ACTUATOR_MAP, LOAD_GAIT, CLEAR(FAULTS) and
START of the user gait; each step is told by name through ``say``.

Threads: ``on_message`` may run on a ``Notifier``'s thread while ``poll`` runs on another
(the console's replan worker, ``proleg.console.replan``): the state they share is guarded
by a lock, and ``poll`` sends its commands outside it. ``due()`` says, without blocking,
whether ``poll`` would act now. ``direction=None`` replans for the direction the stopped
gait ran in (from TELEMETRY), as the console needs; ``proleg run`` gives its own.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from ..errors import LinkError
from ..limbloss import Fallback, best_gait, compiled_map, dead_table, fallback
from ..link.client import Received, RobotClient
from ..link.direction import direction_code, direction_text
from ..link.listeners import Listener
from ..protocol.definition import GAIT_USER, ClearWhat, EventKind, FaultCode, Flag, StopReason
from ..robot import Robot
from ..states import limb_levels
from ..transitions import TransitionTable

#: seconds of link time the replanner waits after the gait stopped, for a FALLBACK event
SETTLE_S = 0.05


@dataclass(frozen=True)
class Replan:
    actuator: str
    table: TransitionTable            # what the robot can still do
    states: tuple[int, ...] | None    # best closed walk (first state repeated at the end), None: none
    rate: float                       # its reward per transition (0 when none)
    reason: str                       # one line for the user
    actuator_map: tuple[int, ...] = ()  # actuator index per limb to run with


def suspect(robot: Robot, code: int, detail: int) -> str | None:
    """The actuator a fault points at: SMA_ON_LIMIT names the actuator (its index in the robot
    file, as core/drive.c sends it), STATE_TIMEOUT the limb. Read as a channel, a hit on a robot
    whose coils are not wired to channels 0, 1, ... in file order named another coil, or none."""
    if code == FaultCode.SMA_ON_LIMIT:
        return robot.actuators[detail].name if 0 <= detail < len(robot.actuators) else None
    if code == FaultCode.STATE_TIMEOUT and 0 <= detail < len(robot.limbs):
        return robot.limbs[detail].actuator
    return None


def describe_transition(robot: Robot, detail: int) -> str:
    """EVENT SUSPECT's detail (from × n_states + to) as "10→11", or "?"."""
    n = robot.n_states
    if detail == 0xFFFF or detail >= n * n:
        return "?"
    t = robot.transitions
    return f"{t.label(detail // n)}→{t.label(detail % n)}"


def without_actuator(robot: Robot, actuator: str) -> TransitionTable:
    """``robot``'s table without the transitions that need ``actuator`` under the compiled map."""
    names = [a.name for a in robot.actuators]
    if actuator not in names or not any(limb.actuator == actuator for limb in robot.limbs):
        raise ValueError(f"no limb of {robot.name} is driven by {actuator!r}")
    return dead_table(robot, names.index(actuator))


def replan(robot: Robot, actuator: str, direction: str = "+x", lost_before: Iterable[str] = ()) -> Replan:
    """The best gait (rate: reward per transition) of ``robot`` without ``actuator``, with
    the compiled limb→actuator map or a remapped one, whichever is better. ``lost_before``:
    actuators lost earlier in the run; a gait that would raise a limb on one of them is not
    taken: then the best gait with all of them dead (their limbs down, the compiled map)."""
    fb: Fallback = fallback(robot, actuator, direction)
    names = [a.name for a in robot.actuators]
    before = tuple(dict.fromkeys(names.index(a) for a in lost_before if a in names and a != actuator))
    if before and fb.states is not None and _raises_on(robot, fb.actuator_map, fb.states, before):
        # a plan without this coil alone brought one lost before back (caterpillar-4 without its tail
        # coil, then without its head coil: a gait raising the tail, whose dead coil was heated up to
        # the state timeout again after the replanner's own CLEAR)
        gone = (names.index(actuator), *before)
        table = dead_table(robot, gone)
        states, rate = best_gait(table, direction)
        fb = Fallback(" and ".join(names[i] for i in gone), gone[0], "dead", compiled_map(robot), table, states,
                      rate)
        if states is None:
            return Replan(actuator, table, None, 0.0,
                          f"without {fb.actuator} (lost before) no gait moves {robot.name} in {direction}",
                          fb.actuator_map)
    if fb.states is None:
        return Replan(actuator, fb.table, None, 0.0,
                      f"without {actuator} no gait moves {robot.name} in {direction}, with the compiled "
                      "limb→actuator map nor with the remaining coils raising the lost coil's limbs",
                      fb.actuator_map)
    return Replan(actuator, fb.table, fb.states, fb.rate, fb.describe(robot), fb.actuator_map)


def _raises_on(robot: Robot, actuator_map: tuple[int, ...], states: Iterable[int], actuators: Iterable[int]) -> bool:
    """Whether a walk through ``states`` raises a limb that ``actuator_map`` gives one of ``actuators``."""
    on = [i for i, a in enumerate(actuator_map) if a in set(actuators)]
    return any(limb_levels(s, robot.levels)[i] > 0 for s in states for i in on)


@dataclass
class Replanner(Listener):
    """Replan a running gait after an actuator loss (module doc). ``direction``: the run's
    (+x or -x), or None to follow the running gait's. A loaded gait whose way START left
    unstated is not replanned: which way should the new gait go?"""

    robot: Robot
    client: RobotClient
    direction: str | None = "+x"
    say: Callable[[str], None] = print
    actions: list[str] = field(default_factory=list)   # what it did, one line each
    _suspect: str | None = None
    _fault: tuple[int, int] | None = None
    _stopped_at: float | None = None
    _fell_back: bool = False
    _ran: str | None = "+x"                             # the direction the gait ran in (telemetry; None: unstated)
    _done: set[str] = field(default_factory=set)
    _given_up: int | None = None                        # the actuator the firmware's fallback gave up (FALLBACK)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def _tell(self, text: str) -> None:
        self.actions.append(text)
        self.say(text)

    def on_message(self, rx: Received) -> None:
        m = rx.message
        if m.name == "TELEMETRY":
            if m.flags & Flag.RUNNING:
                way = direction_text(m.direction)
                self._ran = way if way in ("+x", "-x") else None
            return
        if m.name != "EVENT":
            return
        told = None
        with self._lock:
            if m.kind == EventKind.FAULT and m.code in (FaultCode.STATE_TIMEOUT, FaultCode.SMA_ON_LIMIT):
                self._fault = (m.code, m.detail)
            elif m.kind == EventKind.SUSPECT:
                name = self.robot.actuators[m.code].name if m.code < len(self.robot.actuators) else None
                self._suspect = name
                n = self.robot.n_states
                where = (f"in state {self.robot.transitions.label(m.detail % n)}, the step's target"
                         if m.detail < n * n and m.detail // n == m.detail % n
                         else f"transition {describe_transition(self.robot, m.detail)} failed")
                told = f"firmware suspects {name or 'no actuator'} ({where})"
            elif m.kind == EventKind.GAIT_STOPPED and m.code == StopReason.FAULT:
                self._stopped_at = rx.time
                self._fell_back = False
            elif m.kind == EventKind.FALLBACK:
                name = self.robot.actuators[m.code].name if m.code < len(self.robot.actuators) else str(m.code)
                ok = m.code < len(self.robot.actuators)
                way = self._direction()
                fb = fallback(self.robot, m.code, way) if ok and way is not None else None
                self._fell_back = True
                self._stopped_at = None
                if ok:
                    self._given_up = m.code
                self._done.add(name)
                told = f"firmware fell back by itself: {fb.describe(self.robot) if fb else name}"
        if told is not None:
            self._tell(told)

    def __post_init__(self) -> None:
        if self.direction not in ("+x", "-x", None):
            raise ValueError(f"Replanner: direction {self.direction!r}: expected +x, -x or None")

    def _direction(self) -> str | None:
        return self.direction or self._ran

    def due(self) -> bool:
        """Whether ``poll`` would act now: the gait stopped on a fault SETTLE_S ago and the
        firmware did not fall back by itself."""
        with self._lock:
            return (self._stopped_at is not None and not self._fell_back
                    and self.client.link.clock() - self._stopped_at >= SETTLE_S)

    def poll(self) -> None:
        """Act once the stream has been quiet for SETTLE_S after the gait stopped on a fault."""
        with self._lock:
            if self._stopped_at is None or self._fell_back:
                return
            if self.client.link.clock() - self._stopped_at < SETTLE_S:
                return
            self._stopped_at = None
            actuator = self._suspect
            if actuator is None and self._fault is not None:
                actuator = suspect(self.robot, *self._fault)
            self._suspect, self._fault = None, None
            again = actuator in self._done
            lost_before = tuple(self._done)  # each coil replanned around (or given up) in this run
            if actuator is not None:
                self._done.add(actuator)
            direction = self._direction()
            given_up = self._given_up
        if actuator is None:
            self._tell("gait stopped on a fault that names no actuator: not replanning")
            return
        if direction is None:
            self._tell("the loaded gait's way was not stated (START without +x/-x): not replanning")
            return
        if again:
            self._tell(f"{actuator} lost again after replanning: giving up")
            return
        plan = replan(self.robot, actuator, direction, lost_before)
        self._tell(f"replanning: {plan.reason}")
        if plan.states is None:
            return
        if given_up is not None and given_up in plan.actuator_map:
            # the firmware refuses a map naming the coil its fallback gave up (only the empty map,
            # the operator's clear, takes it back): replanning past a second loss would need it
            self._tell(f"the plan needs {self.robot.actuators[given_up].name}, which the firmware gave up: "
                       "not replanning (clear takes it back)")
            return
        try:
            self.client.request("SET_ACTUATOR_MAP", retries=2, actuators=tuple(plan.actuator_map))
            self.client.load_gait(plan.states[:-1])
            self.client.request("CLEAR", retries=2, what=int(ClearWhat.FAULTS))
            self.client.request("START", retries=2, gait=GAIT_USER, direction=direction_code(direction, GAIT_USER))
        except LinkError as e:
            self._tell(f"replanning failed: {e}")
            return
        self._tell(f"loaded and started {'→'.join(plan.table.label(s) for s in plan.states)} in {direction}")
