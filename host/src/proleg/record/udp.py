"""Live telemetry over UDP into the tools people plot with, one datagram per TELEMETRY frame,
under the recordings' field names (``proleg.record.fields``):

- ``plotjuggler``: a JSON object per datagram (PlotJuggler's "UDP server" source with the JSON
  parser; tick "use field as timestamp" with ``timestamp``, the firmware time in seconds);
- ``teleplot``: Teleplot's lines ``>name:timestamp_ms:value``, one per field, newline-separated
  (Teleplot listens on UDP 47269 by default).

``UdpStreamer`` is a ``Listener``; a send that fails (no route, nobody listening on an ICMP-
answering host) is counted in ``errors`` and never stops the run.
"""

from __future__ import annotations

import socket
from typing import Any

from ..errors import LinkError, UsageError
from ..link.client import Received
from ..link.listeners import Listener
from ..protocol.enums import Flag
from .fields import RecordingMeta, dumps, telemetry_row

UDP_FORMATS = ("plotjuggler", "teleplot")
#: getaddrinfo's answers for a name that does not exist (not a DNS server that did not answer).
_NO_SUCH_HOST = {socket.EAI_NONAME, getattr(socket, "EAI_NODATA", socket.EAI_NONAME)}


def parse_endpoint(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) → (host, port)."""
    host, sep, port = text.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise UsageError(f"--udp {text}: expected HOST:PORT, e.g. 127.0.0.1:9870")
    return host, int(port)


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

    def __init__(self, endpoint: str, fmt: str, meta: RecordingMeta):
        if fmt not in FORMATTERS:
            raise UsageError(f"--udp-format {fmt}: expected one of {', '.join(UDP_FORMATS)}")
        self.host, self.port = parse_endpoint(endpoint)
        self.meta = meta
        self.format = fmt
        self.sent = 0
        self.errors = 0
        try:
            info = socket.getaddrinfo(self.host, self.port, type=socket.SOCK_DGRAM)[0]
            self._addr = info[4]
            self._sock: socket.socket | None = socket.socket(info[0], socket.SOCK_DGRAM)
        except socket.gaierror as e:
            if e.errno in _NO_SUCH_HOST:  # the argument names no host: a usage mistake, not a failed link
                raise UsageError(f"--udp {endpoint}: no host {self.host!r} ({e.strerror}); expected HOST:PORT of a "
                                 "host that resolves, e.g. 127.0.0.1:9870") from None
            raise LinkError(f"--udp {endpoint}: {e.strerror or e}") from None
        except OSError as e:
            raise LinkError(f"--udp {endpoint}: {e.strerror or e}") from None

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
        except OSError:
            self.errors += 1

    def stop(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
