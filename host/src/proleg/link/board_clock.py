"""How fast the board's clock runs against the link's, from TELEMETRY's ``time_ms``.

A simulated board at ``proleg sim --pty --speed 5`` counts its link watchdog on its own clock,
five times faster than the wall clock the host counts its heartbeat on; the client divides
its heartbeat period by this rate so that the watchdog never trips between two PINGs.
"""

from __future__ import annotations

#: the link-clock window (s) the rate is measured over, and the largest rate believed
RATE_WINDOW_S = 0.2
MAX_BOARD_RATE = 50.0


class BoardClockRate:
    """``rate``: board seconds per link second, at least 1 and at most ``MAX_BOARD_RATE``,
    re-estimated over windows of ``RATE_WINDOW_S``; a board clock that steps back (a reset)
    starts over."""

    def __init__(self) -> None:
        self.rate = 1.0
        self._anchor: tuple[float, int] | None = None

    def seen(self, now: float, board_ms: int) -> None:
        """The newest TELEMETRY of a batch read at link time ``now`` (a backlog read at once
        is not a fast clock: only its last frame counts)."""
        anchor = self._anchor
        if anchor is None or board_ms < anchor[1]:
            self._anchor = (now, board_ms)
            return
        elapsed = now - anchor[0]
        if elapsed >= RATE_WINDOW_S:
            self.rate = min(MAX_BOARD_RATE, max(1.0, (board_ms - anchor[1]) / 1000.0 / elapsed))
            self._anchor = (now, board_ms)
