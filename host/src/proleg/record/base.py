"""The writer and reader interfaces every recording format implements, and ``Recording``.

A ``Writer`` is a ``Listener`` (``proleg.link.listeners``): it gets every decoded message and
writes it at once (flushed per line or message), so a killed console loses at most the last
one. Writing never raises into the ``Notifier``'s thread: a failed write (a full disk...)
closes the writer and keeps the error in ``writer.error`` (a ``LinkError`` naming the file)
for the caller to report. ``mark(host_s, t_s, text)`` records a fault injection.
A ``Reader`` reads a file back into a ``Recording``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import LinkError
from ..link.client import Received
from ..link.listeners import Listener
from ..names import identifier
from .fields import RecordingMeta, event_row, injection_row, telemetry_row


class Writer(Listener, ABC):
    """One recording format's writer (subclasses: ``open``, ``write_telemetry``, ``write_event``,
    ``close``)."""

    #: file suffixes this writer is chosen for (lower case, with the dot)
    suffixes: tuple[str, ...] = ()

    def __init__(self, path: str | Path, meta: RecordingMeta):
        self.path = Path(path)
        self.meta = meta
        self.error: LinkError | None = None
        self.records = 0
        self._open = False
        try:
            self.open()
            self._open = True
        except OSError as e:
            raise LinkError(f"cannot write record file {self.path}: {e.strerror or e}") from None

    @abstractmethod
    def open(self) -> None:
        """Create the file(s) and write the metadata."""

    @abstractmethod
    def write_telemetry(self, row: dict[str, Any]) -> None: ...

    @abstractmethod
    def write_event(self, row: dict[str, Any]) -> None: ...

    @abstractmethod
    def close(self) -> None: ...

    def on_message(self, rx: Received) -> None:
        m = rx.message
        if m.name == "TELEMETRY":
            self._guard(self.write_telemetry, telemetry_row(self.meta, rx.time, m.fields, rx.truth))
        else:
            self._guard(self.write_event, event_row(rx.time, m.name, m.fields, self.meta))

    def mark(self, host_s: float, t_s: float | None, text: str) -> None:
        """Record a fault injected by the simulator (plots draw it as a marker)."""
        self._guard(self.write_event, injection_row(host_s, t_s, text))

    def _guard(self, write: Any, row: dict[str, Any]) -> None:
        if not self._open:
            return
        try:
            write(row)
            self.records += 1
        except OSError as e:
            self.error = LinkError(f"cannot write record file {self.path}: {e.strerror or e}")
            self.stop()

    def stop(self) -> None:
        if self._open:
            self._open = False
            try:
                self.close()
            except OSError as e:
                self.error = self.error or LinkError(f"cannot write record file {self.path}: {e.strerror or e}")


class Reader(ABC):
    """One recording format's reader."""

    suffixes: tuple[str, ...] = ()

    def __init__(self, path: str | Path):
        self.path = Path(path)

    @abstractmethod
    def read(self) -> Recording: ...

    def _text(self, path: Path | None = None) -> str:
        p = path or self.path
        try:
            return p.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise LinkError(f"record file {p} does not exist") from None
        except (OSError, UnicodeDecodeError) as e:
            raise LinkError(f"cannot read record file {p}: {getattr(e, 'strerror', None) or e}") from None


@dataclass
class Recording:
    """A recording's telemetry as arrays (firmware time in s, ψ in degrees, duty in %) and its
    events (dicts with the events-table columns, ``proleg.record.fields.EVENT_COLUMNS``)."""

    path: Path
    meta: RecordingMeta
    time_s: np.ndarray
    seq: np.ndarray
    measured: np.ndarray
    target: np.ndarray
    step: np.ndarray
    flags: np.ndarray
    psi_deg: np.ndarray  # [frames, limbs]
    duty_pct: np.ndarray  # [frames, channels]
    displacement_mm: np.ndarray | None
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def limbs(self) -> int:
        return int(self.psi_deg.shape[1])

    @property
    def channels(self) -> int:
        return int(self.duty_pct.shape[1])

    @classmethod
    def from_rows(cls, path: Path, meta: RecordingMeta, rows: list[dict[str, Any]],
                  events: list[dict[str, Any]]) -> Recording:
        """Assemble from telemetry rows named as ``meta.columns()`` says."""
        if not rows:
            raise LinkError(f"{path}: no TELEMETRY frames in the recording")
        psi_cols = [f"psi_{identifier(n)}_deg" for n in meta.limb_names]
        duty_cols = [f"duty_{identifier(n)}_pct" for n in meta.channel_names]

        def num(r: dict[str, Any], k: str) -> float:
            v = r.get(k)
            return math.nan if v is None or v == "" else float(v)

        try:
            ints = {k: np.array([int(r[k]) for r in rows], dtype=np.int64)
                    for k in ("seq", "measured", "target", "step", "flags")}
            x = np.array([num(r, "displacement_mm") for r in rows], dtype=float)
            return cls(
                path=path, meta=meta, time_s=np.array([float(r["t_s"]) for r in rows]), **ints,
                psi_deg=np.array([[num(r, c) for c in psi_cols] for r in rows], dtype=float).reshape(len(rows), -1),
                duty_pct=np.array([[num(r, c) for c in duty_cols] for r in rows], dtype=float).reshape(len(rows), -1),
                displacement_mm=None if np.all(np.isnan(x)) else x, events=events,
            )
        except (KeyError, TypeError, ValueError) as e:
            raise LinkError(f"{path}: malformed telemetry ({e.__class__.__name__}: {e})") from None
