"""JSON Lines: the first line ``{"msg": "META", ...metadata}``, then one object per message
with ``"msg"`` and the same field names and physical units as the CSV columns
(``pandas.read_json(path, lines=True)`` reads it; ``msg`` tells the rows apart).
"""

from __future__ import annotations

import json
from typing import Any, TextIO

from ..errors import RecordingError
from ..link.client import Received
from ..link.listeners import Listener
from .base import Reader, Recording, Writer, torn_last, write_row
from .fields import RecordingMeta, dumps, event_row, injection_row, telemetry_row


class JsonlWriter(Writer):
    suffixes = (".jsonl", ".ndjson")

    def open(self) -> None:
        self._f: TextIO = self._create(self.path, encoding="utf-8")
        self._line({"msg": "META", **self.meta.as_dict()})

    def _line(self, obj: dict[str, Any]) -> None:
        write_row(self._f, dumps(obj) + "\n")

    def write_telemetry(self, row: dict[str, Any]) -> None:
        self._line({"msg": "TELEMETRY", **row})

    def write_event(self, row: dict[str, Any]) -> None:
        self._line(row)

    def close(self) -> None:
        self._f.close()


class JsonlReader(Reader):
    suffixes = JsonlWriter.suffixes

    def read(self) -> Recording:
        p = self.path
        lines = self._text().splitlines()
        meta: RecordingMeta | None = None
        rows: list[tuple[str, dict[str, Any]]] = []
        events: list[tuple[str, dict[str, Any]]] = []
        for n, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                if n == len(lines):
                    torn_last(f"{p}:{n}")  # a killed recorder's last, half-written line
                    break
                raise RecordingError(f"{p}:{n}: not JSON") from None
            if not isinstance(obj, dict):
                raise RecordingError(f"{p}:{n}: expected a JSON object")
            msg = obj.get("msg")
            if msg == "META":
                meta = _meta(f"{p}:{n}", obj)
            elif msg == "TELEMETRY":
                rows.append((f"{p}:{n}", obj))
            elif msg:
                events.append((f"{p}:{n}", obj))
        if meta is None:
            raise RecordingError(f"{p}: not a proleg JSON Lines recording (no META line)")
        return Recording.from_rows(p, meta, rows, events)


def _meta(where: str, obj: dict[str, Any]) -> RecordingMeta:
    try:
        return RecordingMeta.from_dict(obj)
    except ValueError as e:
        raise RecordingError(f"{where}: not proleg recording metadata ({e})") from None


class JsonlPrinter(Listener):
    """Every message as one JSON line on a text stream (``--format jsonl``): the JSONL
    recording's objects without the META line. A reader that goes away (``| head``) closes it."""

    def __init__(self, meta: RecordingMeta, out: TextIO, *, telemetry_only: bool = False):
        self.meta = meta
        self.out = out
        self.telemetry_only = telemetry_only
        self.closed = False

    def on_message(self, rx: Received) -> None:
        if self.closed or (self.telemetry_only and rx.message.name != "TELEMETRY"):
            return
        m = rx.message
        if m.name == "TELEMETRY":
            obj = {"msg": "TELEMETRY", **telemetry_row(self.meta, rx.time, m.fields, rx.truth)}
        else:
            obj = event_row(rx.time, m.name, m.fields, self.meta)
        self._write(obj)

    def mark(self, host_s: float, t_s: float | None, text: str) -> None:
        """A fault the simulator injected: the JSONL recording's INJECT line."""
        if not self.closed and not self.telemetry_only:
            self._write(injection_row(host_s, t_s, text))

    def _write(self, obj: dict[str, Any]) -> None:
        try:
            self.out.write(dumps(obj) + "\n")
            self.out.flush()
        except BrokenPipeError:
            self.closed = True
