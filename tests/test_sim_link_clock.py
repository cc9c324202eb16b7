"""SimLink's virtual clock: a positive wait always moves time (a sub-nanosecond remainder of a
float deadline once made proleg learn's explorer rest for ever on the simulator)."""

from __future__ import annotations

from proleg.link.sim_link import SimLink


class _SilentBoard:
    def __init__(self) -> None:
        self.advanced = 0.0

    def write(self, data: bytes) -> None:
        pass

    def read(self) -> bytes:
        return b""

    def advance(self, seconds: float) -> None:
        self.advanced += seconds


def test_a_sub_nanosecond_timeout_still_advances_the_clock():
    link = SimLink(_SilentBoard())
    link.read(0.123456789)
    before = link.clock()
    assert link.read(1e-10) == b""
    assert link.clock() > before

