"""The host's model of the firmware's on-time debt (proleg.gait.coil_debt) against a
brute-force, tick-by-tick re-enactment of core/sma.c's budget over a gait's cycles."""

from __future__ import annotations

import math

from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from proleg.gait.coil_debt import EPS_S, Step, coil_budget, cycle_debt

TICK_HZ = 100  # 10 ms ticks keep the brute force quick; the model takes any tick rate
CYCLES = 25


def firmware_cuts(steps_ticks, max_on_ms: int, min_cooldown_ms: int, tick_hz: int = TICK_HZ) -> list[bool]:
    """Per coil: does sma_tick cut it (an on-limit hit) within CYCLES cycles from cool coils?
    steps_ticks: (on coils, drive ticks, hold ticks). Written out from sma.c / render.py:
    times in whole ticks, refill_q8 = on_us / ((cooldown_us >> 8) + 1) capped at 10000, each
    tick first charges what the pin carried since the last one, then decides the output."""
    tick = round(1_000_000 / tick_hz)
    on_us = math.ceil(max_on_ms * tick_hz / 1000 - 1e-9) * tick
    cd_us = math.ceil(min_cooldown_ms * tick_hz / 1000 - 1e-9) * tick
    refill_q8 = min(10_000, on_us // ((cd_us >> 8) + 1))
    n = len(steps_ticks[0][0])
    debt, applied, cut = [0] * n, [False] * n, [False] * n
    for _ in range(CYCLES):
        for on, drive, hold in steps_ticks:
            for t in range(drive + hold):
                for c in range(n):
                    if applied[c]:
                        debt[c] += tick
                    else:
                        debt[c] = max(0, debt[c] - ((tick * refill_q8) >> 8))
                    want = on[c] and t < drive
                    if want and debt[c] + tick > on_us:
                        cut[c] = True
                        want = False
                    applied[c] = want
    return cut


coils = st.integers(1, 3)


@st.composite
def gaits(draw):
    n = draw(coils)
    steps = draw(st.lists(
        st.tuples(st.lists(st.booleans(), min_size=n, max_size=n), st.integers(1, 200), st.integers(0, 60)),
        min_size=1, max_size=6,
    ))
    return [(tuple(on), d, h) for on, d, h in steps]


@settings(max_examples=150, deadline=None)
# the last step's drive runs on into the first's: only the second cycle shows 3.2 s in a row
@example([((True,), 160, 0), ((False,), 50, 0), ((True,), 160, 0)], 3000, 800)
@given(gaits(), st.integers(20, 500).map(lambda x: 10 * x), st.integers(1, 300).map(lambda x: 10 * x))
def test_the_model_flags_exactly_the_coils_the_firmware_would_cut(steps_ticks, max_on_ms, min_cooldown_ms):
    budget = coil_budget(max_on_ms, min_cooldown_ms, TICK_HZ)
    steps = [Step(on, d / TICK_HZ, h / TICK_HZ) for on, d, h in steps_ticks]
    debts = cycle_debt(steps, budget.payback)
    # a coil gaining debt every cycle is cut in about max_on / gain cycles: keep that
    # within the brute force's CYCLES (the model flags any gain at all)
    assume(all(d.growth_s == 0 or d.growth_s * (CYCLES - 3) >= budget.max_on_s for d in debts))
    flagged = [d.growth_s > 0 or d.peak_s > budget.max_on_s + EPS_S for d in debts]
    assert flagged == firmware_cuts(steps_ticks, max_on_ms, min_cooldown_ms)


def test_holding_a_raised_limb_pays_the_debt_back():
    # one coil: 2.5 s drive then a 1 s hold, twice per cycle, under max_on 3000 / cool-down 800
    budget = coil_budget(3000, 800, 800)
    steps = [Step((True,), 2.5, 1.0), Step((False,), 0.8, 0.1)]
    (d,) = cycle_debt(steps, budget.payback)
    assert d.growth_s == 0 and d.peak_s == 2.5 and d.at_step == 0
    assert not firmware_cuts([((True,), 250, 100), ((False,), 80, 10)], 3000, 800)[0]
    # counting the held second as on-time (the old check) would have said 3.5 s > 3 s


def test_a_drive_past_max_on_is_flagged_and_cut():
    budget = coil_budget(3000, 800, TICK_HZ)
    steps = [Step((True,), 1.6, 0.0), Step((True,), 1.6, 0.1), Step((False,), 0.8, 0.1)]  # 3.2 s in a row
    (d,) = cycle_debt(steps, budget.payback)
    assert d.growth_s == 0 and d.peak_s > budget.max_on_s and d.at_step == 1
    assert firmware_cuts([((True,), 160, 0), ((True,), 160, 10), ((False,), 80, 10)], 3000, 800) == [True]


def test_the_budget_rounds_as_the_firmware_does():
    b = coil_budget(3000, 800, 800)  # tick 1250 µs; refill_q8 = 3e6 // 3126 = 959, paid as 959/256
    assert b.max_on_s == 3.0 and b.payback == 959 / 256  # the fraction of a µs carries from tick to tick
    assert coil_budget(3000, 10, 1000).payback == 10_000 / 256  # at most 39×
