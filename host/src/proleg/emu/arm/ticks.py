"""Tick-budget measurement and stack use on the arm-emu board.

``TickMarks`` is a part of ``ArmEmuBoard`` (board.py): a tick's busy time runs from the
firmware's ``hal_tick_mark(1)`` to its ``hal_tick_mark(0)``, stores to BKP_DR1 that
``bkp.py`` passes to ``_on_mark``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .memmap import CYC_PER_US, RAM_BASE, RAM_SIZE


@dataclass(frozen=True)
class TickBudget:
    """Busy time per control tick (app_tick entry to the next wait), µs."""

    tick_period_us: int
    ticks: int
    mean: float
    p99: float
    max: float

    def as_dict(self) -> dict:
        # a float, as avr-emu's (emu/avr/budget.py: 1e6 / tick_hz need not be whole): one type in the JSON
        return {"tick_period_us": float(self.tick_period_us), "tick_busy_us": {
            "ticks": self.ticks, "mean": round(self.mean, 1), "p99": round(self.p99, 1), "max": round(self.max, 1)}}


class TickMarks:
    """Busy time per tick and the deepest stack use, for ``ArmEmuBoard``."""

    def _on_mark(self, busy: int, now: int) -> None:
        if busy:
            self._tick_start = now
            self._idle_ran = self._idle_hook is None  # the wait after this tick runs the idle loop once
        elif self._tick_start is not None:
            self.busy_us.append((now - self._tick_start) / CYC_PER_US)
            self._tick_start = None

    def stack_peak_bytes(self) -> int:
        """Deepest stack use since power-on: RAM is all zeros at reset, so the lowest
        non-zero byte between the end of static data and the initial SP marks the deepest
        point the stack wrote. A lower bound (zeros pushed at the very bottom do not show)."""
        sp0 = int.from_bytes(self._flash[0:4], "little")
        static_end = max((s.value + s.size for s in self.elf.symbols.values()
                          if RAM_BASE <= s.value < RAM_BASE + RAM_SIZE), default=RAM_BASE)
        ram = bytes(self.uc.mem_read(static_end, sp0 - static_end))
        for i, b in enumerate(ram):
            if b:
                return sp0 - (static_end + i)
        return 0

    def clear_ticks(self) -> None:
        """Start a new measurement window (e.g. after boot), as ``AvrEmuBoard.clear_ticks``."""
        self.busy_us.clear()

    def tick_budget(self) -> TickBudget:
        b = sorted(self.busy_us)
        if not b:
            return TickBudget(self.tick_us, 0, 0.0, 0.0, 0.0)
        p99 = b[min(len(b) - 1, int(0.99 * len(b)))]
        return TickBudget(self.tick_us, len(b), sum(b) / len(b), p99, b[-1])
