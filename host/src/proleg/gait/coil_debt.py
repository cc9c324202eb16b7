"""The firmware's on-time debt budget for one SMA coil, as the host plans with it.

``core/sma.c`` (docs/safety.md, "What is bounded") keeps, per coil, an on-time *debt*:
every µs the coil drives above the hold ceiling adds a µs, every µs it does not (holding a
reached state at or below the hold ceiling, lowering a limb, resting) pays back
``max_on_ms`` / ``min_cooldown_ms`` µs, and the debt never goes below 0. A drive that would
take the debt past ``max_on_ms`` is cut (SMA_ON_LIMIT) and the coil stays off until the
debt is paid. Holding a raised limb is therefore *not* on-time.

The host sees a gait as steps: during a step the coils that raise one of their limbs drive
for the step's duration, the others pay back; then the reached state is held (every coil
pays back). ``cycle_debt`` runs a gait's steps cyclically from cool coils and gives each
coil's largest debt once the cycles have settled, or how much it gains per cycle when it
never settles. ``learn.pieces`` and ``gait.feasibility`` both use ``charge``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

EPS_S = 1e-9  # float slack, far below one tick


@dataclass(frozen=True)
class CoilBudget:
    max_on_s: float  # the most debt a coil may carry: max_on_ms in whole ticks
    payback: float   # seconds of debt paid back per second not on, rounded as sma.c rounds it


def refill_q8(on_us: int, cooldown_us: int) -> int:
    """sma.c set_times: on-time paid back per µs not on, × 256, rounded down, at most 10000
    (39×)."""
    return min(10_000, on_us // ((cooldown_us >> 8) + 1))


def coil_budget(max_on_ms: float, min_cooldown_ms: float, tick_hz: int) -> CoilBudget:
    """The budget the firmware builds from ``[safety]`` (render.py turns the times into whole
    ticks, sma.c's set_times the pay-back into a ×256 rate, rounded down and at most 39×;
    sma_tick carries the fraction of a µs from tick to tick, so the rate is paid as it is)."""
    tick_us = round(1_000_000 / tick_hz)
    on_us = math.ceil(max_on_ms * tick_hz / 1000.0 - 1e-9) * tick_us
    cooldown_us = math.ceil(min_cooldown_ms * tick_hz / 1000.0 - 1e-9) * tick_us
    return CoilBudget(on_us / 1e6, refill_q8(on_us, cooldown_us) / 256)


def charge(debt: Sequence[float], on: Sequence[bool], seconds: float, payback: float) -> list[float]:
    """Each coil's debt after ``seconds`` in which the coils ``on`` drive: + seconds for a coil
    that is on, − seconds × ``payback`` (not below 0) for one that is not."""
    return [x + seconds if c else max(0.0, x - seconds * payback) for x, c in zip(debt, on)]


@dataclass(frozen=True)
class Step:
    """One step of a gait as the coils see it: ``on`` drive for ``drive_s``, then the reached
    state is held for ``hold_s`` with every coil paying back."""

    on: tuple[bool, ...]
    drive_s: float
    hold_s: float


@dataclass(frozen=True)
class CoilDebt:
    peak_s: float        # the largest debt, over every cycle (from cool coils) once settled
    at_step: int         # the step (0-based) whose drive reaches it
    growth_s: float      # debt gained per cycle when it never settles (> 0), else 0


def cycle_debt(steps: Sequence[Step], payback: float) -> list[CoilDebt]:
    """Each coil's debt running ``steps`` cyclically from cool coils (see module docstring).

    The debt is a Lindley recursion: when the debt a coil drives up in one cycle is no more
    than it can pay back in it, the debt from any point on depends only on the last cycle, so
    the second cycle from cool coils already shows the settled peak. Otherwise the coil gains
    ``growth_s`` every cycle and sooner or later is cut, whatever its peak so far."""
    n = len(steps[0].on) if steps else 0
    total = sum(s.drive_s + s.hold_s for s in steps)
    out = []
    for c in range(n):
        on_s = sum(s.drive_s for s in steps if s.on[c])
        growth = on_s - (total - on_s) * payback
        debt, peak, at = 0.0, 0.0, 0
        for _ in range(2):
            for k, s in enumerate(steps):  # ``charge`` for one coil, unrolled (thousands of ties)
                debt = debt + s.drive_s if s.on[c] else max(0.0, debt - s.drive_s * payback)
                if debt > peak + EPS_S:
                    peak, at = debt, k
                debt = max(0.0, debt - s.hold_s * payback)
        out.append(CoilDebt(peak, at, growth if growth > EPS_S else 0.0))
    return out
