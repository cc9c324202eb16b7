"""Live telemetry over UDP into the tools people plot with, one datagram per TELEMETRY frame,
under the recordings' field names (``proleg.record.fields``):

- ``plotjuggler``: a JSON object per datagram (PlotJuggler's "UDP server" source with the JSON
  parser; tick "use field as timestamp" with ``timestamp``, the firmware time in seconds);
- ``teleplot``: Teleplot's lines ``>name:timestamp_ms:value``, one per field, newline-separated
  (Teleplot listens on UDP 47269 by default).

``resolve_endpoint`` reads ``--udp HOST:PORT`` and resolves its host before a command opens
anything (``cli.main.udp_options``). ``UdpStreamer`` is a ``Listener``; a send that fails (no route, nobody listening on an ICMP-
answering host) is counted in ``errors`` and never stops the run; one that fails for another
reason than nobody listening is said once (a warning) for each reason.
"""

from __future__ import annotations

import errno
import logging
import socket
from dataclasses import dataclass
from typing import Any

from ..errors import LinkError, UsageError
from ..link.client import Received
from ..link.listeners import Listener
from ..protocol.enums import Flag
from .fields import RecordingMeta, dumps, telemetry_row

log = logging.getLogger("proleg")

UDP_FORMATS = ("plotjuggler", "teleplot")
#: getaddrinfo's answers for a name that does not exist (not a DNS server that did not answer).
_NO_SUCH_HOST = {socket.EAI_NONAME, getattr(socket, "EAI_NODATA", socket.EAI_NONAME)}


EXAMPLE = "expected HOST:PORT, e.g. 127.0.0.1:9870"


def parse_endpoint(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) → (host, port); a ``UsageError`` saying what is
    wrong with it."""
    host, sep, port = text.rpartition(":")
    host = host.strip()
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    port = port.strip()
    if not sep:
        raise UsageError(f"--udp {text}: no ':PORT' ({EXAMPLE})")
    if not host:
        raise UsageError(f"--udp {text}: no HOST before ':' ({EXAMPLE})")
    if not port:
        raise UsageError(f"--udp {text}: no PORT after ':' ({EXAMPLE})")
    if not port.isascii() or not port.isdigit():
        raise UsageError(f"--udp {text}: port {port!r} is not a number ({EXAMPLE})")
    if not 0 < int(port) < 65536:
        raise UsageError(f"--udp {text}: port {int(port)} is outside 1..65535 ({EXAMPLE})")
    return host, int(port)


@dataclass(frozen=True)
class UdpEndpoint:
    """``--udp HOST:PORT`` parsed and resolved (``resolve_endpoint``)."""

    text: str
    host: str
    port: int
    family: int
    address: tuple


def resolve_endpoint(text: str) -> UdpEndpoint:
    """``HOST:PORT`` parsed and its host resolved, before a command opens anything: a name that
    resolves to nothing was said only once the robot was connected (a recording created, left
    with its header alone). A name that does not exist, or a malformed endpoint, is a
    ``UsageError`` (exit 2); a resolver that cannot answer now a ``LinkError`` (exit 1)."""
    host, port = parse_endpoint(text)
    try:
        info = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)[0]
    except socket.gaierror as e:
        if e.errno in _NO_SUCH_HOST:  # the argument names no host: a usage mistake, not a failed link
            raise UsageError(f"--udp {text}: no host {host!r} ({e.strerror}); expected HOST:PORT of a host that "
                             "resolves, e.g. 127.0.0.1:9870") from None
        raise LinkError(f"--udp {text}: cannot resolve {host!r} now ({e.strerror or e}): is the network up? "
                        "(an IP address needs no resolver)") from None
    except UnicodeError:  # "a..b": no host name at all (its IDNA encoding fails)
        raise UsageError(f"--udp {text}: {host!r} is no host name; {EXAMPLE}") from None
    except OSError as e:
        raise LinkError(f"--udp {text}: cannot resolve {host!r} ({e.strerror or e})") from None
    return UdpEndpoint(text, host, port, info[0], info[4])


def plotjuggler_datagram(row: dict[str, Any]) -> bytes:
    return dumps({"timestamp": row["t_s"], **{k: v for k, v in row.items() if v is not None}}).encode()


def teleplot_datagram(row: dict[str, Any]) -> bytes:
    ms = round(row["t_s"] * 1000)
    lines = [f">{k}:{ms}:{v:g}" if isinstance(v, float) else f">{k}:{ms}:{v}"
             for k, v in row.items() if k not in ("t_s", "t_host_s") and v is not None]
    return "\n".join(lines).encode()


FORMATTERS = {"plotjuggler": plotjuggler_datagram, "teleplot": teleplot_datagram}


class UdpStreamer(Listener):
    """Sends every TELEMETRY frame to ``host:port`` in ``fmt`` (``UDP_FORMATS``)."""

    def __init__(self, endpoint: str | UdpEndpoint, fmt: str, meta: RecordingMeta):
        if fmt not in FORMATTERS:
            raise UsageError(f"--udp-format {fmt}: expected one of {', '.join(UDP_FORMATS)}")
        if isinstance(endpoint, str):
            endpoint = resolve_endpoint(endpoint)
        self.host, self.port = endpoint.host, endpoint.port
        self.meta = meta
        self.format = fmt
        self.sent = 0
        self.errors = 0
        self._addr = endpoint.address
        self._said: set[int] = set()
        try:
            self._sock: socket.socket | None = socket.socket(endpoint.family, socket.SOCK_DGRAM)
        except OSError as e:
            raise LinkError(f"--udp {endpoint.text}: {e.strerror or e}") from None
        if endpoint.family == socket.AF_INET:
            # a broadcast address (255.255.255.255, a subnet's .255: PlotJuggler on another
            # machine of the LAN) is sent to only with SO_BROADCAST; without it every send
            # failed with EACCES, nothing was streamed and nothing said so
            try:
                self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            except OSError:
                pass

    def on_message(self, rx: Received) -> None:
        if self._sock is None or rx.message.name != "TELEMETRY":
            return
        row = telemetry_row(self.meta, rx.time, rx.message.fields, rx.truth)
        if row["flags"] & Flag.STATE_UNKNOWN:
            del row["measured"]  # its placeholder (65535 at boot) is no state: a live plot would spike to it
        data = FORMATTERS[self.format](row)
        try:
            self._sock.sendto(data, self._addr)
            self.sent += 1
        except OSError as e:
            self.errors += 1
            if e.errno != errno.ECONNREFUSED and e.errno not in self._said:
                # nobody listening yet (an ICMP port unreachable) is the stream's ordinary lot;
                # any other failure means no datagram reaches the host: said once, the run goes on
                self._said.add(e.errno)
                log.warning("warning: --udp %s:%d: cannot send (%s): the stream does not reach it; the run goes on",
                            self.host, self.port, e.strerror or e)

    def stop(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
