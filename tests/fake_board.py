"""Test double: a tiny Python stand-in for the firmware + robot, speaking the real protocol.

It is what the link tests run against when the compiled simulated board is not wanted: a two-level-per-limb robot whose ψ rises towards
``psi_high_deg`` while its actuator is driven and relaxes to ``psi_low_deg`` otherwise, a gait
sequencer that advances when the target state is held for ``hold_ms``, E-stop latching,
and the command set (PING, GET_INFO, GET_STATS, START, STOP, ESTOP, LOAD_GAIT, SET_PARAM,
SET_TELEMETRY_RATE, CLEAR) with ACK/NACK. Duck-types the board interface ``SimLink`` wraps.
It is not the firmware's specification; ``proleg.sim`` runs the real C.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from proleg.protocol.codec import FrameDecoder, Message, encode
from proleg.protocol.definition import (
    BY_NAME,
    DIR_UNSTATED,
    GAIT_USER,
    MAX_GAIT_STEPS,
    PROTOCOL_VERSION,
    ClearWhat,
    Direction,
    ErrorCode,
    EventKind,
    Flag,
    ParamId,
    StopReason,
)

#: Paper robot R1 (rows = from, columns = to); + x gait 00→10→11→01, − x its reverse.
R1_REWARDS = ((0, -1, 1, 0), (1, 0, 0, -1), (-1, 0, 0, 1), (0, 0, 0, 0))
R1_GAITS = {Direction.PLUS_X: ((0, 2, 3, 1),), Direction.MINUS_X: ((0, 1, 3, 2),)}


@dataclass
class FakeBoard:
    robot_name: str = "paper-r1"
    board_name: str = "fake"
    limbs: int = 2
    tick_hz: int = 1000
    telemetry_hz: int = 50
    psi_star_deg: float = 20.0
    psi_low_deg: float = 5.0
    psi_high_deg: float = 35.0
    tau_s: float = 0.15
    hold_ms: int = 100
    drive_duty: int = 6000
    max_duty: int = 8000
    step_mm: float = 10.0
    rewards: Sequence[Sequence[float]] = R1_REWARDS
    gaits: dict[Direction, tuple[tuple[int, ...], ...]] = field(default_factory=lambda: dict(R1_GAITS))
    build_id: int = 0x00C0FFEE
    gait_hash: int = 0x1234ABCD
    #: tests: answer no command (a dead or wrong device)
    silent: bool = False
    #: tests: drop every n-th TELEMETRY frame before it is sent (0 = never)
    drop_every: int = 0

    def __post_init__(self) -> None:
        self.time_s = 0.0
        self.displacement_mm = 0.0
        self.psi = [self.psi_low_deg] * self.limbs
        self.duty = [0] * self.limbs
        self.running = False
        self.gait = 0
        self.direction = Direction.PLUS_X
        self.step = 0
        self.sequence: tuple[int, ...] = ()
        self.user_gait: tuple[int, ...] = ()
        self.estop = False
        self.seq = 0
        self.frames_sent = 0
        self.received: list[Message] = []
        self._held_s = 0.0
        self._tick_acc = 0.0
        self._tel_acc = 0.0
        self._tx = bytearray()
        self._rx = FrameDecoder()
        self._nacks = 0
        self._measured = self._classify()
        self._send(self._info(0))

    # ------------------------------------------------------------------ board interface
    def write(self, data: bytes) -> None:
        for msg in self._rx.feed(bytes(data)):
            self.received.append(msg)
            if not self.silent:
                self._command(msg)

    def read(self) -> bytes:
        out, self._tx = bytes(self._tx), bytearray()
        return out

    def advance(self, seconds: float) -> None:
        period = 1.0 / self.tick_hz
        self._tick_acc += seconds
        while self._tick_acc >= period - 1e-12:
            self._tick_acc -= period
            self._tick(period)

    # ------------------------------------------------------------------ firmware
    @property
    def n_states(self) -> int:
        return 1 << self.limbs

    def _classify(self) -> int:
        state = 0
        for p in self.psi:
            state = (state << 1) | (1 if p >= self.psi_star_deg else 0)
        return state

    def _target(self) -> int:
        return self.sequence[self.step] if self.running and self.sequence else self._measured

    def _tick(self, dt: float) -> None:
        self.time_s += dt
        target = self._target()
        for i in range(self.limbs):
            want = (target >> (self.limbs - 1 - i)) & 1
            self.duty[i] = self.drive_duty if (self.running and not self.estop and want) else 0
            goal = self.psi_high_deg if self.duty[i] else self.psi_low_deg
            self.psi[i] += (goal - self.psi[i]) * min(1.0, dt / self.tau_s)
        measured = self._classify()
        if measured != self._measured:
            r = self.rewards[self._measured][measured]
            self.displacement_mm += float(r) * self.step_mm
            self._measured = measured
        if self.running and measured == target:
            self._held_s += dt
            if self._held_s * 1000 >= self.hold_ms:
                self._held_s = 0.0
                self._event(EventKind.STATE_REACHED, self.step, target)
                self.step = (self.step + 1) % len(self.sequence)
        else:
            self._held_s = 0.0
        if self.telemetry_hz:
            self._tel_acc += dt
            if self._tel_acc >= 1.0 / self.telemetry_hz - 1e-9:
                self._tel_acc -= 1.0 / self.telemetry_hz
                self._telemetry()

    def _flags(self) -> int:
        f = Flag(0)
        if self.running:
            f |= Flag.RUNNING
        if self.estop:
            f |= Flag.ESTOP
        if self.user_gait:
            f |= Flag.USER_GAIT
        return int(f)

    def _telemetry(self) -> None:
        seq, self.seq = self.seq, (self.seq + 1) & 0xFFFF
        if self.drop_every and (seq + 1) % self.drop_every == 0:
            return
        self._send(Message.new(
            "TELEMETRY", seq=seq, time_ms=int(self.time_s * 1000) & 0xFFFFFFFF, measured=self._measured,
            target=self._target(), gait=self.gait, direction=int(self.direction), step=self.step,
            flags=self._flags(), psi=tuple(int(round(p * 100)) for p in self.psi),
            duty=tuple(self.duty),
        ))

    def _send(self, msg: Message) -> None:
        self._tx += encode(msg)
        self.frames_sent += 1

    def _event(self, kind: EventKind, code: int, detail: int) -> None:
        self._send(Message.new("EVENT", time_ms=int(self.time_s * 1000), kind=int(kind), code=code, detail=detail))

    def _info(self, token: int) -> Message:
        return Message.new(
            "INFO", token=token, protocol_version=PROTOCOL_VERSION, build_id=self.build_id,
            gait_hash=self.gait_hash, robot_name=self.robot_name, board=self.board_name, limbs=self.limbs,
            actuators=self.limbs, gaits=len(self.gaits[Direction.PLUS_X]), max_gait_steps=MAX_GAIT_STEPS,
            tick_hz=self.tick_hz, telemetry_hz=self.telemetry_hz,
        )

    def _ack(self, msg: Message) -> None:
        self._send(Message.new("ACK", token=msg.token, cmd=msg.id))

    def _nack(self, msg: Message, error: ErrorCode, detail: int = 0) -> None:
        self._nacks += 1
        self._send(Message.new("NACK", token=msg.token, cmd=msg.id, error=int(error), detail=detail))

    def _stop(self, reason: StopReason) -> None:
        if self.running:
            self.running = False
            self._event(EventKind.GAIT_STOPPED, int(reason), 0)
        self.duty = [0] * self.limbs

    def _command(self, msg: Message) -> None:  # noqa: C901 - one branch per command
        name = msg.name
        if BY_NAME[name].direction != "h2r":
            return
        if name == "PING":
            self._ack(msg)
        elif name == "GET_INFO":
            self._send(self._info(msg.token))
        elif name == "GET_STATS":
            c = self._rx
            self._send(Message.new(
                "STATS", token=msg.token, rx_ok=c.frames_ok, crc_errors=c.crc_errors,
                framing_errors=c.framing_errors, unknown_ids=c.unknown_ids, bad_length=c.bad_length,
                bad_value=c.bad_value, nacks=self._nacks, tx_frames=self.frames_sent, tx_dropped=0, tick_overruns=0,
            ))
        elif name == "START":
            if self.estop:
                return self._nack(msg, ErrorCode.ESTOP_LATCHED)
            if msg.direction not in (0, 1) and not (msg.direction == DIR_UNSTATED and msg.gait == GAIT_USER):
                return self._nack(msg, ErrorCode.OUT_OF_RANGE, 2)  # as cmd.c
            direction = msg.direction
            if msg.gait == GAIT_USER:
                if not self.user_gait:
                    return self._nack(msg, ErrorCode.NO_GAIT)
                seq = self.user_gait
            elif msg.gait < len(self.gaits.get(direction, ())):
                seq = self.gaits[direction][msg.gait]
            else:
                return self._nack(msg, ErrorCode.NO_GAIT, msg.gait)
            self.running, self.gait, self.direction, self.step, self.sequence = True, msg.gait, direction, 0, seq
            self._ack(msg)
            self._event(EventKind.GAIT_STARTED, msg.gait, int(direction))
        elif name == "STOP":
            self._stop(StopReason.COMMAND)
            self._ack(msg)
        elif name == "ESTOP":
            self.estop = True
            self._stop(StopReason.ESTOP)
            self._ack(msg)
            self._event(EventKind.ESTOP, 0, 0)
        elif name == "CLEAR":
            if msg.what & ClearWhat.ESTOP:
                self.estop = False
            self._ack(msg)
            self._event(EventKind.FAULT_CLEARED, msg.what, 0)
        elif name == "LOAD_GAIT":
            states = tuple(msg.states)
            if self.running:
                return self._nack(msg, ErrorCode.NOT_ALLOWED)
            if len(states) < 2:
                return self._nack(msg, ErrorCode.OUT_OF_RANGE, 0)
            for k, s in enumerate(states):
                nxt = states[(k + 1) % len(states)]
                if s >= self.n_states or nxt >= self.n_states or s == nxt:
                    return self._nack(msg, ErrorCode.FORBIDDEN_TRANSITION, k)
            self.user_gait = states
            self._ack(msg)
            self._event(EventKind.GAIT_LOADED, 0, len(states))
        elif name == "SET_PARAM":
            if msg.param not in {int(p) for p in ParamId}:
                return self._nack(msg, ErrorCode.OUT_OF_RANGE, msg.param)
            if msg.param == ParamId.DRIVE_DUTY:
                if msg.value > self.max_duty:
                    return self._nack(msg, ErrorCode.SAFETY_LIMIT, msg.param)
                if msg.value < 0:
                    return self._nack(msg, ErrorCode.OUT_OF_RANGE, msg.param)
                self.drive_duty = msg.value
            elif msg.param == ParamId.HOLD_MS:
                self.hold_ms = max(0, msg.value)
            self._ack(msg)
        elif name == "GET_ACTUATOR_MAP":  # the build's map, no coil given up (no fallback here)
            self._send(Message.new("ACTUATOR_MAP", token=msg.token, lost=0xFF, actuators=tuple(range(self.limbs))))
        elif name == "SET_TELEMETRY_RATE":
            if msg.hz > self.tick_hz:
                return self._nack(msg, ErrorCode.OUT_OF_RANGE, 0)
            self.telemetry_hz = msg.hz
            self._tel_acc = 0.0
            self._ack(msg)
