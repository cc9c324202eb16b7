"""What the console shows, apart from how: the latest telemetry, the events and faults, the
frame rate (``ConsoleModel``, written by the ``Notifier``'s thread and read by the UI's), and
what the robot file says of each limb (``LimbView``)."""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from ..link.client import Received, RobotInfo
from ..protocol.definition import EventKind
from .names import RobotNames, describe_event


@dataclass(frozen=True)
class LimbView:
    """What the console knows about a limb beyond telemetry (from the robot file, if given)."""

    name: str
    psi_star_deg: tuple[float, ...]


@dataclass
class ConsoleModel:
    """Latest telemetry and counters, written by the Notifier thread, read by the UI."""

    info: RobotInfo | None = None
    names: RobotNames = field(default_factory=RobotNames)
    state_label: Callable[[int], str] | None = None
    telemetry: dict | None = None
    truth: dict[str, float] = field(default_factory=dict)
    events: deque[str] = field(default_factory=lambda: deque(maxlen=8))
    faults: deque[str] = field(default_factory=lambda: deque(maxlen=4))
    error: str = ""
    link_error: Exception | None = None  # the Notifier stopped: the link is gone
    _times: deque[float] = field(default_factory=lambda: deque(maxlen=2000))
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def on_message(self, rx: Received) -> None:
        m = rx.message
        with self._lock:
            if m.name == "TELEMETRY":
                self.telemetry = m.fields
                self.truth = rx.truth
                self._times.append(time.monotonic())
            elif m.name == "EVENT":
                text = describe_event(m.fields, self.names, self.state_label)
                self.events.append(text)
                if m.fields["kind"] == EventKind.FAULT:
                    self.faults.append(text)
                elif m.fields["kind"] == EventKind.FAULT_CLEARED:
                    self.faults.clear()

    def on_error(self, exc: Exception) -> None:
        self.error = str(exc)
        self.link_error = exc

    def note(self, text: str) -> None:
        """A line from the host itself (replanning, injected faults) in the events panel."""
        with self._lock:
            self.events.append(text)

    def frame_rate(self, window_s: float = 2.0) -> float:
        with self._lock:
            now = time.monotonic()
            recent = [t for t in self._times if now - t <= window_s]
        if len(recent) < 2:
            return 0.0
        span = max(now - recent[0], 1e-6)
        return len(recent) / span

    def snapshot(self) -> tuple[dict | None, dict[str, float], list[str], list[str]]:
        with self._lock:
            return self.telemetry, dict(self.truth), list(self.events), list(self.faults)
