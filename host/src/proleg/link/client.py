"""``RobotClient``: talk to one robot over any ``Link``.

One decoded-message stream per robot: ``recv()`` returns every message the robot sent
(telemetry, events, replies) in order; a ``Notifier`` (``proleg.link.listeners``) pumps that
stream into listeners (console, recorder, printer, tests), none of which knows the link.

Commands carry a token (1..255) and wait for the reply echoing it; which message answers
which command comes from the protocol definition (``MessageSpec.reply``: INFO for GET_INFO,
STATS for GET_STATS, ACK otherwise; ``reply_answers``), so a reply is matched by token *and*
command: a stale ACK for another command that reused the token does not confirm a STOP or an
ESTOP. A NACK raises ``CommandRefused`` naming the error code; silence raises
``LinkError("no reply to PING within 0.5 s on /dev/ttyUSB0")``. Timeouts run on the link's
clock (virtual time on the simulated board). Replies are recognised whoever is reading:
the waiting command itself when nobody else is, the Notifier thread otherwise.

TELEMETRY sequence numbers are checked: a jump counts the skipped frames in ``stats.lost``;
a backwards jump (a reset) or a new INFO restarts the count. A vanished serial device
(``LinkDisconnected``) is reopened until ``reconnect_timeout`` seconds pass; afterwards
the client sends GET_INFO again (the reply refreshes ``info``) and counts ``stats.reconnects``.

Heartbeat: the firmware's link watchdog (on by default, ``[safety] link_watchdog_ms``) stops
a gait when no valid frame arrives for that long. While anyone reads the client (``recv``,
a Notifier, a waiting command), a connected client sends a PING whenever it has written
nothing for ``heartbeat_s`` seconds of the link's clock (default 0.5 s, a quarter of the
default 2 s watchdog; ``watchdog_ms``, the robot file's, shortens it to a quarter of that),
so an idle session never trips it; the ACKs of those PINGs are not
queued. The period counts on the board's clock: when TELEMETRY shows it running faster than
the link's (a simulated board at ``--speed 5`` behind a pty), the period shrinks in
proportion, or the watchdog would trip between two PINGs. ``heartbeat_s=None`` turns it off
(a test playing a host that went away).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Iterator, Sequence
from types import TracebackType

from ..errors import LinkError
from ..protocol.codec import FrameDecoder, Message, encode
from ..protocol.definition import (
    BY_NAME,
    CHANNEL_CEILING,
    GAIT_USER,
    LIMB_CEILING,
    MESSAGES,
    PROTOCOL_VERSION,
    DIR_UNSTATED,
    ClearWhat,
    Direction,
    ErrorCode,
    Flag,
    MessageSpec,
    ParamId,
    reply_answers,
)
from .base import Link, LinkDisconnected
from .board_clock import BoardClockRate
from .direction import direction_code

# The reply values and the receive side's values live in their own modules; re-exported here so
# ``from proleg.link.client import RobotInfo, Received`` keeps working.
from .received import LinkStats, Received
from .replies import CommandRefused, FirmwareStats, ReplyTimeout, RobotInfo

#: ACTUATOR_MAP's ``lost`` when no coil is given up (core/limbmap.h LIMBMAP_NONE)
LIMBMAP_NONE = 0xFF

__all__ = [
    "CommandRefused",
    "FirmwareStats",
    "LinkStats",
    "Received",
    "ReplyTimeout",
    "RobotClient",
    "RobotInfo",
]

DEFAULT_TIMEOUT = 0.5
#: how long ``connect`` keeps asking GET_INFO (link clock, seconds)
CONNECT_WITHIN_S = 3.0
#: how long each of ``connect``'s GET_INFO tries waits (a round trip at 115200 Bd is ~10 ms)
CONNECT_TRY_S = 0.05
#: decoded messages kept for ``recv`` when nobody reads them (oldest dropped first)
QUEUE_LIMIT = 65536
#: default heartbeat period (link clock, s): at most half of any watchdog ≥ 1 s; divided by
#: how much faster than the link's clock the board's runs (``RobotClient.board_rate``)
HEARTBEAT_S = 0.5
#: The heartbeat comes at least this many times per link watchdog period (the default 0.5 s
#: is a quarter of the default 2 s watchdog): a robot file's shorter watchdog shortens it.
WATCHDOG_SHARE = 4
_EPS = 1e-9  # clock comparisons: virtual time advances in float steps
#: How long ``start`` waits for the board to know its state after a reset: an MPU-6050 starts
#: in 100 ms at most (datasheet), then the state needs its debounce and a telemetry frame.
KNOWN_STATE_WAIT_S = 1.0
#: messages that can answer a command (the declared replies plus NACK)
_REPLY_NAMES = frozenset({m.reply for m in MESSAGES if m.reply} | {"NACK"})
_PING = BY_NAME["PING"]


class RobotClient:
    def __init__(
        self,
        link: Link,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        reconnect_timeout: float = 10.0,
        max_limbs: int = LIMB_CEILING,
        max_channels: int = CHANNEL_CEILING,
        poll_s: float = 0.02,
        heartbeat_s: float | None = HEARTBEAT_S,
        watchdog_ms: int | None = None,
    ):
        self.link = link
        self.timeout = timeout
        self.reconnect_timeout = reconnect_timeout
        self.poll_s = poll_s
        self.info: RobotInfo | None = None
        self.stats = LinkStats()
        self.decoder = FrameDecoder(max_limbs=max_limbs, max_channels=max_channels)
        self._queue: deque[Received] = deque(maxlen=QUEUE_LIMIT)
        self._rx_lock = threading.Lock()
        self._tx_lock = threading.Lock()
        self._cond = threading.Condition()
        self._replies: dict[int, Message] = {}
        self._waiting: dict[int, MessageSpec] = {}  # token -> the command waiting for its reply
        self._token = 0
        self._last_seq: int | None = None
        self._state_known = False  # the last TELEMETRY frame since the last INFO had a known state
        self._running: tuple[int, int] | None = None  # (gait, direction) the last TELEMETRY ran, if any
        self._reconnect_lock = threading.Lock()
        self._closed = False
        self.heartbeat_s = heartbeat_s
        self.fit_heartbeat(watchdog_ms)
        self.heartbeats = 0  # PINGs sent by the heartbeat
        self._board_clock = BoardClockRate()  # a board at --speed 5 behind a pty counts 5× faster
        self._last_tx: float | None = None  # link clock of the last write (None: not connected yet)
        self._heartbeat_tokens: set[int] = set()

    # ------------------------------------------------------------------ lifecycle
    def connect(self, timeout: float | None = None, *, within_s: float = CONNECT_WITHIN_S) -> RobotInfo:
        """Handshake: flush the robot's receiver (an empty frame), then GET_INFO, again and
        again (each try waits ``timeout``, default ``CONNECT_TRY_S``) until ``within_s`` seconds
        of the link's clock have passed: a Nano resets when its port opens and its bootloader
        waits about a second, and a noisy link loses frames (an INFO frame is ~45 bytes: at 5 %
        corrupted bytes fewer than one in ten arrives intact). Any INFO that arrives meanwhile
        counts, also a late answer to an earlier try. Raises ``LinkError`` when no INFO came."""
        wait = CONNECT_TRY_S if timeout is None else timeout
        deadline = self.link.clock() + within_s
        tries = 0
        self.info = None
        while True:
            self._write(b"\0")
            tries += 1
            try:
                info = self.get_info(wait)
                break
            except ReplyTimeout:
                if self.info is not None:  # a late answer to an earlier try, or the boot INFO
                    info = self.info
                    break
                if self.link.clock() >= deadline - _EPS:
                    raise ReplyTimeout(
                        f"no reply to GET_INFO within {_seconds(within_s)} ({tries} tries) on {self.link.description}"
                    ) from None
        if info.protocol_version != PROTOCOL_VERSION:
            raise LinkError(
                f"{self.link.description}: robot speaks protocol {info.protocol_version}, "
                f"this proleg speaks {PROTOCOL_VERSION} (rebuild the firmware or update proleg)"
            )
        return info

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.link.close()

    def __enter__(self) -> RobotClient:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    # ------------------------------------------------------------------ commands
    def get_info(self, timeout: float | None = None) -> RobotInfo:
        info = RobotInfo.from_message(self.request("GET_INFO", timeout=timeout))
        self.info = info
        return info

    def ping(self, timeout: float | None = None) -> float:
        """Round trip in seconds (link clock)."""
        t0 = self.link.clock()
        self.request("PING", timeout=timeout)
        return self.link.clock() - t0

    def start(self, gait: int = 0, direction: Direction | int | str = Direction.PLUS_X) -> None:
        """Run gait ``gait`` (``GAIT_USER`` / ``"user"`` for the loaded one) in ``direction``
        (``Direction``, 0/1, ``"+x"``/``"-x"``; for the loaded one, the way it walks, which the
        climb guard checks, or ``UNSTATED``)."""
        g = GAIT_USER if gait == "user" else int(gait)
        if not self._state_known:  # just reset, or last seen without a state: the board would refuse
            self.wait_known_state()  # (it answers for itself if the wait runs out)
        self.request("START", gait=g, direction=direction_code(direction, g))

    def stop(self) -> None:
        self.request("STOP")

    def estop(self) -> None:
        self.request("ESTOP")

    def clear(self, what: ClearWhat | int = ClearWhat.FAULTS | ClearWhat.ESTOP) -> bool:
        """CLEAR ``what``. The operator's word on faults also takes back a coil the firmware's
        fallback gave up (SET_ACTUATOR_MAP with no entries, while no gait runs): the firmware
        refuses built-in gaits without it (NOT_ALLOWED, detail 3; docs/safety.md), and a host
        restarting a gait never clears. Returns whether a coil was taken back."""
        self.request("CLEAR", what=int(what))
        if not int(what) & ClearWhat.FAULTS:
            return False
        try:
            if self.request("GET_ACTUATOR_MAP", retries=2).lost == LIMBMAP_NONE:
                return False
            self.request("SET_ACTUATOR_MAP", retries=2, actuators=())
        except CommandRefused:  # a gait runs (the fallback's): it keeps the coil given up
            return False
        return True

    def load_gait(self, states: Sequence[int]) -> None:
        """Store a user gait: a closed walk without the repeated start state."""
        self.request("LOAD_GAIT", states=tuple(int(s) for s in states))

    def fit_heartbeat(self, watchdog_ms: int | None) -> None:
        """Ping often enough for a link watchdog of ``watchdog_ms`` (the robot file's ``[safety]
        link_watchdog_ms``; None or 0: nothing to fit): at least ``WATCHDOG_SHARE`` times a
        period. A heartbeat that is off stays off."""
        if self.heartbeat_s is not None and watchdog_ms:
            self.heartbeat_s = min(self.heartbeat_s, watchdog_ms / 1000 / WATCHDOG_SHARE)

    def set_param(self, param: ParamId | int | str, index: int, value: int) -> None:
        if isinstance(param, str):
            try:
                param = ParamId[param.upper()]
            except KeyError:
                raise LinkError(f"unknown parameter {param!r}; known: {', '.join(p.name.lower() for p in ParamId)}") from None
        self.request("SET_PARAM", param=int(param), index=int(index), value=int(value))
        if int(param) == ParamId.LINK_WATCHDOG_MS:
            self.fit_heartbeat(int(value))  # a shorter watchdog from here on

    def set_telemetry_rate(self, hz: int) -> None:
        self.request("SET_TELEMETRY_RATE", hz=int(hz))

    def firmware_stats(self, timeout: float | None = None) -> FirmwareStats:
        """The firmware's link counters (GET_STATS)."""
        return FirmwareStats.from_message(self.request("GET_STATS", timeout=timeout))

    def request(self, name: str, *, timeout: float | None = None, retries: int = 0,
                **fields: int | tuple[int, ...]) -> Message:
        """Send command ``name`` with a fresh token; return its reply (the one the protocol
        definition names: ACK, INFO or STATS). NACK raises ``CommandRefused``. Without a reply
        within ``timeout`` the same frame (same token) is sent again up to ``retries`` times;
        then ``LinkError``."""
        spec = BY_NAME.get(name)
        if spec is None or spec.direction != "h2r":
            raise LinkError(f"{name!r} is not a command")
        token = self._next_token()
        frame = encode(Message(name, {"token": token, **fields}))
        with self._cond:
            self._waiting[token] = spec
            self._replies.pop(token, None)
        wait = self.timeout if timeout is None else timeout
        # A START sent again after its ACK was lost is refused: the board runs the gait the
        # first one started (a restart would restart its step). Whether the refusal is that,
        # the TELEMETRY before and after tells (_started_after_all).
        idle_before = name == "START" and self.stats.telemetry > 0 and self._running is None
        attempt = 0
        try:
            for attempt in range(retries + 1):
                self._write(frame)
                try:
                    reply = self._wait_reply(token, wait, name)
                    break
                except ReplyTimeout as e:
                    if attempt == retries:
                        self.stats.timeouts += 1
                        if retries:
                            raise ReplyTimeout(f"{e} ({retries + 1} tries)") from None
                        raise
                    self.stats.retries += 1
        finally:
            with self._cond:
                self._waiting.pop(token, None)
                self._replies.pop(token, None)
        if reply.name == "NACK":
            note = ""
            if name == "START" and attempt > 0 and reply.error == ErrorCode.NOT_ALLOWED and reply.detail == 1:
                if idle_before and self._started_after_all(fields, wait):
                    self.stats.lost_acks += 1
                    return Message("ACK", {"token": token, "cmd": spec.id})
                note = (f"; this was try {attempt + 1}: an earlier one may have started the gait and "
                        "its ACK been lost, which no TELEMETRY showed")
            self.stats.nacks += 1
            raise CommandRefused(name, reply.error, reply.detail, self.link.description, note)
        return reply

    def _started_after_all(self, fields: dict, timeout: float) -> bool:
        """A START sent again was refused because a gait runs, and the board ran none before
        the first try: whether the next TELEMETRY frame (within ``timeout``) runs the gait asked
        for, the way asked for. Then the first try started it and only its ACK was lost."""
        seen = self.stats.telemetry
        deadline = self.link.clock() + timeout
        while self.stats.telemetry == seen:
            now = self.link.clock()
            if now >= deadline - _EPS:
                return False
            if self._rx_lock.acquire(blocking=False):
                try:
                    self._pump(min(self.poll_s, deadline - now))
                finally:
                    self._rx_lock.release()
            else:  # a Notifier reads: the frames count as it receives them
                with self._cond:
                    self._cond.wait(self.poll_s)
        running = self._running
        if running is None or running[0] != fields.get("gait"):
            return False
        way = fields.get("direction")
        return way == DIR_UNSTATED or running[1] == way

    def _next_token(self) -> int:
        with self._cond:
            self._token = self._token % 255 + 1
            self._heartbeat_tokens.discard(self._token)
            return self._token

    def _write(self, data: bytes) -> None:
        with self._tx_lock:
            try:
                self.link.write(data)
            except LinkDisconnected:
                self._reconnect()
                self.link.write(data)
            self._last_tx = self.link.clock()

    @property
    def board_rate(self) -> float:
        """How many times faster than the link's clock the board's runs (``board_clock``)."""
        return self._board_clock.rate

    def _heartbeat(self) -> None:
        """PING when nothing was written for ``heartbeat_s`` (keeps the link watchdog fed)."""
        period, last = self.heartbeat_s, self._last_tx
        if period is None or last is None or self._closed:
            return
        period /= self.board_rate  # on the board's clock, as its watchdog counts
        if self.link.clock() - last < period - _EPS:
            return
        token = self._next_token()
        with self._cond:
            self._heartbeat_tokens.add(token)
        self.heartbeats += 1
        self._write(encode(Message("PING", {"token": token})))

    def _wait_reply(self, token: int, timeout: float, name: str) -> Message:
        deadline = self.link.clock() + timeout
        while True:
            with self._cond:
                reply = self._replies.get(token)
                if reply is not None:
                    return reply
            now = self.link.clock()
            if now >= deadline - _EPS:
                raise ReplyTimeout(f"no reply to {name} within {_seconds(timeout)} on {self.link.description}")
            if self._rx_lock.acquire(blocking=False):
                try:
                    self._pump(min(self.poll_s, deadline - now))
                finally:
                    self._rx_lock.release()
            else:  # another thread (a Notifier) is reading and will hand the reply over
                with self._cond:
                    if token not in self._replies:
                        self._cond.wait(self.poll_s)

    # ------------------------------------------------------------------ receiving
    def recv(self, timeout: float = 0.0) -> Message | None:
        """The next message the robot sent, or None after ``timeout`` seconds (link clock)."""
        rx = self.recv_received(timeout)
        return None if rx is None else rx.message

    def recv_received(self, timeout: float = 0.0) -> Received | None:
        """Like ``recv`` with the time of receipt and the link's ground truth."""
        queue = self._queue
        if queue:
            return queue.popleft()
        deadline = self.link.clock() + timeout
        while True:
            with self._rx_lock:
                if queue:
                    return queue.popleft()
                remaining = deadline - self.link.clock()
                self._pump(max(0.0, min(remaining, self.poll_s * 5)))
            if queue:
                return queue.popleft()
            if self.link.clock() >= deadline - _EPS:
                return None

    def telemetry(self, timeout: float = 1.0, count: int | None = None) -> Iterator[Message]:
        """TELEMETRY messages as they arrive (other messages are consumed and skipped);
        raises ``LinkError`` when none arrives within ``timeout`` seconds."""
        n = 0
        while count is None or n < count:
            deadline = self.link.clock() + timeout
            while True:
                msg = self.recv(max(0.0, deadline - self.link.clock()))
                if msg is not None and msg.name == "TELEMETRY":
                    break
                if msg is None and self.link.clock() >= deadline - _EPS:
                    raise LinkError(f"no telemetry within {_seconds(timeout)} on {self.link.description}")
            n += 1
            yield msg

    @property
    def state_known(self) -> bool:
        """The newest TELEMETRY frame since the board last (re)started gave a known state."""
        return self._state_known

    def wait_known_state(self, timeout: float = KNOWN_STATE_WAIT_S) -> Message | None:
        """The first TELEMETRY frame whose state is known (no ``STATE_UNKNOWN`` flag), or None
        when none arrives within ``timeout`` seconds: the board refuses START until it has read
        every IMU (NOT_ALLOWED, detail 2), e.g. just after it reset. Every message received
        meanwhile stays queued for ``recv``, in order."""
        seen: list[Received] = []
        deadline = self.link.clock() + timeout
        try:
            while True:
                rx = self.recv_received(max(0.0, deadline - self.link.clock()))
                if rx is None:
                    return None
                seen.append(rx)
                msg = rx.message
                if msg.name == "TELEMETRY" and not int(msg.flags) & Flag.STATE_UNKNOWN:
                    return msg
        finally:
            self._queue.extendleft(reversed(seen))

    def _pump(self, timeout: float) -> int:
        """Read the link once (caller holds ``_rx_lock``); decode; queue. Returns messages read."""
        self._heartbeat()
        try:
            data = self.link.read(timeout)
        except LinkDisconnected:
            self._reconnect()
            return 0
        if not data:
            return 0
        dec = self.decoder
        msgs = dec.feed(data)
        st = self.stats
        st.frames_ok = dec.frames_ok
        st.crc_errors = dec.crc_errors
        st.framing_errors = dec.framing_errors
        st.unknown_ids = dec.unknown_ids
        st.bad_length = dec.bad_length
        st.bad_value = dec.bad_value
        if not msgs:
            return 0
        now = self.link.clock()
        truth = self.link.truth()
        append = self._queue.append
        notify = False
        newest_ms = None  # the batch's last TELEMETRY: a backlog read at once is not a fast clock
        for m in msgs:
            name = m.name
            if name == "TELEMETRY":
                st.telemetry += 1
                flags = m.fields["flags"]
                self._state_known = not flags & Flag.STATE_UNKNOWN
                self._running = (m.fields["gait"], m.fields["direction"]) if flags & Flag.RUNNING else None
                seq = m.fields["seq"]
                last = self._last_seq
                if last is not None and seq != (last + 1) & 0xFFFF:
                    gap = (seq - last - 1) & 0xFFFF
                    if gap < 0x8000:
                        st.lost += gap
                    else:
                        st.seq_restarts += 1
                self._last_seq = seq
                newest_ms = m.fields["time_ms"]
            elif name in _REPLY_NAMES:
                token = m.fields["token"]
                waiting = self._waiting.get(token)
                answers = waiting is not None and reply_answers(name, m.fields, waiting)
                if name == "INFO":
                    self._last_seq = None  # a reset or a new session restarts the sequence
                    self._state_known = False
                    if not answers:
                        self.info = RobotInfo.from_message(m)
                if answers:
                    self._replies[token] = m
                    notify = True
                elif waiting is None and token in self._heartbeat_tokens and reply_answers(name, m.fields, _PING):
                    self._heartbeat_tokens.discard(token)
                    continue  # the heartbeat's own ACK: nobody asked for it
            append(Received(m, now, truth))
        if newest_ms is not None:
            self._board_clock.seen(now, newest_ms)
        if notify:
            with self._cond:
                self._cond.notify_all()
        return len(msgs)

    def _reconnect(self) -> None:
        """Reopen a vanished device; then ask for INFO again (without waiting)."""
        if not self._reconnect_lock.acquire(blocking=False):
            with self._reconnect_lock:  # another thread is reconnecting: wait for it
                return
        try:
            self._reconnect_locked()
        finally:
            self._reconnect_lock.release()

    def _reconnect_locked(self) -> None:
        deadline = time.monotonic() + self.reconnect_timeout
        delay = 0.05
        while True:
            if self._closed:
                raise LinkError(f"{self.link.description}: client closed")
            try:
                self.link.reopen()
                break
            except LinkDisconnected:
                pass
            except LinkError as e:
                if time.monotonic() >= deadline:
                    raise LinkError(
                        f"{self.link.description}: device disconnected and not back within "
                        f"{_seconds(self.reconnect_timeout)} ({e})"
                    ) from None
            if time.monotonic() >= deadline:
                raise LinkError(f"{self.link.description}: device disconnected and not back within "
                                f"{_seconds(self.reconnect_timeout)}")
            time.sleep(delay)
            delay = min(delay * 2, 0.5)
        self.stats.reconnects += 1
        self._last_seq = None
        token = self._next_token()
        try:
            self.link.write(b"\0" + encode(Message("GET_INFO", {"token": token})))
        except LinkError:
            pass  # gone again: the next read notices


def _seconds(t: float) -> str:
    return f"{t:g} s"
