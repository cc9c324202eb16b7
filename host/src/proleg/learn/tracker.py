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
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class TrackerError(ValueError):
    """A tracker file that does not follow the documented format."""


@dataclass(frozen=True)
class Track:
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray | None = None
    theta_deg: np.ndarray | None = None

    def pose(self, t: float) -> tuple[float | None, float | None, float | None]:
        """Linear interpolation at tracker time ``t`` (clamped to the ends)."""
        x = float(np.interp(t, self.t, self.x))
        y = None if self.y is None else float(np.interp(t, self.t, self.y))
        th = None if self.theta_deg is None else float(np.interp(t, self.t, np.unwrap(self.theta_deg, period=360.0)))
        return x, y, th


def read_track(path: str | Path) -> Track:
    path = Path(path)
    try:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    except OSError as e:
        raise TrackerError(f"{path}: cannot read: {e}") from None
    rows = list(csv.reader(lines))
    if not rows or [c.strip() for c in rows[0]][:4] != ["time", "x", "y", "theta"]:
        raise TrackerError(f"{path}: line 1: expected the header time,x,y,theta")
    cols: list[list[float | None]] = [[], [], [], []]
    for k, row in enumerate(rows[1:], start=2):
        if len(row) < 2 or len(row) > 4:
            raise TrackerError(f"{path}: row {k}: expected time,x[,y[,theta]], got {','.join(row)!r}")
        row = row + [""] * (4 - len(row))
        for j, cell in enumerate(row):
            cell = cell.strip()
            if not cell and j >= 2:
                cols[j].append(None)
                continue
            try:
                v = float(cell)
            except ValueError:
                raise TrackerError(f"{path}: row {k}, column {('time', 'x', 'y', 'theta')[j]}: expected a number, got {cell!r}") from None
            if not math.isfinite(v):
                raise TrackerError(f"{path}: row {k}: expected a finite number, got {cell!r}")
            cols[j].append(v)
    t = np.array(cols[0], dtype=float)
    if len(t) < 2 or np.any(np.diff(t) <= 0):
        raise TrackerError(f"{path}: time: expected at least two rows with strictly increasing times")

    def opt(c: list[float | None]) -> np.ndarray | None:
        if all(v is None for v in c):
            return None
        if any(v is None for v in c):
            raise TrackerError(f"{path}: a column is given on some rows only (give it on every row or none)")
        return np.array(c, dtype=float)

    return Track(t, np.array(cols[1], dtype=float), opt(cols[2]), opt(cols[3]))


def _motion_near(track: Track, events: np.ndarray, offset: float, lead_s: float, lag_s: float) -> float:
    step = np.hypot(np.diff(track.x), np.diff(track.y) if track.y is not None else 0.0)
    mid = (track.t[1:] + track.t[:-1]) / 2 - offset
    pos = np.searchsorted(events, mid - lag_s, side="left")  # first event at or after mid - lag
    near = np.zeros(len(mid), dtype=bool)
    ok = pos < len(events)
    near[ok] = events[pos[ok]] <= mid[ok] + lead_s
    return float(step[near].sum() - step[~near].sum())


def estimate_offset(track: Track, event_times: Sequence[float], *, max_offset_s: float = 30.0,
                    step_s: float = 0.02, lead_s: float = 0.5, lag_s: float = 0.1) -> float:
    """Tracker time − firmware time that puts the most tracked motion within
    ``[t − lead_s, t + lag_s]`` of the firmware's state-reached times ``event_times`` (a
    transition moves the robot while it heads for its target state, up to the moment it is
    reached) and the least elsewhere. The search spans ``±max_offset_s`` around the offset
    that lines up the track's start with the first event, in ``step_s`` steps, then takes
    the middle of the plateau (scores within 2 % of the total tracked motion of the best), so
    camera noise does not pick an end of it. Accuracy ≈ ±0.05 s on the synthetic tests; a
    sync event is better when the lab has one."""
    ev = np.sort(np.asarray(event_times, dtype=float))
    if len(ev) == 0:
        raise TrackerError("no transitions to align the tracker with")
    base = track.t[0] - ev[0]
    grid = base + np.arange(-max_offset_s, max_offset_s + step_s / 2, step_s)
    scores = np.array([_motion_near(track, ev, o, lead_s, lag_s) for o in grid])
    best = float(grid[int(np.argmax(scores))])
    fine = best + np.arange(-0.5 * lead_s, 0.5 * lead_s + 1e-9, step_s / 20)
    fscores = np.array([_motion_near(track, ev, o, lead_s, lag_s) for o in fine])
    total = float(np.hypot(np.diff(track.x), np.diff(track.y) if track.y is not None else 0.0).sum())
    top = fine[fscores >= fscores.max() - 0.02 * total]  # the plateau, not the noise's favourite
    return float((top.min() + top.max()) / 2)


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
    given their motion from ``track``; the offset is estimated from the trials' end times
    (their state-reached events) unless given. Returns (new trials, offset used)."""
    from dataclasses import replace

    from .measure import planar_delta

    if offset_s is None:
        offset_s = estimate_offset(track, [t.t_end for t in trials])
    src = TrackerSource(track, offset_s)
    out = []
    for t in trials:
        dx, dy, dth = planar_delta(src.pose_at(t.t_start + settle_s), src.pose_at(t.t_end + settle_s))
        out.append(replace(t, dx=dx, dy=dy, dtheta_deg=dth, source="tracker"))
    return out, offset_s
