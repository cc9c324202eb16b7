"""``RobotClient``: talk to one robot over any ``Link``.

``RobotClient`` is a ``MessageStream`` (``proleg.link.stream``: one decoded-message stream per
robot, TELEMETRY sequence checks, reconnecting, the heartbeat) plus the commands and the wait
for their replies. This module is the entry point: it re-exports what importers take from it
(``Received``, ``RobotInfo``, ``HEARTBEAT_S``...).

Commands carry a token (1..255) and wait for the reply echoing it; which message answers
which command comes from the protocol definition (``MessageSpec.reply``: INFO for GET_INFO,
STATS for GET_STATS, ACK otherwise; ``reply_answers``), so a reply is matched by token *and*
command: a stale ACK for another command that reused the token does not confirm a STOP or an
ESTOP. A NACK raises ``CommandRefused`` naming the error code; silence raises
``LinkError("no reply to PING within 0.5 s on /dev/ttyUSB0")``. Timeouts run on the link's
clock (virtual time on the simulated board). Replies are recognised whoever is reading:
the waiting command itself when nobody else is, the Notifier thread otherwise.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from types import TracebackType

from ..errors import LinkError
from ..names import counted
from ..robot_settings import MIN_LINK_WATCHDOG_MS
from ..protocol.codec import Message, encode
from ..protocol.definition import (
    BY_NAME,
    CHANNEL_CEILING,
    GAIT_USER,
    LIMB_CEILING,
    PROTOCOL_VERSION,
    DIR_UNSTATED,
    ClearWhat,
    Direction,
    ErrorCode,
    ParamId,
)
from .base import Link
from .direction import direction_code

# The reply values and the receive side's values live in their own modules; re-exported here so
# ``from proleg.link.client import RobotInfo, Received`` keeps working.
from .received import LinkStats, Received
from .replies import CommandRefused, FirmwareStats, ReplyTimeout, RobotInfo

# The stream under the commands; its constants are re-exported so
# ``from proleg.link.client import HEARTBEAT_S, WATCHDOG_SHARE`` keeps working.
from .stream import HEARTBEAT_S, KNOWN_STATE_WAIT_S, QUEUE_LIMIT, WATCHDOG_SHARE  # noqa: F401
from .stream import MessageStream, _EPS, _seconds

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


class RobotClient(MessageStream):
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
        super().__init__(
            link,
            reconnect_timeout=reconnect_timeout,
            max_limbs=max_limbs,
            max_channels=max_channels,
            poll_s=poll_s,
            heartbeat_s=heartbeat_s,
            watchdog_ms=watchdog_ms,
        )
        self.timeout = timeout

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
                        f"no reply to GET_INFO within {_seconds(within_s)} ({counted(tries, 'try')}) on {self.link.description}"
                        f"{self._garbled_hint()}"
                    ) from None
        if info.protocol_version != PROTOCOL_VERSION:
            raise LinkError(
                f"{self.link.description}: robot speaks protocol {info.protocol_version}, "
                f"this proleg speaks {PROTOCOL_VERSION} (rebuild the firmware or update proleg)"
            )
        return info

    def _garbled_hint(self) -> str:
        """Why no INFO came, when bytes did but no frame decoded: a board at another baud rate
        (a Nano flashed at 57600 opened at 115200), or another program on the port. Before, the
        error read as if the line were silent, and a lab looked for a pulled cable."""
        if self.stats.frames_ok or not self.stats.corrupt:
            return ""
        baud = getattr(self.link, "baudrate", None)
        other = f"a board at another baud rate than {baud} (--baudrate)" if baud else "a garbled link"
        return f" ({self.stats.corrupt} garbled frames came, none valid: {other}, or not proleg firmware?)"

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
        g = GAIT_USER if gait == "user" else _whole("START gait", gait)
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
        self.request("LOAD_GAIT", states=tuple(_whole("LOAD_GAIT state", s) for s in states))

    def set_param(self, param: ParamId | int | str, index: int, value: int) -> None:
        if isinstance(param, str):
            try:
                param = ParamId[param.upper()]
            except KeyError:
                raise LinkError(f"unknown parameter {param!r}; known: {', '.join(p.name.lower() for p in ParamId)}") from None
        what = f"SET_PARAM {param.name.lower() if isinstance(param, ParamId) else param}"
        unit = " in the parameter's unit (permyriad for a duty, ms for a time, 0.01° for an angle)"
        pid, v = _whole("SET_PARAM param", param), _whole(f"{what} value", value, unit)
        if pid == ParamId.LINK_WATCHDOG_MS and 0 < v < MIN_LINK_WATCHDOG_MS:
            # the board narrows its watchdog to any 1 ms or more, and the heartbeat would then ping
            # every quarter of it (a ping every 0.25 ms); proleg set-param refuses it alike
            raise LinkError(f"{what}: expected at least {MIN_LINK_WATCHDOG_MS} ms (as in a robot file), got {v}")
        self.request("SET_PARAM", param=pid, index=_whole(f"{what} index", index), value=v)
        if pid == ParamId.LINK_WATCHDOG_MS:
            self.fit_heartbeat(v)  # a shorter watchdog from here on

    def set_telemetry_rate(self, hz: int) -> None:
        self.request("SET_TELEMETRY_RATE", hz=_whole("SET_TELEMETRY_RATE hz", hz))

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


def _whole(what: str, value: object, unit: str = "") -> int:
    """``value`` as the whole number a command's field carries. A fraction is a LinkError, not
    truncated: ``set_param("hold_duty", 0, 0.3)`` (a duty as a fraction, not in permyriad) sent 0,
    a hold by bang-bang only, and the board acknowledged it; ``set_param("psi_star_cdeg", 0,
    20.5)`` moved ψ* to 0.20°; ``load_gait([0, 2.7])`` loaded state 2."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not float(value).is_integer():
        raise LinkError(f"{what}: expected a whole number{unit}, got {value!r}")
    return int(value)
