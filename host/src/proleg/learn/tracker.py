"""External tracker files (overhead camera, motion capture) and their clock offset.

Format (docs/learning.md, example docs/examples/tracker-example.csv): CSV with a header
``time,x,y,theta``; ``time`` in seconds on the tracker's clock (any origin, increasing),
``x``/``y`` in the robot file's units (mm usually) in the world frame, ``theta`` the
heading in degrees (x forward); ``y`` and ``theta`` may be left empty. Lines starting with
``#`` are comments.

The firmware stamps its events on its own clock; the tracker has another. The offset
(tracker time = firmware time + offset) comes from a sync event when the lab has one
(e.g. a LED flash seen by the camera), or is estimated by ``estimate_offset``: the robot
moves only during transitions, so the offset that puts the most tracked motion inside the
firmware's transition intervals (and the least outside) is the one that aligns the clocks.
It is searched on a grid (``step_s``) over ``±max_offset_s`` and then refined.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from ..paths import not_a_regular_file
from ..typed import typed_float


class TrackerError(ValueError):
    """A tracker file that does not follow the documented format."""


@dataclass(frozen=True)
class Track:
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray | None = None
    theta_deg: np.ndarray | None = None

    def covers(self, t: float) -> bool:
        """Tracker time ``t`` lies within the track and in no gap of it (a pose there is
        measured, not made up)."""
        return bool(self.t[0] <= t <= self.t[-1]) and self.gap_around(t) is None

    @cached_property
    def max_frame_gap_s(self) -> float:
        """The longest time between two rows that still gives a pose between them: ``GAP_FRAMES``
        of the track's median frame interval. Longer, the camera lost the robot (or dropped
        frames) and a pose there would be interpolated across whatever it did meanwhile."""
        return GAP_FRAMES * float(np.median(np.diff(self.t)))

    def gap_around(self, t: float) -> tuple[float, float] | None:
        """The times of the rows around tracker time ``t`` when they are further apart than
        ``max_frame_gap_s`` (no pose there), else None (a row at ``t`` is never in a gap)."""
        k = int(np.searchsorted(self.t, t, side="left"))
        if k >= len(self.t) or k == 0 or self.t[k] == t:
            return None
        a, b = float(self.t[k - 1]), float(self.t[k])
        return (a, b) if b - a > self.max_frame_gap_s else None

    def pose(self, t: float) -> tuple[float | None, float | None, float | None]:
        """Linear interpolation at tracker time ``t`` (clamped to the ends: ask ``covers``
        first where a pose past them would be a motion of zero that was never measured)."""
        x = float(np.interp(t, self.t, self.x))
        y = None if self.y is None else float(np.interp(t, self.t, self.y))
        th = None if self.theta_deg is None else float(np.interp(t, self.t, np.unwrap(self.theta_deg, period=360.0)))
        return x, y, th


COLUMNS = ("time", "x", "y", "theta")
#: rows further apart than this many of the track's median frame intervals leave a gap: no pose
#: between them (``Track.gap_around``)
GAP_FRAMES = 5
#: the largest magnitude a tracker number may have (seconds or the robot file's unit)
MAX_ABS = 1e9
_MAX_TEXT = "1e9"


def read_track(path: str | Path) -> Track:
    """The track in ``path`` (module docstring); ``TrackerError`` naming the file, the line
    (as an editor counts it, comments included) and the column."""
    path = Path(path)
    rows = _rows(path)
    header = [c.strip() for c in rows[0][1]] if rows else []
    # time,x alone is a header as the rows may be (a tracker along x); a fifth column is not read,
    # so it is refused here and not on every row after (it passed, and each row failed)
    if not 2 <= len(header) <= 4 or header != list(COLUMNS[:len(header)]):
        where = f"line {rows[0][0]}" if rows else "line 1"
        got = f", got {','.join(header)!r}" if rows else ""
        raise TrackerError(f"{path}: {where}: expected the header time,x,y,theta (or time,x or time,x,y){got}")
    cols: list[list[float | None]] = [[], [], [], []]
    shape = ",".join(COLUMNS[:2]) + "".join(f"[,{c}" for c in COLUMNS[2:len(header)]) + "]" * (len(header) - 2)
    for k, row in rows[1:]:
        if len(row) < 2 or len(row) > len(header):
            raise TrackerError(f"{path}: line {k}: expected {shape} as the header says, got {','.join(row)!r}")
        for j, cell in enumerate(row + [""] * (4 - len(row))):
            cols[j].append(_cell(cell.strip(), j, f"{path}: line {k}"))
    t = np.array(cols[0], dtype=float)
    if len(t) < 2:
        raise TrackerError(f"{path}: expected at least two rows of time,x[,y[,theta]] after the header, "
                           f"got {len(t)}")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        k = int(back[0]) + 1  # the first row whose time does not increase
        raise TrackerError(f"{path}: line {rows[k + 1][0]}, column time: expected a time after the previous "
                           f"row's {t[k - 1]:g} s (strictly increasing), got {t[k]:g}")

    def opt(c: list[float | None], j: int) -> np.ndarray | None:
        if all(v is None for v in c):
            return None
        if any(v is None for v in c):
            given = next(i for i, v in enumerate(c) if v is not None)
            empty = next(i for i, v in enumerate(c) if v is None)
            raise TrackerError(f"{path}: line {rows[empty + 1][0]}, column {COLUMNS[j]}: empty, but given on line "
                               f"{rows[given + 1][0]} (give it on every row or none)")
        return np.array(c, dtype=float)

    return Track(t, np.array(cols[1], dtype=float), opt(cols[2], 2), opt(cols[3], 3))


def _rows(path: Path) -> list[tuple[int, list[str]]]:
    """(line number, cells) of every line that is neither blank nor a comment."""
    odd = not_a_regular_file(path)
    if odd:
        raise TrackerError(f"{path}: cannot read: {odd}")
    try:
        data = path.read_bytes()
    except OSError as e:
        raise TrackerError(f"{path}: cannot read: {e.strerror or e}") from None
    try:
        text = data.decode("utf-8-sig")  # a BOM first, as Excel's "CSV UTF-8" writes it, is not a cell
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        raise TrackerError(f"{path}: line {line}: expected UTF-8 text, got byte {data[e.start]:#04x}") from None
    return [(k, next(csv.reader([ln]))) for k, ln in enumerate(text.splitlines(), start=1)
            if ln.strip() and not ln.lstrip().startswith("#")]


def _cell(cell: str, j: int, where: str) -> float | None:
    """Column ``j``'s number (None: an empty y or theta)."""
    if not cell and j >= 2:
        return None
    try:
        v = typed_float(cell)
    except ValueError:
        raise TrackerError(f"{where}, column {COLUMNS[j]}: expected a number, got {cell!r}") from None
    if not abs(v) <= MAX_ABS:
        raise TrackerError(f"{where}, column {COLUMNS[j]}: expected a finite number within ±{_MAX_TEXT}, "
                           f"got {cell!r}")
    return v


def _motion_near(track: Track, events: np.ndarray, offset: float, lead_s: float, lag_s: float) -> float:
    step = np.hypot(np.diff(track.x), np.diff(track.y) if track.y is not None else 0.0)
    mid = (track.t[1:] + track.t[:-1]) / 2 - offset
    pos = np.searchsorted(events, mid - lag_s, side="left")  # first event at or after mid - lag
    near = np.zeros(len(mid), dtype=bool)
    ok = pos < len(events)
    near[ok] = events[pos[ok]] <= mid[ok] + lead_s
    return float(step[near].sum() - step[~near].sum())


def estimate_offset(track: Track, event_times: Sequence[float], *, max_offset_s: float = 30.0,
                    step_s: float = 0.02, lead_s: float = 0.25, lag_s: float = 0.1) -> float:
    """Tracker time − firmware time, from where the tracked motion lies relative to the
    times ``event_times`` at which the firmware saw each transition's new state.

    Give the times the measured state changed (``Trial.t_moved``), not the STATE_REACHED
    events: the ψ-feedback controller confirms a state only once every limb has settled
    clear of its band edges — for a cooling limb up to ~0.6 s after the friction change
    that moved the robot — whereas the measured state changes within the debounce (+ one
    telemetry period) of it.

    A transition's motion ends when its new state is seen (give or take ``lag_s``: the
    plant's or camera's latency) and mostly lies within ``lead_s`` before (a diagonal
    transition passes through an intermediate state); after a piece, the robot relaxes as
    its coils cool, which moves it with no event nearby. So the set of offsets that put
    the most motion within ``[t − lead_s, t + lag_s]`` and the least elsewhere is blurred
    on its high side (motion before events, relaxation) and sharp on its low side: shift
    the clocks the other way by more than ``lag_s`` and the last motion of every transition
    comes after its event. The search: that score on a ``step_s`` grid over
    ``±max_offset_s`` around lining up the track's start with the first event, refined within
    ``± lead_s`` of the best; the estimate is the low edge of the best plateau (scores within
    2 % of the total tracked motion of the best, contiguous with it) + ``lag_s``, i.e. the
    offset at which the latest-seen motion ends exactly at its event. It is off by that
    motion's own delay to its event (−one telemetry period to + the debounce on a robot;
    ≈ +0.03 s on the table plant, which applies a step 30 ms after the crossing) — ±0.06 s
    on the synthetic and simulated tests. A sync event is better when the lab has one."""
    ev = np.sort(np.asarray(event_times, dtype=float))
    if len(ev) == 0:
        raise TrackerError("no transitions to align the tracker with")
    base = track.t[0] - ev[0]
    grid = base + np.arange(-max_offset_s, max_offset_s + step_s / 2, step_s)
    scores = np.array([_motion_near(track, ev, o, lead_s, lag_s) for o in grid])
    best = float(grid[int(np.argmax(scores))])
    fine = best + np.arange(-lead_s, lead_s + 1e-9, step_s / 20)
    fscores = np.array([_motion_near(track, ev, o, lead_s, lag_s) for o in fine])
    total = float(np.hypot(np.diff(track.x), np.diff(track.y) if track.y is not None else 0.0).sum())
    top = fscores >= fscores.max() - 0.02 * total  # the plateau, not the noise's favourite
    k = int(np.argmax(fscores))
    while k > 0 and top[k - 1]:
        k -= 1
    return float(fine[k]) + lag_s


class TrackerSource:
    """Poses from a track at firmware times (``pose_at(t_firmware)``), given the offset."""

    name = "tracker"

    def __init__(self, track: Track, offset_s: float):
        self.track, self.offset_s = track, offset_s

    def pose_at(self, t_firmware: float):
        return self.track.pose(t_firmware + self.offset_s)


def trials_from_events(reached: Sequence[tuple[float, str]], source, *, settle_s: float = 0.05,
                       name: str = "tracker"):
    """Trials from the firmware's state-reached events ``(t_firmware, state label)`` in order
    and a source with ``pose_at(t_firmware)``: transition k runs from event k−1 to event k;
    its motion is the pose change between ``settle_s`` after each (the robot has settled in
    the reached state but not yet left it: keep ``settle_s`` below the robot's hold time)."""
    from .measure import Trial, planar_delta

    out = []
    for (t0, a), (t1, b) in zip(reached, reached[1:]):
        if a == b:
            continue
        dx, dy, dth = planar_delta(source.pose_at(t0 + settle_s), source.pose_at(t1 + settle_s))
        out.append(Trial(a, b, t0, t1, dx, dy, dth, name))
    return out


def attach_track(trials, track: Track, offset_s: float | None = None, *, settle_s: float = 0.05):
    """Trials recorded without a pose (``dx`` None), e.g. a run with ``--source tracker``,
    given their motion from ``track``; the offset is estimated from the times the trials'
    motion ended (``Trial.t_moved``: when the telemetry first showed the new state, else the
    state-reached event) unless given; the poses are read ``settle_s`` after the events
    (the robot settled). A trial that begins or ends outside the track keeps no motion (the
    track says nothing about it; before, the track's end pose made it a motion of 0), and so does
    one whose pose falls in a gap of the track (``Track.gap_around``: before, interpolated across
    it). Returns
    (new trials, offset used, trials left without motion)."""
    from dataclasses import replace

    from .measure import planar_delta

    if offset_s is None:
        offset_s = estimate_offset(track, [t.t_moved for t in trials])
    src = TrackerSource(track, offset_s)
    out, outside = [], []
    for t in trials:
        a, b = t.t_start + settle_s, t.t_end + settle_s
        if not (track.covers(a + offset_s) and track.covers(b + offset_s)):
            outside.append(t)
            continue
        dx, dy, dth = planar_delta(src.pose_at(a), src.pose_at(b))
        out.append(replace(t, dx=dx, dy=dy, dtheta_deg=dth, source="tracker"))
    return out, offset_s, outside
