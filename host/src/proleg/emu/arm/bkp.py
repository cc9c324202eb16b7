"""The backup registers (BKP, RM0008 §5): only BKP_DR1, the firmware's tick-budget marker.

The core writes 1 to BKP_DR1 when a tick's work starts and 0 when it ends
(``hal_tick_mark``). On the chip the BKP clock is off, so the writes are ignored; here each
one is passed to ``on_mark(busy, now)`` so the board times the tick from the firmware's
own markers, whatever the code around them looks like.
"""

from __future__ import annotations

from collections.abc import Callable


class Bkp:
    BASE = 0x40006C00
    DR1 = 0x04

    def __init__(self, on_mark: Callable[[int, int], None]) -> None:
        self.on_mark = on_mark
        self.marks = 0

    def reset(self) -> None:
        pass

    def read(self, off: int, now: int) -> int:
        return 0  # the clock is off: reads as 0 on the chip too

    def write(self, off: int, value: int, now: int) -> None:
        if off == self.DR1:
            self.marks += 1
            self.on_mark(value & 1, now)
