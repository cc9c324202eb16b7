"""The default plant is controllable: a toy ψ-feedback loop walks the paper's gaits, and it keeps
its displacement per cycle under SMA drift where the tuned open-loop timing does not (SPEC §1)."""

from __future__ import annotations

import numpy as np
import pytest

from proleg.sim.openloop import OpenLoopDrive, run_open_loop, tune_open_loop
from proleg.sim.plant import Plant, PlantParams

R1 = np.array([[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]], float)
X = np.nan
R1_LEFT_ONLY = np.array([[0, X, 1, X], [X, X, X, X], [-1, X, 0, 1], [X, X, 0, 0]], float)
STEP = PlantParams().step_mm


def digits(state: int, levels) -> list[int]:
    out = []
    for k in reversed(levels):
        state, d = divmod(state, k)
        out.append(d)
    return out[::-1]


def walk(plant: Plant, gait, cycles, limb_channel, duty=0.6, dt=0.002, hold_s=0.1, timeout_s=6.0,
         on_below=3.0, off_above=10.0, down_margin=1.0):
    """Toy bang-bang on the TRUE ψ: a limb that must be up switches its coil on below
    ψ* + on_below and off above ψ* + off_above; a limb that must be down switches it off.
    A target counts as reached when the true state holds it for hold_s. Returns the times."""
    levels = plant.levels
    limbs = plant.params.limbs
    nch = max(a.channel for a in plant.params.actuators) + 1
    on = [False] * nch
    reached = []
    for target in list(gait[1:]) * cycles:
        want = digits(target, levels)
        t0, held = plant.time_s, 0.0
        while held < hold_s:
            psi = plant.psi_deg
            up: list[bool | None] = [None] * nch
            down = [False] * nch
            for i, lvl in enumerate(want):
                ps, ch = limbs[i].psi_star_deg, limb_channel[i]
                if lvl >= 1:
                    if psi[i] < ps[lvl - 1] + on_below:
                        up[ch] = True
                    elif psi[i] >= ps[lvl - 1] + off_above and up[ch] is None:
                        up[ch] = False
                if lvl < len(ps) and psi[i] >= ps[lvl] - down_margin:
                    down[ch] = True
            for c in range(nch):
                if down[c] or up[c] is False:
                    on[c] = False
                elif up[c]:
                    on[c] = True
                elif not any(limb_channel[i] == c and want[i] >= 1 for i in range(len(want))):
                    on[c] = False
            plant.step(dt, [duty if on[c] else 0.0 for c in range(nch)])
            held = held + dt if plant.true_state == target else 0.0
            assert plant.time_s - t0 < timeout_s, f"state {target} not reached within {timeout_s} s"
        reached.append(plant.time_s)
    return reached


def per_cycle_feedback(plant: Plant, gait, limb_channel, cycles=3) -> tuple[float, float]:
    walk(plant, gait, 1, limb_channel)                 # first cycle starts cold: not counted
    x0, t0 = plant.displacement_mm, plant.time_s
    walk(plant, gait, cycles, limb_channel)
    return (plant.displacement_mm - x0) / cycles, (plant.time_s - t0) / cycles


@pytest.mark.parametrize("gait", [[0, 2, 1, 0], [0, 1, 2, 0], [0, 2, 3, 1, 0], [0, 1, 3, 2, 0]])
def test_psi_feedback_reaches_every_state_of_the_paper_gaits_within_seconds(gait):
    p = Plant(PlantParams(), R1)
    times = walk(p, gait, 3, [0, 1])
    n = len(gait) - 1
    cycle_s = (times[-1] - times[n - 1]) / 2
    assert cycle_s < 4.0


def test_psi_feedback_walks_the_loss_of_actuation_gait_with_the_left_coil_only():
    p = Plant(PlantParams(), R1_LEFT_ONLY)
    p.kill_actuator(1)
    per_cycle, _ = per_cycle_feedback(p, [0, 2, 3, 2, 0], [0, 0])
    assert per_cycle == pytest.approx(1 * STEP)       # the paper's C_L1: +1 per cycle
    assert p.unexpected_transitions == 0


def test_open_loop_drive_has_the_papers_seven_parameters_and_pulses():
    d = OpenLoopDrive.two(0.6, 0.5, 2.0, 0.4, 0.8, 2.0, 1.0)
    assert d.n_parameters == 7
    assert d.duties(0.1) == [0.6, 0.0]
    assert d.duties(1.1) == [0.0, 0.4]
    assert d.duties(2.3) == [0.6, 0.0]
    assert d.duties(1.9) == [0.0, 0.0]


@pytest.fixture(scope="module")
def tuned():
    return tune_open_loop(PlantParams(), R1, +1)


def drifted(step: float) -> Plant:
    p = Plant(PlantParams(), R1)
    for ch in (0, 1):
        p.inject_drift(ch, rate=0.0, mode="power", step=step)
    return p


def test_tuned_open_loop_walks_forward_on_the_fresh_plant(tuned):
    assert tuned.displacement_per_cycle_mm >= 2 * STEP
    p = Plant(PlantParams(), R1)
    run_open_loop(p, tuned.drive, tuned.drive.period_s)
    x = run_open_loop(p, tuned.drive, 4 * tuned.drive.period_s)
    assert x / 4 == pytest.approx(tuned.displacement_per_cycle_mm)


def test_under_sma_drift_psi_feedback_keeps_its_displacement_per_cycle_and_open_loop_does_not(tuned):
    gait = [0, 2, 3, 1, 0]
    fresh_fb, fresh_cycle_s = per_cycle_feedback(Plant(PlantParams(), R1), gait, [0, 1])
    assert fresh_fb == pytest.approx(3 * STEP)
    for step in (0.2, 0.3):
        fb, cycle_s = per_cycle_feedback(drifted(step), gait, [0, 1])
        assert fb == pytest.approx(fresh_fb)           # same displacement per cycle ...
        assert cycle_s > fresh_cycle_s                 # ... the coils just take longer
        q = drifted(step)
        run_open_loop(q, tuned.drive, tuned.drive.period_s)
        ol = run_open_loop(q, tuned.drive, 3 * tuned.drive.period_s) / 3
        assert ol < 0.5 * tuned.displacement_per_cycle_mm
