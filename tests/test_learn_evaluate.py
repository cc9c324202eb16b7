"""learn.evaluate's plant windows against the plant itself: a trial's motion is what the
pose moved between the explorer's two reads (``settle_s`` = WINDOW_SHIFT_S after each
STATE_REACHED event), so ``plant_changes`` must give each trial exactly the plant changes
whose motion landed between those reads, and ``effective_truth`` (noise-free) what the
trials measured. The oracle steps a table plant whose true state follows a script and reads
its displacement at every pose time."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from proleg.learn.estimate import estimate
from proleg.learn.evaluate import WINDOW_SHIFT_S, effective_truth, plant_changes
from proleg.learn.measure import Trial
from proleg.sim.plant import Plant, PlantParams
from proleg.transitions import TransitionTable

DT = 0.002  # the simulated link's step
LEVELS = (2, 2)
N = 4
#: every change of state allowed (no passes), each with its own reward (steps)
REWARD = np.array([[0, -1, 1, 2], [1.5, 0, -2.5, -1], [-1.2, 3, 0, 1], [0.5, 2.2, -0.7, 0]], float)


class ScriptedPlant(Plant):
    """The table plant with its true state given as (from time s, state) instead of from ψ."""

    def __init__(self, script, rewards=REWARD, noise_mm=0.0):
        self.script = script
        super().__init__(PlantParams(noise_mm=noise_mm), rewards, LEVELS)

    def _classify(self) -> int:
        return [s for t, s in self.script if getattr(self, "_t", 0.0) >= t - 1e-9][-1]


def _table() -> TransitionTable:
    src, dst = zip(*[(a, b) for a in range(N) for b in range(N) if a != b])
    return TransitionTable(LEVELS, np.array(src), np.array(dst), REWARD[list(src), list(dst)])


def _explore(change_gaps, states, event_steps, noise_mm=0.0):
    """Step the scripted plant in DT and take the explorer's trials: an event at each of
    ``event_steps`` (DT grid, half a step off so no booking ties with a pose read), the pose
    WINDOW_SHIFT_S later; a trial from each event to the next whose states differ."""
    script, t = [(0.0, 0)], 0.0
    for gap, s in zip(change_gaps, states):
        t += gap
        script.append((t, (script[-1][1] + s) % N))
    plant = ScriptedPlant(script, noise_mm=noise_mm)
    events = np.cumsum(event_steps) * DT + DT / 2 - WINDOW_SHIFT_S
    times, disp, state = [0.0], [0.0], [plant.true_state]
    while plant.time_s < events[-1] + WINDOW_SHIFT_S + 2 * DT:
        plant.step(DT, [0.0, 0.0])
        times.append(plant.time_s)
        disp.append(plant.displacement_mm)
        state.append(plant.true_state)

    def at(t_s, series):  # the plant as it was at time t_s (its last step not after it)
        return series[int(np.searchsorted(times, t_s, side="right")) - 1]

    table = _table()
    trials = []
    for t0, t1 in zip(events, events[1:]):
        a, b = at(t0, state), at(t1, state)
        if a != b:
            dx = at(t1 + WINDOW_SHIFT_S, disp) - at(t0 + WINDOW_SHIFT_S, disp)
            trials.append(Trial(table.label(a), table.label(b), float(t0), float(t1), dx, source="sim"))
    return table, plant, trials


CHANGES = st.lists(st.floats(0.004, 0.6), min_size=1, max_size=12)
STATES = st.lists(st.integers(1, N - 1), min_size=12, max_size=12)
EVENTS = st.lists(st.integers(5, 400), min_size=2, max_size=14)


@settings(max_examples=150, deadline=None)
@given(CHANGES, STATES, EVENTS)
# a change whose first limb crosses at 0.3 s, 9 ms before a pose read, and is booked 21 ms after it
@example([0.3, 0.6], [1] * 12, [154, 200, 200])
def test_each_trial_gets_the_plant_motion_booked_between_its_pose_reads(change_gaps, states, event_steps):
    table, plant, trials = _explore(change_gaps, states, event_steps, noise_mm=0.5)
    for tr, seen in zip(trials, plant_changes(trials, plant.transitions)):
        assert sum(p.reward_mm for p in seen) == pytest.approx(tr.dx, abs=1e-9), (tr, seen)


@settings(max_examples=60, deadline=None)
@given(CHANGES, STATES, EVENTS)
@example([0.3, 0.6], [1] * 12, [154, 200, 200])
def test_on_a_noise_free_plant_the_effective_truth_is_what_the_trials_measured(change_gaps, states, event_steps):
    table, plant, trials = _explore(change_gaps, states, event_steps)
    truth_mm = REWARD * plant.params.step_mm
    eff = effective_truth(table, truth_mm, trials, plant.transitions)
    est = estimate(table, trials)
    measured = ~np.isnan(est.dx.mean)
    assert np.allclose(eff.reward[measured], est.dx.mean[measured], atol=1e-9)
    assert np.allclose(eff.reward[~measured], truth_mm[table.src, table.dst][~measured])


def test_a_change_is_booked_when_its_motion_is_added():
    """Booked simultaneous_s after its first limb crossed; a pass (both legs forbidden, the
    whole allowed) when its last leg is: the motion is in displacement_mm from then on."""
    x = np.nan
    stroke = np.array([[0, x, x, 4.0], [x, 0, x, x], [x, x, 0, x], [1.0, x, x, 0]], float)
    plant = ScriptedPlant([(0.0, 0), (1.0, 2), (3.5, 3), (6.0, 0)], stroke)
    booked = []
    last = 0.0
    while plant.time_s < 7.0:
        plant.step(DT, [0.0, 0.0])
        if plant.displacement_mm != last:
            booked.append(plant.time_s)
            last = plant.displacement_mm
    w = plant.params.simultaneous_s
    got = plant.transitions
    assert [(p.src, p.dst) for p in got] == [(0, 3), (3, 0)]
    assert [p.t_s for p in got] == pytest.approx([1.0, 6.0], abs=DT)
    assert [p.t_booked_s for p in got] == pytest.approx(booked)
    assert booked == pytest.approx([3.5 + w, 6.0 + w], abs=DT)
