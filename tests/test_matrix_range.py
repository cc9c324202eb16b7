"""The measured matrix over hold margins (``measure_matrix_range``): what `hil_tests` compare a
gait's walk with. Its range must contain every margin's own measurement, entry by entry and
for any walk, and one margin must give back ``measure_matrix`` itself."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.robot import load_robot
from proleg.sim.physical import measure_matrix, measure_matrix_range

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


@functools.cache
def r1():
    return load_robot(ROBOTS / "paper-r1.toml")


@functools.cache
def r1_range():
    return measure_matrix_range(r1(), (2.0, 4.0, 8.0), repeats=1)


def test_one_margin_gives_back_the_measured_matrix():
    one = measure_matrix_range(r1(), (4.0,), repeats=1)
    plain = measure_matrix(r1(), repeats=1)
    np.testing.assert_array_equal(one.low_mm, plain.matrix_mm)
    np.testing.assert_array_equal(one.high_mm, plain.matrix_mm)


def test_a_walks_range_takes_each_step_at_its_own_extreme():
    """Hand-built: two margins that disagree on different steps. The range of 0→1→0 is the
    sum of the per-step extremes (-1 + -3 .. 2 + 1), wider than either margin's own sum."""
    from proleg.sim.physical.measure import MatrixRange

    low = np.array([[np.nan, -1.0], [-3.0, np.nan]])
    high = np.array([[np.nan, 2.0], [1.0, np.nan]])
    rng = MatrixRange((2.0, 8.0), (), low, high)
    assert rng.cycle_range([0, 1, 0]) == (-4.0, 3.0)
    assert rng.cycle_range([1, 0, 1, 0]) == (-7.0, 4.0)
    assert rng.cycle_range([0]) == (0.0, 0.0)


def test_one_margins_range_is_its_own_sum_along_any_walk():
    one = measure_matrix_range(r1(), (4.0,), repeats=1)
    walk = [0, 2, 1, 0, 1, 3, 2, 0]
    along = sum(one.at(4.0).matrix_mm[a, b] for a, b in zip(walk, walk[1:]))
    assert one.cycle_range(walk) == pytest.approx((along, along))


def test_the_hold_margin_changes_r1s_entries():
    """The reason for a range: how far past ψ* the held limbs sit moves R1's entries by tenths
    of a millimetre (so a range that collapsed to one value would be a bug, not physics)."""
    rng = r1_range()
    spread = np.nanmax(rng.high_mm - rng.low_mm)
    assert spread > 0.2, spread


@st.composite
def walks(draw):
    _, allowed = r1().transitions.dense()
    n = len(allowed)
    state = draw(st.integers(0, n - 1))
    out = [state]
    for _ in range(draw(st.integers(1, 10))):
        nxt = [b for b in range(n) if b != state and allowed[state][b]]
        state = draw(st.sampled_from(nxt))
        out.append(state)
    return out


@settings(max_examples=60, deadline=None)
@given(walks())
def test_a_walks_range_holds_what_every_margin_measures_along_it(walk):
    rng = r1_range()
    low, high = rng.cycle_range(walk)
    assert low <= high
    for m in rng.measured:
        along = sum(m.matrix_mm[a, b] for a, b in zip(walk, walk[1:]))
        assert low - 1e-9 <= along <= high + 1e-9


def test_an_entry_reached_at_only_some_margins_keeps_those_values(monkeypatch):
    """NaN (not reached) at one margin does not hide what the others measured; an entry no
    margin reached stays NaN."""
    from proleg.sim.physical import measure as measure_mod

    nan = float("nan")
    by_margin = {2.0: [[nan, -0.4], [nan, nan]], 4.0: [[nan, nan], [0.5, nan]], 8.0: [[nan, -0.1], [0.7, nan]]}

    def fake(robot, *, margin_deg, **kwargs):
        m = np.array(by_margin[margin_deg])
        return measure_mod.MeasuredMatrix(["0", "1"], m, m * 0, np.isfinite(m).astype(int), m * 0, (), "test")

    monkeypatch.setattr(measure_mod, "measure_matrix", fake)
    rng = measure_mod.measure_matrix_range(None, (2.0, 4.0, 8.0))
    assert rng.low_mm[0, 1] == -0.4 and rng.high_mm[0, 1] == -0.1
    assert rng.low_mm[1, 0] == 0.5 and rng.high_mm[1, 0] == 0.7
    assert np.isnan(rng.low_mm[0, 0]) and np.isnan(rng.high_mm[1, 1])


def test_a_level_narrower_than_two_margins_is_held_in_its_middle():
    """A three-level limb with critical angles 12° and 18°, held 8° past: level 1 (12..18°)
    cannot be 8° inside both edges, so the drive holds it at 15° instead of cooling it out of
    the level (which made every state with that level unreachable at 8°)."""
    from types import SimpleNamespace

    from proleg.sim.physical.measure import IdealDrive

    robot = SimpleNamespace(actuators=[SimpleNamespace(name="a")], limbs=[SimpleNamespace(actuator="a")])
    plant = SimpleNamespace(levels=(3,), true_psi_star_deg=[[12.0, 18.0]])
    drive = IdealDrive(robot, plant, margin_deg=8.0)
    assert drive.command([13.0], 1) == [1]    # below the middle: heat
    assert drive.command([15.0], 1) == [0]    # at it: hold
    assert drive.command([17.0], 1) == [-1]   # above it: cool
    assert drive.command([20.0], 2) == [1]    # level 2 is open above: 18 + 8 = 26° to reach
    wide = IdealDrive(robot, SimpleNamespace(levels=(3,), true_psi_star_deg=[[12.0, 40.0]]), margin_deg=8.0)
    assert wide.command([19.0], 1) == [1] and wide.command([25.0], 1) == [0] and wide.command([33.0], 1) == [-1]


def test_no_margins_is_an_error():
    with pytest.raises(ValueError, match="no hold margins"):
        measure_matrix_range(r1(), ())


# -- the history range: the same matrix made in other orders ---------------------------------------
@functools.cache
def r1_history():
    from proleg.sim.physical import measure_history_range

    return measure_history_range(r1(), repeats=1)


def test_the_history_range_holds_every_order_and_its_first_order_is_the_plain_measurement():
    from proleg.sim.physical.measure import ORDERS

    h = r1_history()
    assert h.orders == ORDERS
    np.testing.assert_array_equal(h.at("rows").matrix_mm, measure_matrix(r1(), repeats=1).matrix_mm)
    for order in ORDERS:
        m = h.at(order).matrix_mm
        ok = ~np.isnan(m)
        assert (h.low_mm[ok] <= m[ok]).all() and (m[ok] <= h.high_mm[ok]).all(), order


def test_an_entry_depends_on_what_came_before_it_where_both_limbs_move_not_where_one_does():
    """R1, measured in three orders: the one-limb steps with the other limb down (00↔01, 00↔10)
    are the same whatever came before (within 0.2 mm), but a step into or out of 11 (both limbs
    raised) is not: which end crosses ψ* first depends on the coils' heat the step before left."""
    h, t = r1_history(), r1().transitions
    span = {(t.label(a), t.label(b)): h.high_mm[a, b] - h.low_mm[a, b]
            for a in range(t.n_states) for b in range(t.n_states) if a != b}
    for step in (("00", "01"), ("01", "00"), ("00", "10"), ("10", "00")):
        assert span[step] < 0.2, (step, span[step])
    assert max(span[("00", "11")], span[("11", "00")]) > 0.5, span


def test_the_pooled_matrix_is_the_mean_and_spread_of_every_orders_samples():
    """A brute-force recount: with one sample an order, the pooled entry is the mean of the three
    orders' entries and its spread their population spread; the samples add up."""
    from proleg.sim.physical.measure import pooled

    h = r1_history()
    p = pooled(h.measured)
    stack = np.array([m.matrix_mm for m in h.measured])
    n = r1().transitions.n_states
    for a in range(n):
        for b in range(n):
            if a != b:
                assert p.matrix_mm[a, b] == pytest.approx(float(np.mean(stack[:, a, b])), abs=1e-12)
                assert p.std_mm[a, b] == pytest.approx(float(np.std(stack[:, a, b])), abs=1e-9)
                assert p.samples[a, b] == sum(int(m.samples[a, b]) for m in h.measured) == 3


def test_an_unknown_order_is_refused_before_anything_is_measured():
    from proleg.sim.physical import measure_history_range

    with pytest.raises(ValueError, match="order must be one of rows, reversed, shuffled, got 'sideways'"):
        measure_history_range(None, ("rows", "sideways"))
