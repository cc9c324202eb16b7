"""The simulated robot body: thermal model, SMA hysteresis, ψ, true state, displacement, faults."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import SimError
from proleg.sim.plant import PASS_S, LimbParams, Plant, PlantParams
from proleg.sim.sma import Hysteresis, SmaParams, cooling_branch, heating_branch

R1 = np.array([[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]], float)
X = np.nan
R1_LEFT_ONLY = np.array([[0, X, 1, X], [X, X, X, X], [-1, X, 0, 1], [X, X, 0, 0]], float)
SMA = SmaParams()


def time_to(plant: Plant, cond, duties, dt=0.001, limit=10.0) -> float:
    t0 = plant.time_s
    while not cond(plant):
        plant.step(dt, duties)
        if plant.time_s - t0 > limit:
            raise AssertionError("condition not reached")
    return plant.time_s - t0


# -- thermal ---------------------------------------------------------------------------------------
def test_temperature_covers_63_percent_of_its_rise_after_one_time_constant():
    p = Plant()
    tau, duty = SMA.tau_s, 0.6
    rise = duty * SMA.full_power_w / SMA.conductance_w_per_k
    n = round(tau / 0.001)
    for _ in range(n):
        p.step(0.001, [duty, 0.0])
    got = (p.temperature_c[0] - 25.0) / rise
    assert got == pytest.approx(1 - math.exp(-1), abs=1e-6)
    assert 0.5 <= tau <= 3.0


def test_thermal_step_is_exact_for_any_step_size():
    fine, coarse = Plant(), Plant()
    for _ in range(2000):
        fine.step(0.0005, [0.7, 0.2])
    coarse.step(1.0, [0.7, 0.2])
    assert coarse.temperature_c == pytest.approx(fine.temperature_c, abs=1e-9)


def test_temperature_relaxes_to_ambient_when_off():
    p = Plant()
    p.step(2.0, [0.8, 0.8])
    p.step(30.0, [0.0, 0.0])
    assert p.temperature_c == pytest.approx([25.0, 25.0], abs=1e-6)


# -- Liang–Rogers hysteresis ------------------------------------------------------------------------
def sweep(h: Hysteresis, temps):
    return [h.update(t) for t in temps]


def test_heating_and_cooling_branches_differ():
    h = Hysteresis(SMA.as_c, SMA.af_c, SMA.ms_c, SMA.mf_c, temp=25.0)
    up = np.linspace(25, 100, 301)
    heating = dict(zip(up, sweep(h, up)))
    down = up[::-1]
    cooling = dict(zip(down, sweep(h, down)))
    mid_heat = (SMA.as_c + SMA.af_c) / 2
    mid_cool = (SMA.ms_c + SMA.mf_c) / 2
    assert heating[25.0] == 0.0 and heating[100.0] == 1.0
    assert cooling[100.0] == 1.0 and cooling[25.0] == 0.0
    # 60 °C: still martensite on the way up, still austenite on the way down
    t60 = up[np.argmin(abs(up - 60))]
    assert heating[t60] == 0.0 and cooling[t60] == 1.0
    assert heating_branch(mid_heat, SMA.as_c, SMA.af_c) == pytest.approx(0.5)
    assert cooling_branch(mid_cool, SMA.ms_c, SMA.mf_c) == pytest.approx(0.5)


def test_partial_heating_then_reheating_returns_to_the_same_point_without_a_jump():
    h = Hysteresis(SMA.as_c, SMA.af_c, SMA.ms_c, SMA.mf_c, temp=25.0)
    sweep(h, np.linspace(25, 73, 100))
    a_peak = h.alpha
    assert 0.3 < a_peak < 0.7
    sweep(h, np.linspace(73, 60, 50))       # cooling above Ms: no reverse transformation
    assert h.alpha == a_peak
    sweep(h, np.linspace(60, 73, 50))       # reheating: nothing happens until the old peak
    assert h.alpha == pytest.approx(a_peak)
    h.update(75.0)
    assert h.alpha == pytest.approx(heating_branch(75.0, SMA.as_c, SMA.af_c))


def test_partial_cooling_then_heating_starts_from_the_reversal_fraction():
    h = Hysteresis(SMA.as_c, SMA.af_c, SMA.ms_c, SMA.mf_c, temp=25.0)
    sweep(h, np.linspace(25, 100, 100))
    sweep(h, np.linspace(100, 47, 100))
    a_r = h.alpha
    assert a_r == pytest.approx(0.5, abs=0.01)
    sweep(h, np.linspace(47, SMA.af_c, 200))
    assert h.alpha == pytest.approx(1.0)


# The steepest a Liang–Rogers branch gets: π/2 per transformation band.
SLOPE = math.pi / 2 / min(SMA.af_c - SMA.as_c, SMA.ms_c - SMA.mf_c)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(min_value=10.0, max_value=120.0), min_size=1, max_size=60))
def test_fraction_stays_in_0_1_and_moves_continuously_under_any_temperature_history(temps):
    h = Hysteresis(SMA.as_c, SMA.af_c, SMA.ms_c, SMA.mf_c, temp=25.0)
    t_prev, a_prev = 25.0, 0.0
    for t in temps:
        a = h.update(t)
        assert 0.0 <= a <= 1.0
        assert abs(a - a_prev) <= SLOPE * abs(t - t_prev) + 1e-12
        if t > t_prev:
            assert a >= a_prev
        elif t < t_prev:
            assert a <= a_prev
        t_prev, a_prev = t, a


# -- body, ψ, state --------------------------------------------------------------------------------
def test_psi_crosses_psi_star_within_a_second_at_duty_06_and_relaxes_when_off():
    p = Plant(PlantParams(), R1)
    t_up = time_to(p, lambda q: q.psi_deg[0] >= 20.0, [0.6, 0.0])
    assert 0.3 <= t_up <= 0.8
    assert p.dpsi_dps[0] > 0
    assert p.true_state == 2            # "10"
    t_down = time_to(p, lambda q: q.psi_deg[0] < 20.0, [0.0, 0.0])
    assert 0.5 <= t_down <= 1.5
    p.step(10.0, [0.0, 0.0])
    assert p.psi_deg == pytest.approx([0.0, 0.0], abs=1e-6)
    assert p.dpsi_dps == pytest.approx([0.0, 0.0], abs=1e-6)


def test_dpsi_is_the_rate_of_change_of_psi():
    p = Plant()
    for _ in range(700):
        p.step(0.001, [0.6, 0.0])
    psi0, rate = p.psi_deg[0], p.dpsi_dps[0]
    p.step(0.0001, [0.6, 0.0])
    assert (p.psi_deg[0] - psi0) / 0.0001 == pytest.approx(rate, rel=0.02)


def test_left_actuator_alone_goes_00_10_11_and_back_through_10():
    p = Plant(PlantParams(), R1_LEFT_ONLY)
    p.kill_actuator(1)
    for _ in range(3000):
        p.step(0.002, [0.6, 0.6])
    assert p.true_state == 3
    for _ in range(3000):
        p.step(0.002, [0.0, 0.6])
    assert [(a, b) for _, a, b, _ in p.transitions] == [(0, 2), (2, 3), (3, 2), (2, 0)]
    assert p.unexpected_transitions == 0
    assert p.displacement_mm == pytest.approx((1 + 1 + 0 - 1) * p.params.step_mm)


def test_dead_actuator_never_heats():
    p = Plant()
    p.kill_actuator(0)
    for _ in range(500):
        p.step(0.02, [1.0, 0.0])
    assert p.temperature_c[0] == 25.0
    assert p.austenite[0] == 0.0
    assert p.psi_deg[0] == 0.0
    assert p.power_factor[0] == 0.0


def test_power_drift_slows_the_response():
    fresh, aged = Plant(), Plant()
    aged.inject_drift(0, rate=0.0, step=0.3)
    t_fresh = time_to(fresh, lambda q: q.psi_deg[0] >= 20.0, [0.6, 0.0])
    t_aged = time_to(aged, lambda q: q.psi_deg[0] >= 20.0, [0.6, 0.0])
    assert t_aged > 1.3 * t_fresh


def test_power_drift_grows_with_on_time():
    p = Plant()
    p.inject_drift(0, rate=0.02)
    for _ in range(100):
        p.step(0.1, [0.5, 0.0])
    assert p.power_factor[0] == pytest.approx(math.exp(-0.02 * 5.0))
    assert p.power_factor[1] == 1.0


def test_temperature_drift_slows_the_response():
    fresh, aged = Plant(), Plant()
    aged.inject_drift(0, rate=0.0, mode="temperature", step=8.0)
    t_fresh = time_to(fresh, lambda q: q.psi_deg[0] >= 20.0, [0.6, 0.0])
    t_aged = time_to(aged, lambda q: q.psi_deg[0] >= 20.0, [0.6, 0.0])
    assert t_aged > 1.2 * t_fresh


def test_stroke_drift_lowers_the_reachable_angle():
    p = Plant()
    p.inject_drift(0, rate=0.0, mode="stroke", step=0.5)
    p.step(5.0, [1.0, 0.0])
    p.step(0.5, [1.0, 0.0])
    assert p.psi_deg[0] == pytest.approx(0.5 * p.params.direct_gain_deg, rel=1e-3)


def scripted_drive(p: Plant, seed: int = 1, seconds: float = 40.0, dt: float = 0.002) -> None:
    """Random pulses: one coil, the other, both or none, each for 0.3–1.2 s."""
    rng = np.random.default_rng(seed)
    patterns = [(0.6, 0.0), (0.0, 0.6), (0.8, 0.0), (0.0, 0.8), (0.6, 0.6), (0.0, 0.0), (0.0, 0.0)]
    t = 0.0
    while t < seconds:
        duties = list(patterns[int(rng.integers(len(patterns)))])
        hold = float(rng.uniform(0.3, 1.2))
        for _ in range(int(hold / dt)):
            p.step(dt, duties)
        t += hold


def test_displacement_is_the_sum_of_true_rewards_over_the_true_transitions():
    p = Plant(PlantParams(noise_mm=0.0), R1)
    scripted_drive(p)
    trans = p.transitions
    assert len(trans) >= 10
    expected = sum(R1[a, b] for _, a, b, _ in trans) * p.params.step_mm
    assert p.displacement_mm == pytest.approx(expected)
    # consecutive: each transition starts where the previous ended
    assert all(x.dst == y.src for x, y in zip(trans, trans[1:]))
    assert all(x.src != x.dst for x in trans)


class ScriptedPlant(Plant):
    """The table plant with its true state given as (from time s, state) instead of from ψ."""

    def __init__(self, script, rewards=R1_LEFT_ONLY):
        self.script = script
        super().__init__(PlantParams(noise_mm=0.0), rewards)

    def _classify(self) -> int:
        return [s for t, s in self.script if getattr(self, "_t", 0.0) >= t - 1e-9][-1]


def _run(script, seconds, rewards=R1_LEFT_ONLY):
    p = ScriptedPlant([(0.0, 0)] + script, rewards)
    for _ in range(round(seconds / 0.01)):
        p.step(0.01, [0.0, 0.0])
    return [(a, b, r) for _, a, b, r in p.transitions], p.unexpected_transitions


def test_a_forbidden_transition_that_happens_earns_nothing_and_is_counted():
    # the table says the right end cannot move (00 -> 01 forbidden): it happened, at once
    assert _run([(1.0, 1)], 1.1) == ([(0, 1, 0.0)], 1)


def test_a_state_passed_through_on_the_way_to_an_allowed_one_is_one_transition():
    """Full strokes' leads cross one limb first on purpose: 00 -> 10 -> 11, both legs forbidden,
    is the matrix's 00 -> 11. The table plant counted two unexpected transitions and 0 mm."""
    stroke = np.array([[0, X, X, 4.0], [X, 0, X, X], [X, X, 0, X], [1.0, X, X, 0]], float)
    step = PlantParams().step_mm
    moves, unexpected = _run([(1.0, 2), (3.5, 3), (6.0, 1), (7.0, 0)], 9.0, stroke)
    assert (moves, unexpected) == ([(0, 3, 4.0 * step), (3, 0, 1.0 * step)], 0)
    assert _run([(1.0, 2)], 3.0, stroke) == ([(0, 2, 0.0)], 1)  # held there: it happened (so far)
    assert _run([(1.0, 2), (1.0 + PASS_S + 0.5, 3)], PASS_S + 3.0, stroke) == ([(0, 2, 0.0), (2, 3, 0.0)], 2)  # too long
    assert _run([(1.0, 1), (2.0, 0)], 3.0) == ([(0, 1, 0.0), (1, 0, 0.0)], 2)  # there and back: no pass
    # a second leg the table allows is its own transition (caterpillar-4's proleg lifted past
    # its second edge: what the firmware's step really did on this body, as before)
    allowed_on = R1_LEFT_ONLY.copy()
    allowed_on[1, 3] = 1.0  # 00 -> 01 forbidden, 01 -> 11 allowed
    assert _run([(1.0, 1), (2.0, 3)], 3.0, allowed_on) == ([(0, 1, 0.0), (1, 3, step)], 1)
    # both legs forbidden and the whole too (00 -> 01 -> 11 on R1_LEFT_ONLY): two unexpected
    assert _run([(1.0, 1), (2.0, 3)], 3.0) == ([(0, 1, 0.0), (1, 3, 0.0)], 2)
    # both legs forbidden, the whole allowed, but a limb past its end level and back (00 -> 11
    # -> 10: the right end lifted and dropped): what happened, not a pass
    only_left = np.where(np.eye(4) > 0, 0.0, X)
    only_left[0, 2] = 1.0  # 00 -> 10 allowed, nothing else
    assert _run([(1.0, 3), (2.0, 2)], 3.0, only_left) == ([(0, 3, 0.0), (3, 2, 0.0)], 2)
    assert _run([(1.0, 3), (2.0, 2)], 3.0, stroke) == ([(0, 3, 4.0 * step), (3, 2, 0.0)], 1)  # 00 -> 11 allowed


def test_noise_is_deterministic_for_a_seed():
    runs = []
    for seed in (7, 7, 8):
        p = Plant(PlantParams(noise_mm=0.5), R1, seed=seed)
        scripted_drive(p, seconds=15.0)
        runs.append(p.displacement_mm)
    assert runs[0] == runs[1]
    assert runs[0] != runs[2]
    assert runs[0] != pytest.approx(round(runs[0] / 4.0) * 4.0, abs=1e-9)


def test_changes_of_two_limbs_within_the_window_are_one_transition():
    p = Plant(PlantParams(), R1)
    for _ in range(1500):
        p.step(0.002, [0.6, 0.6])    # identical coils, identical drive: both ends cross together
    assert [(a, b) for _, a, b, _ in p.transitions] == [(0, 3)]
    p2 = Plant(PlantParams(simultaneous_s=0.0), R1)
    p2.step(0.5, [0.6, 0.6])
    p2.step(0.5, [0.6, 0.6])
    assert p2.true_state == 3


def test_state_index_is_mixed_radix_with_the_first_limb_most_significant():
    params = PlantParams(
        limbs=(LimbParams("front", (10.0, 30.0), actuator=0), LimbParams("rear", (20.0,), actuator=1)),
    )
    p = Plant(params, np.zeros((6, 6)))
    assert p.levels == (3, 2)
    p.step(5.0, [1.0, 0.0])      # front ψ = 60° (level 2), rear ψ = 27° (level 1)
    assert p.limb_levels == (2, 1)
    assert p.true_state == 2 * 2 + 1


def test_bad_inputs_raise_sim_errors():
    p = Plant()
    with pytest.raises(SimError, match="outside 0..1"):
        p.step(0.001, [1.5, 0.0])
    with pytest.raises(SimError, match="1 duty given"):
        p.step(0.001, [0.5])
    with pytest.raises(SimError, match="dt_s"):
        p.step(0.0, [0.5, 0.5])
    with pytest.raises(SimError, match="channel 5"):
        p.kill_actuator(5)
    with pytest.raises(SimError, match="mode"):
        p.inject_drift(0, 0.1, mode="magic")
    with pytest.raises(SimError, match="true_rewards"):
        Plant(PlantParams(), np.zeros((3, 3)))
    with pytest.raises(SimError, match="levels"):
        Plant(PlantParams(), None, levels=(3, 2))
    with pytest.raises(SimError, match="af_c"):
        Plant(replace(PlantParams(), actuators=(SmaParams(as_c=90.0), SmaParams(channel=1))))
