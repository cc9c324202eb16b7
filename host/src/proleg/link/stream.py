"""``MessageStream``: the robot's side of one ``Link``, as one stream of decoded messages.

The layer under ``RobotClient`` (``proleg.link.client``, which adds the commands): it writes
frames (``_write``), reads and decodes what comes back (``_pump``), queues it for ``recv``, and
files each reply that answers the command waiting on its token (``_waiting``; token *and*
command, ``reply_answers``) in ``_replies``, notifying ``_cond``. The only frames it sends
itself are the heartbeat's PINGs and the GET_INFO after a reconnect.

One decoded-message stream per robot: ``recv()`` returns every message the robot sent
(telemetry, events, replies) in order; a ``Notifier`` (``proleg.link.listeners``) pumps that
stream into listeners (console, recorder, printer, tests), none of which knows the link.

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
from collections.abc import Iterator

from ..errors import LinkError
from ..protocol.codec import FrameDecoder, Message, encode
from ..protocol.definition import BY_NAME, MESSAGES, Flag, MessageSpec, reply_answers
from .base import Link, LinkDisconnected
from .board_clock import BoardClockRate
from .received import LinkStats, Received
from .replies import RobotInfo

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


class MessageStream:
    """One robot's decoded-message stream; ``RobotClient`` gives the constructor's defaults."""

    def __init__(
        self,
        link: Link,
        *,
        reconnect_timeout: float,
        max_limbs: int,
        max_channels: int,
        poll_s: float,
        heartbeat_s: float | None,
        watchdog_ms: int | None,
    ):
        self.link = link
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
        #: the device stayed away a whole reconnect_timeout: later reconnects try once, not wait again
        self._gone = False
        self._closed = False
        self.heartbeat_s = heartbeat_s
        self.fit_heartbeat(watchdog_ms)
        self.heartbeats = 0  # PINGs sent by the heartbeat
        self._board_clock = BoardClockRate()  # a board at --speed 5 behind a pty counts 5× faster
        self._last_tx: float | None = None  # link clock of the last write (None: not connected yet)
        self._heartbeat_tokens: set[int] = set()

    # ------------------------------------------------------------------ lifecycle
    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.link.close()

    # ------------------------------------------------------------------ sending, heartbeat
    def fit_heartbeat(self, watchdog_ms: int | None) -> None:
        """Ping often enough for a link watchdog of ``watchdog_ms`` (the robot file's ``[safety]
        link_watchdog_ms``; None or 0: nothing to fit): at least ``WATCHDOG_SHARE`` times a
        period. A heartbeat that is off stays off."""
        if self.heartbeat_s is not None and watchdog_ms:
            self.heartbeat_s = min(self.heartbeat_s, watchdog_ms / 1000 / WATCHDOG_SHARE)

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

    def _heartbeat(self) -> float | None:
        """PING when nothing was written for ``heartbeat_s`` (keeps the link watchdog fed).
        Returns the link seconds until the next PING is due (None: no heartbeat), so that a
        read does not block past it: a read waiting 0.1 s for a slow TELEMETRY (7 Hz) let a
        100 ms watchdog trip between two PINGs."""
        period, last = self.heartbeat_s, self._last_tx
        if period is None or last is None or self._closed:
            return None
        period /= self.board_rate  # on the board's clock, as its watchdog counts
        due_in = period - (self.link.clock() - last)
        if due_in > _EPS:
            return due_in
        token = self._next_token()
        with self._cond:
            self._heartbeat_tokens.add(token)
        self.heartbeats += 1
        self._write(encode(Message("PING", {"token": token})))
        return period

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
        due_in = self._heartbeat()
        if due_in is not None:
            timeout = min(timeout, due_in)
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
        # Once the device has stayed away a whole reconnect_timeout, the commands that follow (the
        # console's STOP and ESTOP on leaving) try to reopen it once each: they waited 10 s each
        # again, and a console left 20-30 s after a pulled cable, saying nothing meanwhile.
        deadline = time.monotonic() + (0.0 if self._gone else self.reconnect_timeout)
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
                    self._gone = True
                    raise LinkError(
                        f"{self.link.description}: device disconnected and not back within "
                        f"{_seconds(self.reconnect_timeout)} ({e})"
                    ) from None
            if time.monotonic() >= deadline:
                self._gone = True
                raise LinkError(f"{self.link.description}: device disconnected and not back within "
                                f"{_seconds(self.reconnect_timeout)}")
            time.sleep(delay)
            delay = min(delay * 2, 0.5)
        self._gone = False
        self.stats.reconnects += 1
        self._last_seq = None
        token = self._next_token()
        try:
            self.link.write(b"\0" + encode(Message("GET_INFO", {"token": token})))
        except LinkError:
            pass  # gone again: the next read notices


def _seconds(t: float) -> str:
    return f"{t:g} s"
