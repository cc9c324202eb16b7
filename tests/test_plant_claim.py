"""The claim benchmark's pieces (proleg.report.claim, proleg.sim.openloop.tune_open_loop_robust):
the grid covers every mode singly and in pairs at two strengths, the robust tuner cannot be won
by a knife-edge timing, and a condition the coils cannot physically meet is explained and ends
with a firmware fault and cold coils."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from proleg.report import claim
from proleg.robot import load_robot
from proleg.sim.openloop import OpenLoopDrive, tune_open_loop_robust
from proleg.sim.physical import CONDITION_KEYS, parse_conditions

R1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


def test_the_grid_has_every_mode_singly_at_two_strengths_and_pairs_and_at_least_40_points():
    points = claim.grid()
    assert len(points) >= 40
    singles = {(p.modes[0], p.strength) for p in points if len(p.modes) == 1}
    assert singles == {(m, s) for m in claim.MODES if m not in claim.PAIRED_ONLY for s in ("mild", "strong")}
    pairs = [p for p in points if len(p.modes) == 2]
    assert len(pairs) >= 2 * 10 and {p.strength for p in pairs} == {"mild", "strong"}
    assert claim.PAIRED_ONLY <= {m for p in pairs for m in p.modes}  # each still runs, in a pair
    for p in points:
        parse_conditions(p.conditions)  # every condition string is valid


@pytest.mark.parametrize("mode", sorted(claim.PAIRED_ONLY))
def test_a_mode_run_only_in_pairs_is_the_nominal_robot_alone(mode):
    """On level ground a uniform friction scale changes no contact's share of the grip: the
    same drive moves the plant exactly as the nominal one (so a row of its own could not fail),
    while in its pair on a slope it does change the motion."""
    from proleg.sim.physical import PhysicalPlant

    robot = load_robot(R1)

    def walk(conditions) -> float:
        plant = PhysicalPlant(robot, parse_conditions(conditions))
        for k in range(4000):  # 00 -> 10 -> 11 -> 01 -> 00, 1 s each, at 0.002 s steps
            phase = (k * 0.002) % 4.0
            plant.step(0.002, [0.6 if phase < 2.0 else 0.0, 0.6 if 1.0 <= phase < 3.0 else 0.0])
        return plant.displacement_mm

    strong = claim.MODES[mode][1]
    assert walk(strong) == walk(())
    pair = next(p for p in claim.PAIRS if mode in p)
    other = claim.MODES[pair[0] if pair[1] == mode else pair[1]][1]
    assert walk((*strong, *other)) != walk(other)


def test_every_condition_key_that_is_a_drift_or_error_is_in_the_grid():
    used = {c.split("=")[0] for p in claim.grid() for c in p.conditions}
    # supply_v and fatigue_speedup are covered by power and fatigue_cycles
    assert set(CONDITION_KEYS) - used <= {"supply_v", "fatigue_speedup"}
    assert {f.split(":")[0] for p in claim.grid() for f in p.faults} >= {"drift", "dead-actuator"}


class _FakePlant:
    """Moves at a speed set by the drive's first strength, except at one knife-edge strength
    that is very fast at exactly nominal power and backwards 10 % off it."""

    def __init__(self, power: float):
        self.power = power
        self.displacement_mm = 0.0
        self.time_s = 0.0

        class _A:
            channel = 0

        class _P:
            actuators = (_A(),)

        self.params = _P()
        self.temperature_c = [25.0]

    def reset_peak(self) -> None:
        pass  # its temperature is its hottest already

    @property
    def peak_temperature_c(self) -> list[float]:
        return self.temperature_c

    def step(self, dt: float, duties: list[float]) -> None:
        s = duties[0]
        self.temperature_c = [max(self.temperature_c[0], 25.0 + 100.0 * s)]  # its hottest: 25 + 100 × duty °C
        if s == 0.0:
            return
        if abs(s - 0.7) < 1e-9:
            rate = 10.0 if abs(self.power - 1.0) < 1e-9 else -1.0
        else:
            rate = s
        self.displacement_mm += rate * dt
        self.time_s += dt


def test_the_robust_tuner_scores_the_worst_power_so_a_knife_edge_does_not_win():
    res = tune_open_loop_robust(_FakePlant, (0,), +1, max_duty=0.8, run_s=4.0, dt_s=0.05, budget=200)
    assert res.drive.strength[0] == pytest.approx(0.8)
    assert res.worst_speed_mm_s == pytest.approx(min(res.speed_by_power.values()))
    assert set(res.speed_by_power) == {0.9, 1.0, 1.1}
    assert res.evaluations <= 200


def test_a_drive_that_overheats_its_coil_does_not_win_the_tuning():
    """Duty 0.8 is the fastest but heats the fake coil to 105 °C; 0.7 is the knife edge; so
    with a 100 °C ceiling the best is 0.6 (85 °C), whatever the search order."""
    free = tune_open_loop_robust(_FakePlant, (0,), +1, max_duty=0.8, run_s=4.0, dt_s=0.05, budget=200)
    capped = tune_open_loop_robust(_FakePlant, (0,), +1, max_duty=0.8, run_s=4.0, dt_s=0.05, budget=200,
                                   max_coil_c=100.0)
    assert free.drive.strength[0] == pytest.approx(0.8) and free.peak_coil_c == pytest.approx(105.0)
    assert capped.drive.strength[0] == pytest.approx(0.6) and capped.peak_coil_c == pytest.approx(85.0)
    assert capped.worst_speed_mm_s == pytest.approx(min(capped.speed_by_power.values()))


def test_the_robust_tuner_keeps_to_its_budget():
    res = tune_open_loop_robust(_FakePlant, (0,), +1, run_s=2.0, dt_s=0.1, budget=7)
    assert res.evaluations <= 7


@pytest.mark.slow
def test_a_supply_that_cannot_heat_the_coils_is_explained_and_ends_in_a_fault_with_cold_coils():
    robot = load_robot(R1)
    point = claim.GridPoint("collapse", ("supply collapse",), "strong", ("power=0.2",))
    possible, why = claim.physically_possible(robot, point)
    assert not possible and "cannot transform far enough" in why and "°C" in why
    fb = claim.feedback_run(robot, point, duration_s=20.0)
    assert not fb.completed and fb.fault and fb.coil_max_end_c < 50.0


def test_a_claim_row_of_a_three_limb_robot_is_plain_json():
    """The bench writes every row with json.dumps: a numpy bool from a numpy displacement
    (inchworm-3's plant gave one) stopped `bench_claim.py --robot robots/inchworm-3.toml`
    after the whole grid had run."""
    robot = load_robot(R1.parent / "inchworm-3.toml")
    out = claim.feedback_run(robot, claim.NOMINAL, duration_s=6.0)
    row = json.loads(json.dumps(asdict(out)))
    assert row["completed"] is out.completed
    assert type(out.displacement_mm) is float and type(out.speed_mm_s) is float  # not numpy's


def test_learn_then_walk_on_a_larger_robot_takes_the_firmwares_bound_on_the_cycle():
    """caterpillar-4 has 36 states: the "total" objective needs a bound there, and the bench's
    learned gait stopped with a GaitError before the grid. With the robot file's own matrix as
    if measured, the gait is the firmware's gait 0 (the same objective and bound)."""
    from types import SimpleNamespace

    from proleg.firmware.gaits import firmware_gaits

    robot = load_robot(R1.parent / "caterpillar-4.toml")
    reward, allowed = robot.transitions.dense()
    measured = SimpleNamespace(matrix_mm=np.where(allowed, reward, np.nan), duration_s=np.ones_like(reward))
    want = firmware_gaits(robot)["+x"][0]
    got = claim.optimal_gait_of(robot, measured, "+x")
    assert got == tuple(want.states)


def test_an_open_loop_run_reports_why_it_did_not_complete():
    robot = load_robot(R1)
    idle = OpenLoopDrive((0.0, 0.0), (0.5, 0.5), (2.0, 2.0), (0.0, 1.0))
    out = claim.open_loop_run(robot, idle, claim.NOMINAL, duration_s=6.0)
    assert not out.completed and out.note.startswith("stalled") and out.fault == ""


@pytest.mark.slow
def test_the_feedback_run_calibrates_on_the_flat_first_like_a_user():
    """A front IMU mounted 6° crooked: uncalibrated the firmware cannot see state 10 (it stops);
    after the flat calibration the bench does first (proleg calibrate) it walks."""
    robot = load_robot(R1)
    point = claim.point("imu mounting offset (strong)")
    raw = claim.feedback_run(robot, point, duration_s=20.0, calibrate=False)
    cal = claim.feedback_run(robot, point, duration_s=20.0)
    assert cal.completed and cal.speed_mm_s > 0 and not cal.note
    assert cal.speed_mm_s > raw.speed_mm_s


@pytest.mark.slow
def test_on_a_slope_after_the_flat_calibration_the_firmware_levels_itself_at_rest():
    """Decline 10°, calibrated on the flat only: each end's IMU reads ψ ∓ 10°. Put down on the
    slope and started at once, no true pose reads as state 10 (STATE_TIMEOUT, cold coils);
    started after the 2.5 s at rest the bench leaves (as a user would), the firmware levels on
    the slope by itself and walks, as it does levelled by hand (--ground)."""
    robot = load_robot(R1)
    point = claim.point("decline (strong)")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(claim, "REST_ON_GROUND_S", 0.0)
        at_once = claim.feedback_run(robot, point, duration_s=20.0)
    assert not at_once.completed and "STATE_TIMEOUT" in at_once.fault and at_once.coil_max_end_c < 50.0
    rested = claim.feedback_run(robot, point, duration_s=20.0)
    assert rested.completed and rested.fault == "" and not rested.note
    levelled = claim.feedback_run(robot, point, duration_s=20.0, level_on_ground=True)
    assert levelled.fault == "" and not levelled.note


def test_learn_then_walk_gives_a_gait_the_measured_matrix_says_goes_plus_x():
    robot = load_robot(R1)
    states, m = claim.learned_gait(robot, "+x")
    assert states[0] == states[-1] and len(states) >= 3
    assert sum(m.matrix_mm[a][b] for a, b in zip(states, states[1:])) > 0


@pytest.mark.slow
def test_r1_held_at_full_strokes_outwalks_the_best_open_loop_on_the_nominal_robot():
    """Issue 13's nominal target, for R1's body with its limbs raised to full strokes
    (robots/paper-r1-stroke.toml): the ψ-feedback firmware, started as a user would, against
    the open loop the bench tunes (all 7 parameters, 150 drives, worst of ±10 % power) on
    the same plant. With R1's own file (the paper's gait) it is 16 × slower: docs/control.md."""
    robot = load_robot(R1.parent / "paper-r1-stroke.toml")
    tuned = claim.tune_open_loop_for(robot, "+x", budget=150)
    fb = claim.feedback_run(robot, claim.NOMINAL)
    assert fb.completed and fb.fault == "" and not fb.note
    assert fb.speed_mm_s >= tuned.speed_by_power[1.0] > 0, (fb.speed_mm_s, tuned.speed_by_power)


@pytest.mark.parametrize("name, mild, strong", [
    ("paper-r1", "sma-right", "sma-left"),
    ("paper-r1-one-actuator", "sma-left", "sma-left"),  # one coil: both strengths kill it
    ("caterpillar-4", "sma-front", "sma-rear"),          # its limbs named front and rear
])
def test_the_dead_coil_rows_kill_an_end_coil_of_any_robot(name, mild, strong):
    """The grid named R1's coils: on a robot without sma-right the worker died and the bench
    stopped after the grid with a TypeError."""
    robot = load_robot(R1.parent / f"{name}.toml")
    for strength, coil in (("mild", mild), ("strong", strong)):
        plant = claim._plant(robot, claim.point(f"dead coil ({strength})"))
        nch = max(a.channel for a in robot.actuators) + 1
        for _ in range(500):
            plant.step(0.002, [0.8] * nch)
        temps = {a.name: t for a, t in zip(robot.actuators, plant.temperature_c)}
        assert temps[coil] < 26.0 and all(t > 30.0 for n, t in temps.items() if n != coil), (strength, temps)


@pytest.mark.parametrize("cycle_s, run_s", [(None, 40.0), (4.2, 40.0), (10.0, 40.0), (12.3, 50.0), (15.0, 60.0)])
def test_a_long_gait_gets_runs_of_four_nominal_cycles(cycle_s, run_s):
    """A run completes with two cycles: caterpillar-4's ≈ 15 s cycles in a 40 s run ended
    after one in seven slowed rows. Short gaits keep RUN_S."""
    assert claim.run_length(claim.IdealisedWalk(cycle_s is not None, "", 1.0, cycle_s)) == run_s


def test_the_run_length_comes_from_the_idealised_drives_nominal_cycle():
    def nominal(name: str) -> claim.IdealisedWalk:
        return claim.idealised_walk(load_robot(R1.parent / f"{name}.toml"), claim.NOMINAL)

    assert claim.run_length(nominal("paper-r1")) == claim.RUN_S
    assert claim.run_length(nominal("caterpillar-4")) > claim.RUN_S


def test_a_heavier_body_warms_more_slowly_which_is_all_its_mass_changes():
    """mass_g is the body node's heat capacity: every force of the quasi-static crawl scales
    with the weight, so the mass acts through the body's temperature alone."""
    from proleg.sim.physical import PhysicalPlant

    robot = load_robot(R1)
    body = {}
    for mass in (3.3, 8.0):
        plant = PhysicalPlant(robot, parse_conditions((f"mass_g={mass}",)))
        for _ in range(6000):
            plant.step(0.005, [0.3, 0.3])
        body[mass] = plant.body_temperature_c
    ambient = parse_conditions(()).get("ambient_c")
    assert body[3.3] - ambient > 0.8  # the coils warm the body ...
    assert 0 < body[8.0] - ambient < 0.6 * (body[3.3] - ambient)  # ... a heavier one less in 30 s
