"""arm-emu's fast path over the firmware's tick wait (emu/arm/mmio.py ``_wait_skip``) jumps
emulated time instead of running the idle loop; the firmware's clock (``ms_count``, counted
by SysTick_Handler, the base of hal_micros) must still follow the emulated cycles one to
one at every tick rate. It did not below 500 Hz: a jump from a pending SysTick wrap to the
next folded two wraps into one interrupt (0.59x real time at 200 Hz, 0.72x at 400)."""

from __future__ import annotations

import dataclasses

import pytest

from proleg.errors import BuildError, ProlegError
from proleg.paths import robots_dir
from proleg.robot import load_robot


def _board_at(tick_hz: int):
    from proleg.emu.arm import ArmEmuRobot, bluepill_elf

    r1 = load_robot(robots_dir() / "paper-r1.toml")
    robot = dataclasses.replace(r1, control=dataclasses.replace(r1.control, tick_hz=tick_hz))
    try:
        elf = bluepill_elf(robot)
    except BuildError:
        raise
    except ProlegError as e:  # pragma: no cover - toolchain broken
        pytest.skip(f"bluepill build unavailable: {e}")
    return ArmEmuRobot(robot, elf, plant_dt_s=1.0 / tick_hz).board


@pytest.mark.parametrize("tick_hz", [200, 250, 400, 1000])  # 200: the lowest rate the build accepts
def test_the_firmware_clock_follows_emulated_time_across_tick_wait_skips(tick_hz):
    board = _board_at(tick_hz)
    jumps: list[int] = []
    skip = board._wait_skip

    def counted_skip() -> None:
        before = board.native.cycles.value
        skip()
        jumps.append(board.native.cycles.value - before)

    board._wait_skip = counted_skip
    board.run_us(50_000)  # boot
    ms0, t0 = board._word(board._ms_count.value), board.time_us
    ticks0 = board._word(board._next_tick.value)
    board.run_us(400_000)
    ms1, t1 = board._word(board._ms_count.value), board.time_us
    ticks1 = board._word(board._next_tick.value)
    # the fast path did run, and skipped most of the idle time in long jumps
    assert sum(j for j in jumps if j >= 100 * 72) >= 0.2 * (t1 - t0) * 72
    # one SysTick interrupt per emulated millisecond, none lost in a jump (±1 at either end)
    assert abs((ms1 - ms0) - (t1 - t0) / 1000) <= 2
    # and the firmware ran one tick per tick period of emulated time
    assert abs((ticks1 - ticks0) - (t1 - t0)) <= 2 * 1_000_000 // tick_hz


def test_no_jump_while_a_systick_wrap_waits_to_be_taken():
    """A pending SysTick (the wrap happened, its handler has not run yet, so ms_count lags by
    one) stops the fast path: jumping on from there to the next wrap would lose a ms. Whether
    the tick wait ever reads SYST_CVR with a wrap pending depends on where the wait's loads fall
    in the image, so several rates are watched (at 200 Hz the image of 2026-12-01 never did)."""
    pending_calls: list[int] = []
    other_calls: list[int] = []
    for tick_hz in (200, 250, 400):
        board = _board_at(tick_hz)
        board.run_us(50_000)
        skip = board._wait_skip

        def watched_skip(board=board, skip=skip) -> None:
            pending, before = board.scs.systick_pending, board.native.cycles.value
            skip()
            (pending_calls if pending else other_calls).append(board.native.cycles.value - before)

        board._wait_skip = watched_skip
        board.run_us(100_000)
    assert pending_calls, "hal_micros never read SYST_CVR with a wrap pending in the tick wait"
    assert all(j == 0 for j in pending_calls)
    assert any(j > 0 for j in other_calls)
