"""Run a simulation step on a thread in (roughly) real time: ``PacedLoop(step, step_s)``
calls ``step(step_s)`` again and again, sleeping so that virtual time keeps to wall time ×
``speed`` (it never sleeps to catch up: a slow step just runs late). The CAN bridge and the
CAN port serve a simulated board to a host in another process this way.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable


class PacedLoop:
    """``start(speed)`` runs ``step(step_s)`` on a daemon thread named ``name``; ``stop()``
    ends it (waits up to 2 s for the step under way)."""

    def __init__(self, step: Callable[[float], None], step_s: float, name: str):
        self.step, self.step_s, self.name = step, step_s, name
        self._running = False
        self._thread: threading.Thread | None = None

    def start(self, speed: float = 1.0) -> PacedLoop:
        self._running = True
        self._thread = threading.Thread(target=self._run, args=(speed,), name=self.name, daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._running = False
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None

    def _run(self, speed: float) -> None:
        t0, virtual = time.monotonic(), 0.0
        while self._running:
            self.step(self.step_s)
            virtual += self.step_s
            ahead = virtual / speed - (time.monotonic() - t0)
            if ahead > 0:
                time.sleep(ahead)
