"""Run a gait on the simulated robot and report what happened.

The firmware is commanded over its link exactly as a real board would be (START,
STOP, ...); what it reports (events, telemetry) is compared with the plant's ground
truth: the true state transitions and the centre-of-mass displacement. A gait cycle
is counted each time the firmware reports reaching step 0 of the running gait; the
displacement per cycle is the plant's displacement between consecutive such events.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..protocol.codec import FrameDecoder, Message, encode
from ..protocol.definition import Direction, EventKind, FaultCode
from .closed_loop import SimulatedRobot

DIRECTION_CODE = {"+x": int(Direction.PLUS_X), "-x": int(Direction.MINUS_X)}


@dataclass
class Fault:
    time_s: float
    code: str
    detail: int


@dataclass
class GaitRun:
    """What one run of a gait produced: firmware view and plant truth side by side."""

    robot: str
    direction: str
    gait: int
    duration_s: float
    states_reached: list[int] = field(default_factory=list)  # firmware STATE_REACHED, in order
    cycle_displacements_mm: list[float] = field(default_factory=list)
    displacement_mm: float = 0.0  # plant truth over the whole run
    true_transitions: int = 0
    unexpected_transitions: int = 0
    faults: list[Fault] = field(default_factory=list)
    telemetry_frames: int = 0
    telemetry_lost: int = 0  # sequence-number gaps
    link_errors: dict[str, int] = field(default_factory=dict)
    replies: list[Message] = field(default_factory=list)
    telemetry: list[Message] = field(default_factory=list)

    @property
    def cycles(self) -> int:
        return len(self.cycle_displacements_mm)

    @property
    def mean_cycle_mm(self) -> float | None:
        c = self.cycle_displacements_mm
        return sum(c) / len(c) if c else None


class SimSession:
    """A host talking to one simulated robot over its (simulated) serial link."""

    def __init__(self, sim: SimulatedRobot, keep_telemetry: bool = False, listener=None):
        self.sim = sim
        self.listener = listener  # called with proleg.link.Received for every message
        self.decoder = FrameDecoder(len(sim.robot.limbs), len(sim.robot.actuators))
        self.keep_telemetry = keep_telemetry
        self._token = 0
        self._last_seq: int | None = None
        self._run: GaitRun | None = None
        self._cycle_start_mm: float | None = None
        self._scheduled: list[tuple[float, str]] = []  # (virtual time s, fault), sorted
        self.inbox: list[Message] = []

    def schedule_fault(self, at_s: float, fault: str) -> None:
        """Inject ``fault`` (see proleg.sim.closed_loop.FAULTS) once virtual time reaches ``at_s``."""
        self._scheduled.append((at_s, fault))
        self._scheduled.sort()

    def send(self, name: str, **fields) -> int:
        self._token = self._token % 255 + 1
        self.sim.write(encode(Message.new(name, token=self._token, **fields)))
        return self._token

    def advance(self, seconds: float, chunk_s: float = 0.02) -> None:
        """Run the simulation, handling every message the firmware sends."""
        steps = max(1, round(seconds / chunk_s))
        for _ in range(steps):
            while self._scheduled and self.sim.time_s >= self._scheduled[0][0] - 1e-9:
                self.sim.inject(self._scheduled.pop(0)[1])
            self.sim.advance(chunk_s)
            for msg in self.decoder.feed(self.sim.read()):
                self._handle(msg)

    def request(self, name: str, timeout_s: float = 0.2, **fields) -> Message | None:
        """Send a command and return the reply carrying its token (None on timeout)."""
        token = self.send(name, **fields)
        waited = 0.0
        while waited < timeout_s:
            self.advance(0.005, 0.005)
            waited += 0.005
            for i, m in enumerate(self.inbox):
                if m.fields.get("token") == token:
                    return self.inbox.pop(i)
        return None

    def _handle(self, msg: Message) -> None:
        if self.listener is not None:
            from ..link.client import Received

            self.listener(Received(msg, self.sim.time_s, {"displacement_mm": self.sim.plant.displacement_mm}))
        run = self._run
        if msg.name == "TELEMETRY":
            seq = msg.seq
            if self._last_seq is not None and run is not None:
                run.telemetry_lost += (seq - self._last_seq - 1) % 0x10000
            self._last_seq = seq
            if run is not None:
                run.telemetry_frames += 1
                if self.keep_telemetry:
                    run.telemetry.append(msg)
            return
        if msg.name == "EVENT":
            t = msg.time_ms / 1000.0
            if run is not None and msg.kind == EventKind.STATE_REACHED:
                run.states_reached.append(msg.detail)
                if msg.code == 0:  # step 0 of the gait: a cycle boundary
                    now = self.sim.plant.displacement_mm
                    if self._cycle_start_mm is not None:
                        run.cycle_displacements_mm.append(now - self._cycle_start_mm)
                    self._cycle_start_mm = now
            elif run is not None and msg.kind == EventKind.FAULT:
                run.faults.append(Fault(t, FaultCode(msg.code).name, msg.detail))
            return
        self.inbox.append(msg)
        if run is not None:
            run.replies.append(msg)

    def run_gait(self, direction: str = "+x", gait: int = 0, duration_s: float = 60.0) -> GaitRun:
        """START the gait, run for ``duration_s`` of virtual time, STOP, report."""
        plant = self.sim.plant
        start_mm = plant.displacement_mm
        start_transitions = len(plant.transitions)
        start_unexpected = plant.unexpected_transitions
        run = GaitRun(self.sim.robot.name, direction, gait, duration_s)
        self._run, self._cycle_start_mm, self._last_seq = run, None, None
        self.send("START", gait=gait, direction=DIRECTION_CODE[direction])
        self.advance(duration_s)
        self.send("STOP")
        self.advance(0.05)
        self._run = None
        run.displacement_mm = plant.displacement_mm - start_mm
        run.true_transitions = len(plant.transitions) - start_transitions
        run.unexpected_transitions = plant.unexpected_transitions - start_unexpected
        run.link_errors = {k: v for k, v in self.decoder.counters().items() if k != "frames_ok" and v}
        return run
