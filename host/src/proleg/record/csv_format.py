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

from ..errors import RecordingError
from ..names import counted
from .base import Reader, Recording, Writer, torn_last, write_row
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

    @classmethod
    def files(cls, path: Path) -> list[Path]:
        return [path, events_path(path), meta_path(path)]

    def open(self) -> None:
        self._columns = self.meta.columns()
        self._tel: TextIO = self._create(self.path, encoding="utf-8", newline="")
        self._ev: TextIO = self._create(events_path(self.path), encoding="utf-8", newline="")
        with self._create(meta_path(self.path), encoding="utf-8") as f:
            f.write(json.dumps(self.meta.as_dict(), indent=1) + "\n")
        self._row(self._tel, self._columns)
        self._row(self._ev, list(EVENT_COLUMNS))

    @staticmethod
    def _row(f: TextIO, cells: list[Any]) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(cells)
        write_row(f, buf.getvalue())

    def write_telemetry(self, row: dict[str, Any]) -> None:
        self._row(self._tel, [_cell(row[c]) for c in self._columns])

    def write_event(self, row: dict[str, Any]) -> None:
        self._row(self._ev, [_cell(row[c]) for c in EVENT_COLUMNS])

    def close(self) -> None:
        for f in (self._tel, self._ev):
            f.close()


def _value(cell: str) -> Any:
    """A CSV cell as the JSON value it was written from: "" → None, an int, a float, else text."""
    if cell == "":
        return None
    for kind in (int, float):
        try:
            return kind(cell)
        except ValueError:
            pass
    return cell


class CsvReader(Reader):
    suffixes = (".csv",)

    def read(self) -> Recording:
        p = self.path
        text = self._text()
        mp = meta_path(p)
        if not mp.exists():
            raise RecordingError(f"{p}: not a proleg CSV recording (its metadata {mp.name} is missing)")
        try:
            meta = RecordingMeta.from_dict(json.loads(self._text(mp)))
        except ValueError as e:
            raise RecordingError(f"{mp}: not proleg recording metadata ({e})") from None
        header, rows = self._table(p, text)
        if "seq" not in header:
            raise RecordingError(f"{p}: not a proleg CSV recording (no 'seq' column in the first row)")
        telemetry = [(w, {k: _value(v) for k, v in r.items()}) for w, r in rows]
        events: list[tuple[str, dict[str, Any]]] = []
        ep = events_path(p)
        if ep.exists():
            # the numbers as numbers, as the JSONL and MCAP readers give them; msg, kind and text stay text
            events = [(w, {**r, **{k: _value(r[k]) for k in ("t_host_s", "t_s", "code", "detail") if k in r}})
                      for w, r in self._table(ep, self._text(ep))[1]]
        return Recording.from_rows(p, meta, telemetry, events)

    @staticmethod
    def _table(path: Path, text: str) -> tuple[list[str], list[tuple[str, dict[str, str]]]]:
        """The header and each row as {column: cell} with ``file:line``. Every row has the
        header's cells; a short last row with no newline after it (a killed recorder's) is
        dropped with a warning."""
        reader = csv.reader(io.StringIO(text, newline=""))
        lines = [(reader.line_num, cells) for cells in reader]
        if not lines:
            return [], []
        header = lines[0][1]
        rows = [(f"{path}:{n}", cells) for n, cells in lines[1:] if cells]
        if rows and len(rows[-1][1]) < len(header) and not text.endswith("\n"):
            torn_last(rows.pop()[0])
        for where, cells in rows:
            if len(cells) != len(header):
                raise RecordingError(f"{where}: {counted(len(cells), 'cell')}, expected {len(header)} as in the header")
        return header, [(w, dict(zip(header, cells))) for w, cells in rows]
