"""The writer and reader interfaces every recording format implements, and ``Recording``.

A ``Writer`` is a ``Listener`` (``proleg.link.listeners``): it gets every decoded message and
writes it at once (flushed per line or message), so a killed console loses at most the last
one (an MCAP at most its last chunk of 16 KiB: ``mcap_format.CHUNK_BYTES``). Writing never raises into the ``Notifier``'s thread: a failed write (a full disk...)
closes the writer and keeps the error in ``writer.error`` (a ``LinkError`` naming the file)
for the caller to report. ``mark(host_s, t_s, text)`` records a fault injection.
A ``Reader`` reads a file back into a ``Recording``; a missing or malformed file is a
``RecordingError`` naming the file and line (exit 2: a bad input file).
"""

from __future__ import annotations

import logging
import math
import os
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..errors import LinkError, RecordingError
from .. import interrupts
from ..link.client import Received
from ..link.listeners import Listener
from ..names import identifier, legacy_identifier
from ..paths import not_a_regular_file
from .fields import RecordingMeta, event_row, injection_row, telemetry_row

log = logging.getLogger(__name__)


def what_was_kept(recorder: "Writer | None", path: str | Path | None = None) -> str:
    """What an interrupted run's recording is: none, stopped earlier by an error, or kept
    whole up to the interruption (in ``path``, default the recorder's own)."""
    if recorder is None:
        return "nothing recorded"
    if recorder.error is not None:
        return f"the recording stopped earlier: {recorder.error}"
    return f"recording kept in {path if path is not None else recorder.path} (complete up to there)"


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
        self._held = False  # owes interrupts.release()
        self._created: list[tuple[Path, IO[Any]]] = []
        self._pending: dict[Path, Path] = {}  # a new file beside an earlier recording -> that recording
        try:
            self.open()
            self._held = interrupts.hold()  # from here a Ctrl-C lands between two rows (_guard), not inside one
            self._open = True
        except OSError as e:
            self._discard()
            name = self._pending.get(Path(e.filename), e.filename) if e.filename else self.path
            raise LinkError(f"cannot write record file {name}: {e.strerror or e}") from None
        except BaseException:  # Ctrl-C while the file is being created: no half-written header left
            self._let_go()
            self._discard()
            raise

    @classmethod
    def files(cls, path: Path) -> list[Path]:
        """Every file a recording at ``path`` is made of."""
        return [path]

    def _create(self, path: Path, mode: str = "w", **kw: Any) -> IO[Any]:
        """Open ``path`` for writing; ``open`` creates every file through this, so a failure
        part-way removes what it had created (nothing half-written is left). Where an earlier
        recording has that name, the new file is made beside it and takes its name with the
        first row (``_commit``): a session that never records (interrupted before START, a
        link that never came up) leaves the earlier one as it was."""
        if path.is_file() and not path.is_symlink():
            target, path = path, path.with_name(f".{path.name}.proleg-new")
            self._pending[path] = target
        f = open(path, mode, **kw)
        self._created.append((path, f))
        return f

    def _commit(self) -> None:
        """The new files take their names (replacing the earlier recording's)."""
        for new, target in self._pending.items():
            os.replace(new, target)
        self._created = [(self._pending.get(p, p), f) for p, f in self._created]
        self._pending = {}

    def _discard(self) -> None:
        for path, f in self._created:
            try:
                f.close()
            except OSError:
                pass
            if not path.is_symlink():  # the user's link (to a device...) stays
                path.unlink(missing_ok=True)
        self._pending = {}

    @abstractmethod
    def open(self) -> None:
        """Create the file(s) (with ``_create``) and write the metadata."""

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
            with interrupts.deferred():  # a Ctrl-C lands between two rows, not inside one
                write(row)
                self.records += 1
                if self._pending:
                    self._commit()
        except OSError as e:
            self.error = LinkError(f"cannot write record file {self.path}: {e.strerror or e}")
            self.stop()
            # said now: a console or run goes on, and the error line came only at its end
            log.warning("warning: %s: the recording stopped here (kept up to its last whole row); the session "
                        "goes on", self.error)

    def _let_go(self) -> None:
        if self._held:
            self._held = False
            interrupts.release()

    def discard(self) -> None:
        """Close and remove the recording (one of nothing: a run that never started)."""
        self._open = False
        self._let_go()
        self._discard()

    def stop(self) -> None:
        if self._open:
            try:
                with interrupts.deferred():  # the footer is written whole
                    self._open = False
                    self.close()
            except OSError as e:
                self.error = self.error or LinkError(f"cannot write record file {self.path}: {e.strerror or e}")
            finally:
                if self._pending:  # a session that ended with no row is still the recording asked for
                    self._commit()
                self._let_go()
        interrupts.settle()  # let go on a Notifier thread (a failed write): Python's handler is back now


class Reader(ABC):
    """One recording format's reader."""

    suffixes: tuple[str, ...] = ()

    def __init__(self, path: str | Path):
        self.path = Path(path)

    @abstractmethod
    def read(self) -> Recording: ...

    def _text(self, path: Path | None = None) -> str:
        p = path or self.path
        odd = not_a_regular_file(p)
        if odd:
            raise RecordingError(f"cannot read record file {p}: {odd}")
        try:
            return p.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise RecordingError(f"record file {p} does not exist") from None
        except (OSError, UnicodeDecodeError) as e:
            raise RecordingError(f"cannot read record file {p}: {getattr(e, 'strerror', None) or e}") from None


def write_row(f: IO[str], text: str) -> None:
    """Write one row (whole lines) and flush it. When the disk fills part-way through, the file
    is closed and cut back to its last whole row, so it reads back without a torn last line
    (before, a full disk left half a row there)."""
    start = f.tell()
    try:
        f.write(text)
        f.flush()
    except OSError:
        try:
            f.close()  # its buffered rest fails to flush again; the file is closed all the same
        except OSError:
            pass
        try:
            os.truncate(f.name, start)
        except (OSError, TypeError, ValueError):
            pass
        raise


def torn_last(where: str) -> None:
    """Say that a killed recorder's half-written last line is left out."""
    log.warning("warning: %s: torn last line dropped (the recording was cut short while writing it)", where)


def _shown(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _integer(where: str, r: dict[str, Any], k: str) -> int:
    v = r.get(k)
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) < 2**63:
        return v
    raise RecordingError(f"{where}: {k}: expected an integer, got {_shown(v)}")


#: The largest magnitude a recorded number has: firmware times reach 4.3e6 s, angles ±327.67°,
#: duties 100 %, a displacement or temperature far less. 1e308 in a damaged file was plotted,
#: numpy's "overflow encountered in multiply" warnings on stderr and exit 0.
MAX_RECORDED = 1e12


def _number(where: str, r: dict[str, Any], k: str, *, optional: bool = False) -> float:
    v = r.get(k)
    if optional and v is None:
        return math.nan
    expected = "a number or empty" if optional else "a finite number"
    if isinstance(v, (int, float)) and not isinstance(v, bool) and (optional or math.isfinite(v)):
        if (optional and math.isnan(v)) or abs(v) <= MAX_RECORDED:
            return float(v)
        raise RecordingError(f"{where}: {k}: expected {expected} within ±{MAX_RECORDED:g} (a damaged file?), "
                             f"got {_shown(v)}")
    raise RecordingError(f"{where}: {k}: expected {expected}, got {_shown(v)}")


def _column(rows: list[tuple[str, dict[str, Any]]], field: str, name: str, unit: str) -> str:
    """The column of limb or actuator ``name``: ``field_<identifier>_unit``, or, where no row
    has it, the name a recording made before identifiers kept other scripts' characters gave
    it (``names.legacy_identifier``)."""
    col = f"{field}_{identifier(name)}_{unit}"
    old = f"{field}_{legacy_identifier(name)}_{unit}"
    if old != col and not any(col in r for _, r in rows) and any(old in r for _, r in rows):
        return old
    return col


def _check_columns(path: Path, meta: RecordingMeta, rows: list[tuple[str, dict[str, Any]]], named: list[str]) -> None:
    """The ψ and duty columns the metadata names are the rows' own: a recording whose metadata
    is another's (a .meta.json copied or edited beside the CSV) was plotted without a word, a
    limb it does not name left out, one it names but no row has drawn as nothing."""
    def per_limb_or_coil(k: str) -> bool:
        return (k.startswith("psi_") and k.endswith("_deg")) or (k.startswith("duty_") and k.endswith("_pct"))

    missing = [c for c in named if not any(c in r for _, r in rows)]
    extra = sorted({k for _, r in rows for k in r if per_limb_or_coil(k)} - set(named))
    if missing or extra:
        names = (f"limbs {', '.join(meta.limb_names) or '(none)'} and actuators "
                 f"{', '.join(meta.channel_names) or '(none)'}")
        what = f"no row has a column {missing[0]}" if missing else f"its rows have a column {extra[0]} it does not name"
        raise RecordingError(f"{path}: its metadata names {names}, but {what}: the metadata is not this "
                             "recording's")


def event_time(where: str, e: dict[str, Any]) -> float | None:
    """An event's firmware time ``t_s`` (None for a reply, which has none)."""
    return None if e.get("t_s") is None else _number(where, e, "t_s")


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
    duty_pct: np.ndarray  # [frames, actuators] (the robot file's order: meta.channel_names)
    displacement_mm: np.ndarray | None
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def limbs(self) -> int:
        return int(self.psi_deg.shape[1])

    @property
    def channels(self) -> int:
        return int(self.duty_pct.shape[1])

    @classmethod
    def from_rows(cls, path: Path, meta: RecordingMeta, rows: list[tuple[str, dict[str, Any]]],
                  events: list[tuple[str, dict[str, Any]]]) -> Recording:
        """Assemble from telemetry rows named as ``meta.columns()`` says, each with where it
        came from (``file:line``) for the message when a value has the wrong type."""
        if not rows:
            raise RecordingError(f"{path}: no TELEMETRY frames in the recording")
        psi_cols = [_column(rows, "psi", n, "deg") for n in meta.limb_names]
        duty_cols = [_column(rows, "duty", n, "pct") for n in meta.channel_names]
        _check_columns(path, meta, rows, psi_cols + duty_cols)
        ints = {k: np.array([_integer(w, r, k) for w, r in rows], dtype=np.int64)
                for k in ("seq", "measured", "target", "step", "flags")}
        x = np.array([_number(w, r, "displacement_mm", optional=True) for w, r in rows], dtype=float)
        return cls(
            path=path, meta=meta, time_s=np.array([_number(w, r, "t_s") for w, r in rows]), **ints,
            psi_deg=cls._columns(rows, psi_cols), duty_pct=cls._columns(rows, duty_cols),
            displacement_mm=None if np.all(np.isnan(x)) else x,
            events=[{**e, "t_s": event_time(w, e)} for w, e in events],
        )

    @staticmethod
    def _columns(rows: list[tuple[str, dict[str, Any]]], names: list[str]) -> np.ndarray:
        values = [[_number(w, r, c, optional=True) for c in names] for w, r in rows]
        return np.array(values, dtype=float).reshape(len(rows), -1)
