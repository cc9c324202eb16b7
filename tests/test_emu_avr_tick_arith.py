"""Integer arithmetic on the Nano's control path (issue 11; docs/STYLE: no 32-bit division
in the tick on AVR, no atan2 or float on the control path). The exact arduino-nano image,
profiled on avr-emu while R1 walks with no host traffic (every control tick and the
background telemetry): it links no floating-point routine at all, and it spends no cycle
in avr-libgcc's 32-bit division (``__udivmodsi4``/``__divmodsi4``, about 600 cycles each,
which the old firmware ran several times per tick)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proleg.paths import robots_dir
from proleg.robot import load_robot

pytestmark = pytest.mark.skipif(
    not Path("/usr/include/simavr/sim_avr.h").exists() or shutil.which("avr-gcc") is None,
    reason="needs simavr/libsimavr-dev and avr-gcc (make toolchains installs them)",
)

#: avr-libgcc / avr-libc soft-float and libm entry points (any of them linked means float code)
FLOAT_ROUTINES = ("__addsf3", "__subsf3", "__mulsf3", "__divsf3", "__floatsisf", "__floatunsisf",
                  "__fixsfsi", "__fixunssfsi", "__cmpsf2", "__fp_split3", "atan2", "atan", "sqrt")
DIVISIONS = ("__udivmodsi4", "__divmodsi4")


def test_the_walking_nano_runs_no_32_bit_division_and_links_no_float():
    from proleg.emu.avr import AvrEmuRobot
    from proleg.emu.avr.elf import symbols
    from proleg.report import SimSession

    r1 = load_robot(robots_dir() / "paper-r1.toml")
    sim = AvrEmuRobot(r1)
    linked = {s.name for s in symbols(sim.board.elf).values()}
    assert not linked & set(FLOAT_ROUTINES), sorted(linked & set(FLOAT_ROUTINES))

    session = SimSession(sim)
    session.advance(0.1)
    session.request("START", gait=0, direction=0)
    session.advance(0.5)
    sim.board.profile_start()
    session.advance(1.0)
    cycles = sim.board.profile()
    assert sum(cycles.values()) > 15_000_000  # the profile saw the whole second (16 MHz)
    assert cycles.get("hal_i2c_poll", 0) > 0 and cycles.get("__umulhisi3", 0) > 0  # it names library routines
    assert {name: cycles[name] for name in DIVISIONS if name in cycles} == {}
