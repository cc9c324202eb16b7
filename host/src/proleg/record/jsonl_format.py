"""JSON Lines: the first line ``{"msg": "META", ...metadata}``, then one object per message
with ``"msg"`` and the same field names and physical units as the CSV columns
(``pandas.read_json(path, lines=True)`` reads it; ``msg`` tells the rows apart).
"""

from __future__ import annotations

import json
from typing import Any, TextIO

from ..errors import LinkError
from .base import Reader, Recording, Writer
from .fields import RecordingMeta, dumps


class JsonlWriter(Writer):
    suffixes = (".jsonl", ".ndjson")

    def open(self) -> None:
        self._f: TextIO = open(self.path, "w", encoding="utf-8")
        self._line({"msg": "META", **self.meta.as_dict()})

    def _line(self, obj: dict[str, Any]) -> None:
        self._f.write(dumps(obj) + "\n")
        self._f.flush()

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
        rows: list[dict[str, Any]] = []
        events: list[dict[str, Any]] = []
        for n, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                if n == len(lines):
                    break  # a killed recorder's last, half-written line
                raise LinkError(f"{p}:{n}: not JSON") from None
            if not isinstance(obj, dict):
                raise LinkError(f"{p}:{n}: expected a JSON object")
            msg = obj.get("msg")
            if msg == "META":
                meta = RecordingMeta.from_dict(obj)
            elif msg == "TELEMETRY":
                rows.append(obj)
            elif msg:
                events.append(obj)
        if meta is None:
            raise LinkError(f"{p}: not a proleg JSON Lines recording (no META line)")
        return Recording.from_rows(p, meta, rows, events)
