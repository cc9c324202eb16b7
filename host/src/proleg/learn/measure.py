"""Trial logs: one JSON line per completed transition, appended and flushed as it happens.

A record holds the transition (``from``/``to`` as state labels), the firmware's event
times of its start and end (seconds, the firmware's clock), the planar motion in the
robot's start frame when the position source knows it (``dx``, ``dy`` in the robot file's
units, ``dtheta_deg``), where the numbers came from (``source``: "sim", "tracker",
"manual", …) and, when the firmware's telemetry showed it, ``t_seen``: the firmware time at
which the measured (debounced) state first became ``to``. ``t_end`` is the STATE_REACHED
event, which the ψ-feedback controller sends only once every limb has settled clear of
its band edges — for a limb that cools, up to ~0.6 s after the friction change that moved
the robot; ``t_seen`` is within a telemetry period (+ the debounce) of that change, so it
is what a tracker's clock is aligned with (``tracker.estimate_offset``), while the pose is
read after ``t_end`` (settled). Example line::

    {"from": "00", "to": "10", "t_start": 1.204, "t_end": 1.951, "dx": 3.98, "dy": null,
     "dtheta_deg": null, "source": "sim"}

A transition the robot faulted on while making it (STATE_TIMEOUT, the on-time limit) is a
line of its own, a ``Failure``: ``fault`` says what the firmware reported, ``t_fault`` when
(firmware seconds)::

    {"from": "10", "to": "11", "t_fault": 12.31, "fault": "FAULT STATE_TIMEOUT on right"}

``TrialLog`` reopens an existing log and keeps everything in it: a run interrupted halfway
continues with ``remaining`` (what is still to do), and nothing recorded is lost — each
record is written, flushed and fsync'ed before the next transition is measured. A torn
last line (the process died mid-write, so no newline follows it) is dropped with a warning
and overwritten; any other line that is not a record is an error naming it. Opened with
``append=False`` (a report) the file is only read.
"""

from __future__ import annotations

import errno
import json
import math
import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..robot_entries import is_duration
from ..states import limb_levels
from ..transitions import TransitionTable
from ..typed import typed_float


class TrialLogError(ValueError):
    """A trial log line that is not a record (other than a torn last line)."""


@dataclass(frozen=True)
class Trial:
    src: str
    dst: str
    t_start: float
    t_end: float
    dx: float | None = None
    dy: float | None = None
    dtheta_deg: float | None = None
    source: str = ""
    t_seen: float | None = None  # firmware time the measured state first became dst (≤ t_end)
    passed: tuple[str, ...] = ()  # states outside src..dst the telemetry showed on the way

    @property
    def duration_s(self) -> float | None:
        """How long the firmware took to make the transition (``t_end`` − ``t_start``: until it
        reported the state reached, as a gait's step takes), None when the clock says nothing
        (a log with the two equal, or a clock that stepped back) or nothing a robot file takes
        (``robot_entries.is_duration``: the learned file must load)."""
        d = self.t_end - self.t_start
        return d if is_duration(d) else None

    @property
    def t_moved(self) -> float:
        """Best firmware time of the transition's last motion: ``t_seen``, else ``t_end``."""
        return self.t_end if self.t_seen is None else self.t_seen

    def to_json(self) -> str:
        d = asdict(self)
        d["from"], d["to"] = d.pop("src"), d.pop("dst")
        order = ["from", "to", "t_start", "t_end", "dx", "dy", "dtheta_deg", "source"]
        if self.t_seen is not None:
            order.append("t_seen")
        if self.passed:
            d["passed"] = list(self.passed)
            order.append("passed")
        return json.dumps({k: d[k] for k in order}, ensure_ascii=False)

    @classmethod
    def from_json(cls, line: str, where: str = "") -> Trial:
        """A record from its JSON line; ``TrialLogError`` naming ``where`` and the field."""
        try:
            d = json.loads(line)
        except ValueError:
            d = None
        if not isinstance(d, dict):
            raise TrialLogError(f"{where}: expected a trial record (a JSON object with from, to, t_start, t_end, "
                                f"dx…), got {line.strip()[:40]!r}")
        try:
            return cls(_label(d, "from"), _label(d, "to"), _number(d, "t_start", True), _number(d, "t_end", True),
                       _number(d, "dx"), _number(d, "dy"), _number(d, "dtheta_deg"), _source(d),
                       _number(d, "t_seen"), _labels(d.get("passed", [])))
        except ValueError as e:
            raise TrialLogError(f"{where}: {e}") from None


@dataclass(frozen=True)
class Failure:
    """A transition the robot could not make: it faulted while making it (``runner.Explorer``
    records one, and asks for the transition no more; the report writes it "x")."""

    src: str
    dst: str
    t_fault: float | None
    fault: str  # what the firmware reported, e.g. "FAULT STATE_TIMEOUT on mid"

    def to_json(self) -> str:
        return json.dumps({"from": self.src, "to": self.dst, "t_fault": self.t_fault, "fault": self.fault},
                          ensure_ascii=False)

    @classmethod
    def from_dict(cls, d: dict) -> Failure:
        if not isinstance(d["fault"], str):
            raise ValueError(f"fault: expected what the firmware reported (a string), got {d['fault']!r}")
        return cls(_label(d, "from"), _label(d, "to"), _number(d, "t_fault"), d["fault"])


def _record(line: str, where: str) -> Trial | Failure:
    """A trial, or a failure (a line with ``fault``), from its JSON line."""
    try:
        d = json.loads(line)
    except ValueError:
        d = None
    if isinstance(d, dict) and "fault" in d:
        try:
            return Failure.from_dict(d)
        except ValueError as e:
            raise TrialLogError(f"{where}: {e}") from None
    return Trial.from_json(line, where)


#: where a trial's motion came from ("" or no key: not said)
SOURCES = ("sim", "tracker", "manual")
#: the largest magnitude a trial's number may have (a motion or a time; 1e9 mm is 1000 km)
MAX_ABS = 1e9
_MAX_TEXT = "1e9"


def _label(d: dict, key: str) -> str:
    if key not in d:
        raise ValueError(f"{key}: missing (expected a state label)")
    if not isinstance(d[key], str):
        raise ValueError(f"{key}: expected a state label (a string), got {d[key]!r}")
    return d[key]


def _number(d: dict, key: str, required: bool = False) -> float | None:
    v = d.get(key)
    if v is None and not required:
        return None
    if key not in d:
        raise ValueError(f"{key}: missing (expected a number)")
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not abs(v) <= MAX_ABS:
        raise ValueError(f"{key}: expected a number within ±{_MAX_TEXT}{'' if required else ' or null'}, got {v!r}")
    return float(v)


def _source(d: dict) -> str:
    v = d.get("source", "")
    if v != "" and v not in SOURCES:
        raise ValueError(f"source: expected one of {', '.join(SOURCES)}, got {v!r}")
    return v


def _labels(v) -> tuple[str, ...]:
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        raise ValueError(f"passed: expected a list of state labels, got {v!r}")
    return tuple(v)


class TrialLog:
    """An append-only JSONL trial log (see the module docstring)."""

    def __init__(self, path: str | Path, *, append: bool = True, robot: str | None = None,
                 states: Iterable[str] | None = None, transitions: Iterable[tuple[str, str]] | None = None,
                 levels: Sequence[int] | None = None):
        """``append=False`` only reads: the file is never opened for writing, created or
        shortened (a torn last line is skipped, with the same warning).

        ``robot``: the log must be this robot's: a log whose first line names another
        (``{"trial_log": 1, "robot": …}``, written when a log is started for a robot) is an
        error, and a new log starts with that line. ``states``: every record's from/to must
        be one of them (a log of another robot, or not a trial log, is an error naming the
        line). ``transitions``: the (from, to) pairs a record may have (the robot's allowed
        transitions); any other is an error naming the line. ``levels``: each limb's levels, kept
        in a new log's first line; a log whose first line gives others is an error (its labels
        name other states: a limb given a third level keeps ``001`` a label, but of another
        state, and its trials were mixed in without a word)."""
        self.path = Path(path)
        self.trials: list[Trial] = []
        self.failures: list[Failure] = []  # transitions the robot faulted on (``Failure``)
        self.robot: str | None = None
        self._good_bytes = 0
        self._fh = None
        self._states = None if states is None else frozenset(states)
        self._pairs = None if transitions is None else frozenset(transitions)
        if self.path.exists():
            if not self.path.is_file():  # a device read to its end never ends (/dev/zero)
                raise OSError(errno.EINVAL, "not a regular file (a device, pipe or socket)", str(self.path))
            self._read(append, robot, levels)
        if not append:
            return
        self._fh = open(self.path, "r+b" if self.path.exists() else "wb")
        self._fh.truncate(self._good_bytes)  # drop a torn last line
        self._fh.seek(self._good_bytes)
        if self._good_bytes == 0 and robot is not None:  # a new (or empty) log: say whose it is
            head: dict[str, Any] = {"trial_log": 1, "robot": robot}
            if levels is not None:
                head["levels"] = [int(k) for k in levels]
            self._fh.write(json.dumps(head, ensure_ascii=False).encode("utf-8") + b"\n")
            self._fh.flush()
            self.robot = robot

    def _read(self, append: bool, robot: str | None, levels: Sequence[int] | None) -> None:
        data = self.path.read_bytes()
        pos = len(_BOM) if data.startswith(_BOM) else 0  # a log saved by Notepad starts with one
        lines = data[pos:].split(b"\n")
        for k, raw in enumerate(lines):
            last = k == len(lines) - 1
            where = f"{self.path}:{k + 1}"
            if not raw.strip():
                pos += len(raw) + (0 if last else 1)
                if not last:
                    self._good_bytes = pos
                continue
            if k == 0 and not self.trials and (header := _header(raw, where)) is not None:
                name, logged = header
                if robot is not None and name != robot:
                    raise TrialLogError(f"{self.path}: a trial log of {name}, not of {robot} (its first line says so)")
                if levels is not None and logged is not None and list(logged) != list(levels):
                    raise TrialLogError(
                        f"{self.path}: a trial log of {name} with limb levels {','.join(map(str, logged))}, but the "
                        f"robot file has {','.join(map(str, levels))} (its first line says so): its state labels "
                        "name other states; start a new log")
                self.robot = name
                pos += len(raw) + (0 if last else 1)
                self._good_bytes = pos if not last else 0
                continue
            try:
                trial = _record(_text(raw, where), where)
            except TrialLogError:
                if last:  # no newline after it: a write cut short (a whole line is no torn record)
                    warnings.warn(f"{where}: torn last record {'dropped' if append else 'skipped'} "
                                  "(the run was interrupted while writing it)", stacklevel=3)
                    return
                raise
            self._check(trial, where)
            if last:  # complete JSON but no newline: keep it, add the newline on the next append
                self._keep(trial)
                self._good_bytes = pos + len(raw)
                self._needs_newline = True
                return
            self._keep(trial)
            pos += len(raw) + 1
            self._good_bytes = pos

    def _keep(self, record: Trial | Failure) -> None:
        (self.failures if isinstance(record, Failure) else self.trials).append(record)

    def _check(self, trial: Trial | Failure, where: str) -> None:
        """A record's states are the robot's, and its transition one the robot may make."""
        if self._states is not None and not {trial.src, trial.dst} <= self._states:
            field, bad = ("from", trial.src) if trial.src not in self._states else ("to", trial.dst)
            raise TrialLogError(f"{where}: {field}: state {bad!r} is not one of the robot's (a log of "
                                "another robot?)")
        if self._pairs is not None and (trial.src, trial.dst) not in self._pairs:
            raise TrialLogError(f"{where}: from/to: {trial.src}->{trial.dst} is not one of the robot's allowed "
                                "transitions (no change of state, or marked \"x\" in its matrix)")

    _needs_newline = False

    def append(self, trial: Trial | Failure) -> None:
        """Write one record (a trial or a failure), flushed and fsync'ed, and keep it."""
        if self._fh is None:
            raise TrialLogError(f"{self.path}: opened to read only")
        prefix = b"\n" if self._needs_newline else b""
        start = self._fh.tell()
        try:
            self._fh.write(prefix + trial.to_json().encode("utf-8") + b"\n")
            self._fh.flush()
            os.fsync(self._fh.fileno())
        except OSError as e:  # a full disk: the log is cut back to its last whole trial, and named
            fh, self._fh = self._fh, None
            try:
                fh.close()
            except OSError:
                pass
            try:
                os.truncate(self.path, start)
            except OSError:
                pass
            raise OSError(e.errno, e.strerror, str(self.path)) from None
        self._needs_newline = False
        self._keep(trial)

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()

    def __enter__(self) -> TrialLog:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: The UTF-8 byte order mark some editors (Notepad) put at the start of a text file.
_BOM = b"\xef\xbb\xbf"


def _text(raw: bytes, where: str) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise TrialLogError(f"{where}: expected UTF-8 text, got byte {raw[e.start]:#04x} at column {e.start + 1}") from None


def _header(raw: bytes, where: str) -> tuple[str, list[int] | None] | None:
    """The robot a log's first line names (``{"trial_log": 1, "robot": …, "levels": […]}``) and
    its limbs' levels (None in a log written before they were kept), or None when the line is
    no header; ``TrialLogError`` for a header of another format version."""
    try:
        d = json.loads(raw.decode("utf-8"))
    except (ValueError, UnicodeDecodeError):
        return None
    if not isinstance(d, dict) or "trial_log" not in d:
        return None
    version = d["trial_log"]
    if isinstance(version, bool) or version != 1:
        raise TrialLogError(f"{where}: trial_log: expected 1 (the format this proleg reads), got {version!r}")
    if not isinstance(d.get("robot"), str):
        raise TrialLogError(f"{where}: robot: expected the robot's name, got {d.get('robot')!r}")
    levels = d.get("levels")
    if levels is not None and not (isinstance(levels, list) and all(
            isinstance(k, int) and not isinstance(k, bool) and k >= 2 for k in levels)):
        raise TrialLogError(f"{where}: levels: expected each limb's levels, whole numbers ≥ 2, got {levels!r}")
    return d["robot"], levels


def counts(table: TransitionTable, trials: Iterable[Trial]) -> np.ndarray:
    """Trials per allowed transition (aligned with ``table.src``); unknown pairs are ignored."""
    out = np.zeros(table.n_transitions, dtype=np.int64)
    for t in trials:
        try:
            e = table.lookup(table.index(t.src), table.index(t.dst))
        except (ValueError, KeyError):
            continue
        if e is not None:
            out[e] += 1
    return out


def remaining(table: TransitionTable, trials: Iterable[Trial], repeats: int) -> np.ndarray:
    """How many more trials each allowed transition needs to reach ``repeats``."""
    return np.maximum(0, repeats - counts(table, trials))


# ------------------------------------------------------------------------- position sources
Pose = tuple[float | None, float | None, float | None]  # x, y, θ (degrees); None = unknown


def planar_delta(p0: Pose, p1: Pose) -> Pose:
    """Motion from pose p0 to p1 in p0's frame (x forward). With no θ, the world Δx/Δy."""
    x0, y0, th0 = p0
    x1, y1, th1 = p1
    if x0 is None or x1 is None:
        return None, None, None
    wx = x1 - x0
    wy = None if y0 is None or y1 is None else y1 - y0
    if th0 is None or th1 is None:
        return wx, wy, None
    c, s = math.cos(math.radians(th0)), math.sin(math.radians(th0))
    wy0 = wy or 0.0
    dth = (th1 - th0 + 180.0) % 360.0 - 180.0
    return c * wx + s * wy0, -s * wx + c * wy0, dth


class GroundTruthSource:
    """The simulator's ground truth: ``pose()`` returns (x, y, θ) now (any may be None)."""

    name = "sim"

    def __init__(self, pose: Callable[[], Pose]):
        self.pose = pose


def manual_trial(src: str, dst: str, t_start: float, t_end: float, *,
                 ask: Callable[[str], str] = input, units: str = "mm", planar: bool = False) -> Trial | None:
    """The paper's visual method: ask the operator for the transition's motion. Answers:
    ``Δx`` (or ``Δx Δy Δθ`` with ``planar``), empty to skip the trial, and a clear line is
    asked again on anything else. ``ask`` is injectable (tests, a GUI)."""
    what = f"Δx Δy [{units}] Δθ [deg]" if planar else f"Δx [{units}]"
    prompt = f"{src} → {dst}: {what} (empty = skip): "
    while True:
        typed = ask(prompt).strip()
        text = typed.replace(",", " ")
        if not text:
            return None
        parts = text.split()
        try:
            vals = [typed_float(p) for p in parts]
        except ValueError:
            prompt = f"  not a number ({text!r}); {src} → {dst}: {what}: "
            continue
        if len(vals) == 1 or (planar and len(vals) == 3):
            if all(math.isfinite(v) and abs(v) <= MAX_ABS for v in vals):  # what the log can read back
                vals += [None, None] * (len(vals) == 1)  # type: ignore[list-item]
                return Trial(src, dst, t_start, t_end, vals[0], vals[1], vals[2], "manual")
            prompt = f"  expected numbers within ±{_MAX_TEXT} ({text!r}); {src} → {dst}: {what}: "
            continue
        comma = " (a comma separates Δx Δy Δθ: a decimal point is '.')" if "," in typed else ""
        prompt = f"  expected {what}{comma}, got {typed!r}; {src} → {dst}: "


def psi_state(robot: Any, psi_centideg) -> int:
    """The state ψ alone says, without the hysteresis band: each limb's level is how many of
    its ψ* it is at or past (telemetry's ψ, 0.01°). A sag across ψ* that stays inside the band
    changes this and not the measured state."""
    index = 0
    for limb, k, psi in zip(robot.limbs, robot.levels, psi_centideg):
        level = sum(1 for star in limb.psi_star_deg if psi >= round(star * 100))
        index = index * k + level
    return index


def between_levels(levels: tuple[int, ...], a: int, b: int, s: int) -> bool:
    """Is every limb of state ``s`` at a level between its levels in ``a`` and in ``b`` (the
    states a → b may pass through when the limbs it changes cross one by one)?"""
    la, lb, ls = limb_levels(a, levels), limb_levels(b, levels), limb_levels(s, levels)
    return all(min(x, y) <= z <= max(x, y) for x, y, z in zip(la, lb, ls))
