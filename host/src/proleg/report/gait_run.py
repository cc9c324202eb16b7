"""Run a gait on the simulated robot and report what happened.

The firmware is commanded through ``proleg.link.RobotClient`` over a ``SimLink``, exactly as a
real board would be (START, STOP, ... each checked against its acknowledgement); what it
reports (events, telemetry) is compared with the plant's ground truth, which the link attaches
to every received message (``Received.truth``). A gait cycle is counted each time the firmware
reports reaching step 0 of the running gait; the displacement per cycle is the plant's
displacement between consecutive such events.

A START or STOP that is not acknowledged after ``COMMAND_RETRIES`` retries, or that the robot
refuses, is an error of the run (``GaitRun.errors``; a STOP that fails is followed by an
ESTOP); ``GaitRun.ok`` is False then, and also when the firmware reported a fault.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from ..errors import LinkError
from ..link.client import Received, RobotClient
from ..link.direction import direction_code
from ..link.listeners import Listener
from ..link.sim_link import SimLink
from ..protocol.codec import Message
from ..protocol.definition import EventKind, FaultCode, StopReason
from ..sim.closed_loop import SimulatedRobot

#: a START/STOP is sent again this many times when no reply comes within the client's timeout
COMMAND_RETRIES = 4
#: virtual seconds the run goes on after STOP (telemetry is counted until then)
STOP_TAIL_S = 0.05
_EPS = 1e-9
#: ``SimSession.until_info`` runs the board in steps this long (the boot INFO comes at ≈ 2 ms)
INFO_STEP_S = 0.001


@dataclass
class Fault:
    time_s: float
    code: str
    detail: int

    @classmethod
    def of(cls, event: Message) -> Fault:
        """From a FAULT event."""
        return cls(event.time_ms / 1000.0, FaultCode(event.code).name, event.detail)


#: A run's last frames missing for this many frame intervals, and at least ``SILENT_MIN_S``,
#: is a silent link (``GaitRun.end_silence``).
SILENT_FRAMES = 5
SILENT_MIN_S = 0.5


@dataclass
class GaitRun:
    """What one run of a gait produced: firmware view and plant truth side by side."""

    robot: str
    direction: str
    gait: int
    duration_s: float  # asked for; 0 when START was refused or got no answer
    states_reached: list[int] = field(default_factory=list)  # firmware STATE_REACHED, in order
    cycle_displacements_mm: list[float] = field(default_factory=list)
    displacement_mm: float = 0.0  # plant truth over the whole run
    true_transitions: int = 0
    unexpected_transitions: int = 0
    faults: list[Fault] = field(default_factory=list)
    telemetry_frames: int = 0
    telemetry_lost: int = 0  # sequence-number gaps
    #: Seconds at the end of the run (STOP's tail included) in which no telemetry frame came: a
    #: link that went silent loses frames no sequence gap counts (``silent_tail``).
    telemetry_silent_s: float = 0.0
    silent_after_s: float = 0.0  # from START to the last frame (or 0), when telemetry_silent_s says silence
    first_frame_at: float | None = None  # link clock of the first and the last telemetry frame
    last_frame_at: float | None = None
    link_errors: dict[str, int] = field(default_factory=dict)
    replies: list[Message] = field(default_factory=list)
    telemetry: list[Message] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)  # commands not acknowledged or refused
    limb_loss: list[dict] = field(default_factory=list)  # EVENT SUSPECT / FALLBACK fields, in order
    #: GAIT_STOPPED events with reason FAULT: a fault that latched and stopped the gait. A FAULT
    #: event without one is a report (a single on-limit hit, docs/safety.md): the gait went on.
    fault_stops: int = 0
    started_s: float | None = None  # the board's clock (s from boot) at its first GAIT_STARTED

    def after_start(self, time_s: float) -> str:
        """For a board time: ' (6.600 s after START)', or '' when START was never reported."""
        return "" if self.started_s is None else f" ({time_s - self.started_s:.3f} s after START)"

    def end_silence(self, started_at: float, ended_at: float, telemetry_hz: float | None = None) -> None:
        """Set ``telemetry_silent_s`` for a run whose START went out at ``started_at`` and whose
        STOP's tail ended at ``ended_at`` (link clock): the time since the last frame (since START
        if none came), when it is longer than ``SILENT_FRAMES`` frame intervals and
        ``SILENT_MIN_S``, else 0 (a frame due just after the end is no silence). The interval is
        the frames' own (a host may have changed the rate), else ``1 / telemetry_hz``."""
        first, last = self.first_frame_at, self.last_frame_at
        if first is not None and last is not None and self.telemetry_frames > 1 and last > first:
            interval = (last - first) / (self.telemetry_frames - 1)
        else:
            interval = 1.0 / telemetry_hz if telemetry_hz else SILENT_MIN_S
        since = max(last if last is not None else started_at, started_at)
        quiet = ended_at - since
        self.telemetry_silent_s = quiet if quiet > max(SILENT_MIN_S, SILENT_FRAMES * interval) else 0.0
        self.silent_after_s = since - started_at

    def lost_text(self) -> str:
        """"3 lost", or "3 lost, none after 5.0 s of the run (20.1 s without a frame)": what the
        telemetry line says of the frames that did not come."""
        silent = (f", none after {self.silent_after_s:.1f} s of the run ({self.telemetry_silent_s:.1f} s without a "
                  "frame)") if self.telemetry_silent_s else ""
        return f"{self.telemetry_lost} lost{silent}"

    @property
    def cycles(self) -> int:
        return len(self.cycle_displacements_mm)

    @property
    def mean_cycle_mm(self) -> float | None:
        c = self.cycle_displacements_mm
        return sum(c) / len(c) if c else None

    @property
    def ok(self) -> bool:
        """No command failed and the firmware reported no fault."""
        return not self.errors and not self.faults


class GaitRunListener(Listener):
    """Fills a ``GaitRun`` from the decoded-message stream (truth from ``Received.truth``)."""

    def __init__(self, run: GaitRun, keep_telemetry: bool = False):
        self.run = run
        self.keep_telemetry = keep_telemetry
        self._last_seq: int | None = None
        self._last_ms: int | None = None
        self._cycle_start_mm: float | None = None

    def on_message(self, rx: Received) -> None:
        msg, run = rx.message, self.run
        if msg.name == "TELEMETRY":
            seq = msg.seq
            if self._last_seq is not None:
                run.telemetry_lost += (seq - self._last_seq - 1) % 0x10000
            self._last_seq = seq
            ms = msg.time_ms
            if self._last_ms is not None and run.started_s is not None and ms < self._last_ms:
                # the board's clock went back: it reset (a brown-out, its watchdog, a loose
                # supply) and boots idle; the run went on to its end and exited 0, 0 faults
                run.errors.append(f"the board reset after START (its clock went back from {self._last_ms / 1000:.3f} s "
                                  f"to {ms / 1000:.3f} s): a reset board stops the gait and boots idle")
                run.started_s = None  # a second reset is said again; times after it are on the new clock
            self._last_ms = ms
            run.telemetry_frames += 1
            run.last_frame_at = rx.time
            if run.first_frame_at is None:
                run.first_frame_at = rx.time
            if self.keep_telemetry:
                run.telemetry.append(msg)
        elif msg.name == "EVENT":
            if msg.kind == EventKind.STATE_REACHED:
                run.states_reached.append(msg.detail)
                if msg.code == 0:  # step 0 of the gait: a cycle boundary
                    now = rx.truth.get("displacement_mm", 0.0)
                    if self._cycle_start_mm is not None:
                        run.cycle_displacements_mm.append(now - self._cycle_start_mm)
                    self._cycle_start_mm = now
            elif msg.kind == EventKind.FAULT:
                run.faults.append(Fault.of(msg))
            elif msg.kind in (EventKind.SUSPECT, EventKind.FALLBACK):
                run.limb_loss.append(dict(msg.fields))
            elif msg.kind in (EventKind.GAIT_STARTED, EventKind.GAIT_STOPPED):
                if msg.kind == EventKind.GAIT_STOPPED and msg.code == StopReason.FAULT:
                    run.fault_stops += 1
                # a cycle runs from step 0 to step 0 of one gait without a stop between: a
                # fault's stop and a fallback's start end the one under way uncounted
                self._cycle_start_mm = None
                if msg.kind == EventKind.GAIT_STARTED and run.started_s is None:
                    run.started_s = msg.time_ms / 1000.0
        else:
            run.replies.append(msg)


class SimSession:
    """A host talking to one simulated robot through ``RobotClient`` over a ``SimLink``.

    Every received message goes, in order and in this thread, to ``listeners`` (a recorder...)
    and, during ``run_gait``, to the run's ``GaitRunListener``."""

    def __init__(self, sim: SimulatedRobot, keep_telemetry: bool = False, listeners: Iterable[Listener] = ()):
        self.sim = sim
        self.keep_telemetry = keep_telemetry
        self.listeners: list[Listener] = list(listeners)
        self.link = SimLink(sim, step_s=sim.plant_dt_s, description=f"simulated {sim.robot.name}")
        self.client = RobotClient(self.link, max_limbs=len(sim.robot.limbs), max_channels=len(sim.robot.actuators),
                                  watchdog_ms=sim.robot.safety.link_watchdog_ms)
        self._scheduled: list[tuple[float, str]] = []  # (virtual time s, fault), sorted
        self._latched: list[Fault] = []  # faults the board latched and has not cleared since

    def schedule_fault(self, at_s: float, fault: str) -> None:
        """Inject ``fault`` (see proleg.sim.closed_loop.FAULTS) once virtual time reaches ``at_s``."""
        self._scheduled.append((at_s, fault))
        self._scheduled.sort()

    def request(self, name: str, *, retries: int = COMMAND_RETRIES, **fields: int | tuple[int, ...]) -> Message:
        """Send a command and return its reply; raises ``LinkError`` (``CommandRefused`` on NACK)."""
        reply = self.client.request(name, retries=retries, **fields)
        self._dispatch_queued()
        return reply

    def advance(self, seconds: float) -> None:
        """Run the simulation for ``seconds`` of virtual time, handing every message the
        firmware sends to the listeners and injecting scheduled faults on time."""
        clock = self.link.clock
        deadline = clock() + seconds
        while True:
            self._inject_due()
            remaining = deadline - clock()
            if remaining <= _EPS:
                return
            if self._scheduled:
                remaining = min(remaining, max(self.sim.plant_dt_s, self._scheduled[0][0] - self.sim.time_s))
            rx = self.client.recv_received(remaining)
            if rx is not None:
                self._dispatch(rx)

    def until_info(self, limit_s: float) -> float:
        """Run until the board's boot INFO has arrived (``client.info``: it names the firmware
        for a recording's metadata), for at most ``limit_s`` of virtual time, in steps of
        ``INFO_STEP_S``; the virtual seconds that took. The messages go to the listeners."""
        clock = self.link.clock
        t0 = clock()
        while self.client.info is None and clock() - t0 < limit_s - _EPS:
            self.advance(min(INFO_STEP_S, limit_s - (clock() - t0)))
        return clock() - t0

    def run_gait(self, direction: str = "+x", gait: int = 0, duration_s: float = 60.0) -> GaitRun:
        """START the gait, run for ``duration_s`` of virtual time, STOP, report. A START or STOP
        that is refused or never acknowledged is recorded in ``GaitRun.errors``."""
        plant = self.sim.plant
        start_mm = plant.displacement_mm
        start_transitions = len(plant.transitions)
        start_unexpected = plant.unexpected_transitions
        counters = self.client.decoder.counters()
        run = GaitRun(self.sim.robot.name, direction, gait, duration_s)
        if not self.client.state_known:  # just booted: the board refuses START before it knows its state
            self.client.wait_known_state()
        self._dispatch_queued()
        listener = GaitRunListener(run, self.keep_telemetry)
        self.listeners.append(listener)
        try:
            t0 = self.link.clock()
            before = list(self._latched)
            started = self._command(run, "START", gait=gait, direction=direction_code(direction, gait))
            if not started and before:  # refused for a fault latched before START: report it
                run.faults[:0] = before
            if started:
                self.advance(duration_s - (self.link.clock() - t0))
            t_stop = self.link.clock()
            if not self._command(run, "STOP"):
                self._command(run, "ESTOP")  # the coils must go cold whatever the link does
            self.advance(STOP_TAIL_S - (self.link.clock() - t_stop))
            run.end_silence(t0, self.link.clock(), self.sim.robot.control.telemetry_hz)
        finally:
            self.listeners.remove(listener)
        run.displacement_mm = plant.displacement_mm - start_mm
        run.true_transitions = len(plant.transitions) - start_transitions
        run.unexpected_transitions = plant.unexpected_transitions - start_unexpected
        run.link_errors = {
            k: v - counters.get(k, 0)
            for k, v in self.client.decoder.counters().items()
            if k != "frames_ok" and v - counters.get(k, 0)
        }
        return run

    def _command(self, run: GaitRun, name: str, **fields: int) -> bool:
        try:
            self.request(name, **fields)
            return True
        except LinkError as e:
            self._dispatch_queued()
            run.errors.append(f"{name} failed: {e}")
            return False

    def _inject_due(self) -> None:
        while self._scheduled and self.sim.time_s >= self._scheduled[0][0] - _EPS:
            fault = self._scheduled.pop(0)[1]
            self.sim.inject(fault)
            for listener in self.listeners:
                mark = getattr(listener, "mark", None)  # recorders mark injections for the plots
                if callable(mark):
                    mark(self.link.clock(), self.sim.time_s, fault)

    def _dispatch_queued(self) -> None:
        while (rx := self.client.recv_received(0.0)) is not None:
            self._dispatch(rx)

    def _dispatch(self, rx: Received) -> None:
        msg = rx.message
        if msg.name == "EVENT" and msg.kind == EventKind.FAULT:
            self._latched.append(Fault.of(msg))
        elif msg.name == "EVENT" and msg.kind == EventKind.FAULT_CLEARED:
            self._latched.clear()
        for listener in self.listeners:
            listener.on_message(rx)
