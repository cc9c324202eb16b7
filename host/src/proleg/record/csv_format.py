"""CSV: ``run.csv`` holds one row per TELEMETRY frame and nothing else, so
``pandas.read_csv("run.csv")`` reads it as it is (integer columns come back as int64);
``run.events.csv`` holds the other messages (EVENT, replies) and fault injections;
``run.meta.json`` the metadata (robot, board, firmware ids, limb names, ψ*, start time).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any, TextIO

from ..errors import LinkError
from .base import Reader, Recording, Writer
from .fields import EVENT_COLUMNS, RecordingMeta


def events_path(path: Path) -> Path:
    """``run.csv`` → ``run.events.csv``."""
    return path.with_name(f"{path.stem}.events{path.suffix}")


def meta_path(path: Path) -> Path:
    """``run.csv`` → ``run.meta.json``."""
    return path.with_name(f"{path.stem}.meta.json")


def _cell(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(round(v, 6))
    return v


class CsvWriter(Writer):
    suffixes = (".csv",)

    def open(self) -> None:
        self._columns = self.meta.columns()
        meta_path(self.path).write_text(json.dumps(self.meta.as_dict(), indent=1) + "\n", encoding="utf-8")
        self._tel: TextIO = open(self.path, "w", encoding="utf-8", newline="")
        self._ev: TextIO = open(events_path(self.path), "w", encoding="utf-8", newline="")
        self._row(self._tel, self._columns)
        self._row(self._ev, list(EVENT_COLUMNS))

    @staticmethod
    def _row(f: TextIO, cells: list[Any]) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(cells)
        f.write(buf.getvalue())
        f.flush()

    def write_telemetry(self, row: dict[str, Any]) -> None:
        self._row(self._tel, [_cell(row[c]) for c in self._columns])

    def write_event(self, row: dict[str, Any]) -> None:
        self._row(self._ev, [_cell(row[c]) for c in EVENT_COLUMNS])

    def close(self) -> None:
        for f in (self._tel, self._ev):
            f.close()


class CsvReader(Reader):
    suffixes = (".csv",)

    def read(self) -> Recording:
        p = self.path
        text = self._text()
        mp = meta_path(p)
        if not mp.exists():
            raise LinkError(f"{p}: not a proleg CSV recording (its metadata {mp.name} is missing)")
        try:
            meta = RecordingMeta.from_dict(json.loads(self._text(mp)))
        except (ValueError, TypeError, AttributeError) as e:
            raise LinkError(f"{mp}: not proleg recording metadata ({e})") from None
        reader = csv.DictReader(text.splitlines())
        if reader.fieldnames is None or "seq" not in reader.fieldnames:
            raise LinkError(f"{p}: not a proleg CSV recording (no 'seq' column in the first row)")
        rows = [r for r in reader if r.get("seq")]
        events: list[dict[str, Any]] = []
        ep = events_path(p)
        if ep.exists():
            for r in csv.DictReader(self._text(ep).splitlines()):
                r = dict(r)
                r["t_s"] = float(r["t_s"]) if r.get("t_s") else None
                events.append(r)
        return Recording.from_rows(p, meta, rows, events)
