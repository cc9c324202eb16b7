"""The on-time limit in real time on the exact bluepill image at the slowest and the fastest
tick rate the build accepts (issue 11: "verified on the emulators for every tick_hz the build
accepts: a coil is never on longer than max_on_ms + one tick of emulated real time"; the
Nano's rates are in test_emu_avr_firmware.py, the bluepill's 1 kHz in hil_tests). For R1 the
bluepill's fastest rate is set by the I2C share of the tick (two IMU reads ≈ 420 µs at
400 kHz, at most 75 %), well below its [budget]'s."""

from __future__ import annotations

import dataclasses

import pytest

from proleg.errors import BuildError, ProlegError
from proleg.paths import robots_dir
from proleg.robot import load_robot

MAX_ON_MS = 500


def _fastest_r1_rate() -> int:
    """The highest tick_hz the bluepill build accepts for R1: its [budget] and the I2C share."""
    from proleg.firmware.boards import load_board
    from proleg.firmware.placement import I2C_TICK_SHARE, i2c_tick_us, place_imus

    board = load_board("bluepill-f103")
    r1 = load_robot(robots_dir() / "paper-r1.toml")
    i2c_hz = int(board.i2c.get("hz", 400000))
    return min(board.budget.max_tick_hz(2), int(I2C_TICK_SHARE * 1e6 / i2c_tick_us(place_imus(r1, board), i2c_hz)))


def _r1_at(tick_hz: int):
    r1 = load_robot(robots_dir() / "paper-r1.toml")
    return dataclasses.replace(r1, control=dataclasses.replace(r1.control, tick_hz=tick_hz),
                               safety=dataclasses.replace(r1.safety, max_on_ms=MAX_ON_MS))


def _longest_on_ms(robot, seconds: float, *, idle_skip: bool = True) -> float:
    """Both coils dead (they heat, nothing moves), gait 0 started: the longest on-period of any
    coil, sampled every tick of emulated time. ``idle_skip=False``: arm-emu runs every cycle of
    the firmware's tick wait instead of jumping to the next tick (slower, exact)."""
    from proleg.emu.arm import ArmEmuRobot, bluepill_elf
    from proleg.report import SimSession

    try:
        elf = bluepill_elf(robot)
    except BuildError:
        raise
    except ProlegError as e:  # pragma: no cover - toolchain broken
        pytest.skip(f"bluepill build unavailable: {e}")
    sim = ArmEmuRobot(robot, elf, plant_dt_s=1.0 / robot.control.tick_hz)
    if not idle_skip:
        sim.board._wait_skip = lambda: None  # arm-emu's fast path over core/main.c's wait_tick
    session = SimSession(sim)
    session.advance(0.1)
    session.request("START", gait=0, direction=0)
    for a in robot.actuators:
        sim.inject(f"dead-actuator:{a.name}")
    board, longest = sim.board, 0.0
    on_since: list[int | None] = [None] * len(sim.channels)
    for _ in range(round(seconds * robot.control.tick_hz)):
        sim.step()
        now = board.time_us
        for i, ch in enumerate(sim.channels):
            if board.pwm_permyriad(ch):
                on_since[i] = now if on_since[i] is None else on_since[i]
                longest = max(longest, (now - on_since[i]) / 1000)
            else:
                on_since[i] = None
    return longest


def test_the_fastest_accepted_rate_is_the_fastest_the_build_accepts():
    from proleg.firmware.boards import load_board
    from proleg.firmware.build import check_buildable, firmware_gaits
    from proleg.firmware.fit import check_fit

    fastest = _fastest_r1_rate()
    board = load_board("bluepill-f103")
    for robot in (_r1_at(fastest), _r1_at(fastest + 1)):  # the checks proleg build makes before compiling
        if robot.control.tick_hz > fastest:
            with pytest.raises(BuildError, match="tick_hz"):
                check_buildable(robot, board)
                check_fit(robot, board, firmware_gaits(robot))
        else:
            check_buildable(robot, board)
            check_fit(robot, board, firmware_gaits(robot))


@pytest.mark.parametrize("tick_hz, idle_skip", [
    (200, False),
    (200, True),  # was a strict xfail: the tick-wait fast path lost SysTick wraps (mmio.py _wait_skip)
    (_fastest_r1_rate(), True),
])
def test_max_on_ms_holds_in_real_time_on_the_bluepill_at_the_accepted_tick_rates(tick_hz, idle_skip):
    longest = _longest_on_ms(_r1_at(tick_hz), 0.9, idle_skip=idle_skip)
    # + one tick at most; cut up to 3 ms early as on the Nano. Sampled once per tick, the
    # measured period starts up to a tick after the coil came on and ends up to a tick before
    # it went off: up to two ticks short (200 Hz: on 200-205 → off 695-700 ms reads 490 ms)
    assert MAX_ON_MS - 3 - 2 * 1000 / tick_hz <= longest <= MAX_ON_MS + 1000 / tick_hz
