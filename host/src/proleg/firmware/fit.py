"""Whether a board can host a robot, checked before anything is compiled.

``check_fit(robot, board, gaits)`` places every limb's IMU on the board's buses
(``placement.place_imus``), checks the actuators' PWM channels, the I2C time the IMU
reads take per control tick, and estimates the flash and static RAM the firmware needs:
the board file's measured ``base_flash_bytes``/``base_ram_bytes`` (the firmware of a
two-limb robot with tiny tables) plus the robot's tables (gait steps, gait index,
allowed transitions: a bitmap up to 64 states, a sorted 32-bit key list above) plus a
per-limb allowance. It raises ``BuildError`` naming what does not fit and why; the
exact sizes are still checked after compiling (build.py).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import BuildError
from ..names import counted
from .boards import DEFAULT_I2C_HZ, pwm_channel_error
from .placement import ImuPlacement, check_tick_budget, i2c_tick_us, mux_selects_per_tick, place_imus
from .render_gaits import BITMAP_MAX_STATES, gait_table_rows

#: Flash and static RAM one more limb (beyond the two of the measured base) adds: its
#: thresholds, IMU placement, ψ classifier and IMU-check state, and its actuator's thermal
#: budget (RAM measured on the Nano, 2026-11-23: paper-r1 969 B, inchworm-3 1,123 B,
#: planar-4 1,263 B, i.e. 147-154 B per limb with its actuator; caterpillar-4, with two
#: thresholds on some limbs, 1,375 B: the exact check after compiling catches that rest).
FLASH_PER_LIMB = 64
RAM_PER_LIMB = 155
BASE_LIMBS = 2
#: Static RAM of one limb's ψ band beyond the first (psi.c's band_t: five {cos, sin} edges and
#: four edge values, int16 each), kept for every limb up to the robot's most thresholds
#: (bands[CFG_N_LIMBS][CFG_MAX_THRESHOLDS]). Measured on the Nano: two limbs of 2 and 10 levels
#: 1,421 B against 973 B for 2 and 2 (56 B per threshold of the longer limb). Without it four
#: limbs of 10, 2, 2, 2 levels passed the estimate (1,284 B) and failed to link (.bss past RAM).
RAM_PER_BAND = 28


@dataclass(frozen=True)
class Fit:
    placements: tuple[ImuPlacement, ...]
    mux_selects_per_tick: int
    i2c_us_per_tick: float
    table_bytes: int
    flash_estimate: int | None  # None: the board gives no base to estimate from
    ram_estimate: int | None

    def lines(self) -> list[str]:
        out = [p.describe() for p in self.placements]
        out.append(
            f"I2C per tick: about {self.i2c_us_per_tick:.0f} us ({counted(len(self.placements), 'IMU read')}, "
            f"{counted(self.mux_selects_per_tick, 'multiplexer channel switch')})"
        )
        return out


def table_bytes(robot: Any, gaits: Mapping[str, Sequence[Any]]) -> int:
    """Flash the gait and transition tables take (gait_table.c)."""
    n = robot.n_states
    state_bytes = 1 if n <= 256 else 2
    rows = gait_table_rows(gaits)
    steps = sum(len(st) for _, _, st in rows)
    index = 10 * max(1, len(rows))  # first, length; entry first, length, join
    return steps * state_bytes + index + transition_bytes(robot)


def transition_bytes(robot: Any) -> int:
    """Flash the allowed-transition table takes, whatever the gaits: an n × n bitmap up to
    BITMAP_MAX_STATES states, a sorted 32-bit key per transition above."""
    n = robot.n_states
    return (n * n + 7) // 8 if n <= BITMAP_MAX_STATES else 4 * max(1, len(robot.transitions.src))


def _board(board: Any, key: str, default: Any = None) -> Any:
    return board.get(key, default) if isinstance(board, dict) else getattr(board, key, default)


def i2c_hz(board: Any) -> int:
    """The board's I2C clock, Hz ([i2c] hz; load_board checked it)."""
    return int((_board(board, "i2c", {}) or {}).get("hz", DEFAULT_I2C_HZ))


def check_i2c_ticks(robot: Any, board: Any) -> tuple[ImuPlacement, ...]:
    """The IMUs' placement, or BuildError when their I2C reads do not fit each tick
    (``placement.check_tick_budget``). ``flash --dry-run`` asks it too: it printed a command and
    exit 0 for R1 at 3000 Hz on the bluepill, which the build refuses (420 us of I2C in a 333 us tick)."""
    placements = tuple(place_imus(robot, board))
    check_tick_budget(robot, _board(board, "name", "board"), placements, i2c_hz(board))
    return placements


def check_fit(robot: Any, board: Any, gaits: Mapping[str, Sequence[Any]]) -> Fit:
    """Everything about the robot that must fit the board, or BuildError saying what does not."""
    name = _board(board, "name", "board")
    pins = list(_board(board, "pwm_pins", ()) or ())
    for a in robot.actuators:
        if a.channel >= len(pins):
            raise BuildError(pwm_channel_error(robot, a, name, pins))
    placements = check_i2c_ticks(robot, board)
    hz = i2c_hz(board)
    tables = table_bytes(robot, gaits)
    extra = max(0, len(robot.limbs) - BASE_LIMBS)
    flash = None
    base_flash = int(_board(board, "base_flash_bytes", 0) or 0)
    limit_flash = int(_board(board, "flash_bytes", 0) or 0)
    if base_flash:
        flash = base_flash + tables + FLASH_PER_LIMB * extra
        if limit_flash and flash > limit_flash:
            library = getattr(gaits, "library", ())
            lib_note = ""
            if library:
                own = [lg for lg in library if lg.appended]
                state_bytes = 1 if robot.n_states <= 256 else 2
                lib_bytes = sum((len(lg.gait.states) - 1) * state_bytes + 10 for lg in own)
                lib_note = (f"; its gait library ({counted(len(library), 'heading')}, {counted(len(own), 'gait')} of their own) takes about "
                            f"{lib_bytes:,} bytes of that: fewer headings or a smaller max_transitions in [gaits]")
            allowed = transition_bytes(robot)
            fix = "fewer gaits: --max-transitions or another objective, or a larger board"
            if base_flash + allowed + FLASH_PER_LIMB * extra > limit_flash:
                # no choice of gaits fits: the table of allowed transitions alone is too big
                fix = (f"its {len(robot.transitions.src):,} allowed transitions alone take {allowed:,} bytes, "
                       f"too many for any gaits: forbid the transitions the robot does not make ({_narrower(robot)}), "
                       "or a larger board")
            raise BuildError(
                f"robot {robot.name} does not fit board {name} (estimated before compiling; {fix}): "
                f"its gait and transition tables take "
                f"{tables:,} bytes ({robot.n_states:,} states, {len(robot.transitions.src):,} transitions), the rest of "
                f"the firmware about {flash - tables:,}; robot {robot.name} needs {flash:,} bytes of flash, "
                f"board {name} has {limit_flash:,}{lib_note}"
            )
    ram = check_ram(robot, board)
    return Fit(placements, mux_selects_per_tick(placements), i2c_tick_us(placements, hz), tables, flash, ram)


def _narrower(robot: Any) -> str:
    """How the robot file can allow fewer transitions: an unmeasured matrix a narrower
    ``allow`` than the one it has (named only when there is one) and ``forbidden``; a written
    table 'x' entries or rows left out. It said allow = "one-level" to a file that had it."""
    if not getattr(robot, "unmeasured", False):
        return "'x' in the matrix, rows left out of the CSV"
    from ..robot_transitions import allowed_count

    have = len(robot.transitions.src)
    counts = [(rule, allowed_count(rule, robot.levels)) for rule in ("one-limb", "one-level")]
    rules = [f'allow = "{rule}": {count:,} transitions' for rule, count in counts if count < have]
    return "; ".join(rules + ["forbidden = [...] beside the allow it has"])


def check_ram(robot: Any, board: Any) -> int | None:
    """The static RAM estimate (None: the board gives no base to estimate from), or BuildError
    when it and the stack reserve do not fit the board. No gaits needed: ``flash --dry-run``
    asks it too (it printed a command and exit 0 for four limbs of 10, 2, 2, 2 levels on the Nano,
    which the build refuses)."""
    name = _board(board, "name", "board")
    base_ram = int(_board(board, "base_ram_bytes", 0) or 0)
    limit_ram = int(_board(board, "ram_bytes", 0) or 0)
    if not base_ram:
        return None
    extra = max(0, len(robot.limbs) - BASE_LIMBS)
    bands = len(robot.limbs) * (max(lb.levels for lb in robot.limbs) - 2)  # past one per limb
    ram = base_ram + RAM_PER_LIMB * extra + RAM_PER_BAND * bands
    stack = int(_board(board, "stack_bytes", 0) or 0)
    if limit_ram and ram + stack > limit_ram:
        also = f" and {stack:,} for its stack ([board] stack_bytes)" if stack else ""
        raise BuildError(
            f"robot {robot.name} does not fit board {name} (estimated before compiling, {counted(len(robot.limbs), 'limb')}"
            f"{f' of up to {max(lb.levels for lb in robot.limbs)} levels' if bands else ''}): "
            f"robot {robot.name} needs {ram:,} bytes of static RAM{also}, board {name} has {limit_ram:,}"
        )
    return ram
