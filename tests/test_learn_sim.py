"""Proof on the simulated robot: learn paper-r1's matrix through the real firmware in
closed loop with a table plant whose (hidden, noisy) truth matrix moves the robot."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from proleg.gait import optimal_gaits
from proleg.gait.evaluate import evaluate_sequence
from proleg.learn.estimate import estimate, penalised_table
from proleg.learn.evaluate import effective_truth, plant_changes
from proleg.learn.measure import TrialLog, counts
from proleg.learn.robotfile import write_learned_robot
from proleg.learn.simulated import explore_simulated
from proleg.robot import load_robot
from proleg.transitions import TransitionTable

ROOT = Path(__file__).resolve().parent.parent
R1 = ROOT / "robots" / "paper-r1.toml"
NOISE_MM = 0.5
REPEATS = 5


def _truth_file(tmp: Path) -> Path:
    """paper-r1 with its matrix in mm (4 mm per step, each entry ±10 %), noise per transition."""
    from proleg.learn.truth import write_truth

    return write_truth(R1, tmp / "truth.toml", noise_mm=NOISE_MM)


@pytest.fixture(scope="module")
def learned(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("learn-sim")
    robot, truth = load_robot(R1), load_robot(_truth_file(tmp))
    with TrialLog(tmp / "trials.jsonl") as log:
        _added, sim = explore_simulated(robot, truth, log, repeats=REPEATS, seed=3)
        trials = list(log.trials)
    return robot, truth, trials, sim, tmp


def _effective_truth(robot, truth, trials, sim) -> np.ndarray:
    """Noise-free mm per firmware transition: a transition that changes both limbs passes
    through an intermediate state in the plant, whose truth entries then add up (the table
    plant looks up every state change it sees)."""
    mm = np.nan_to_num(truth.transitions.dense()[0]) * 1.0
    return effective_truth(robot.transitions, mm, trials, sim.plant.transitions).reward


def test_every_allowed_transition_is_measured_at_least_r_times(learned):
    robot, _truth, trials, _sim, _tmp = learned
    assert counts(robot.transitions, trials).min() >= REPEATS
    assert all(t.source == "sim" and t.dx is not None for t in trials)


def test_the_learned_matrix_has_the_truths_sign_wherever_the_truth_moves(learned):
    robot, truth, trials, _sim, _tmp = learned
    est = estimate(robot.transitions, trials)
    tv = truth.transitions.reward
    moving = np.abs(tv) > 1.0
    assert moving.sum() == 6
    assert np.all(np.sign(est.dx.mean[moving]) == np.sign(tv[moving]))


def test_at_least_90_percent_of_the_means_are_within_their_95_percent_interval(learned):
    robot, truth, trials, sim, _tmp = learned
    est = estimate(robot.transitions, trials)
    eff = _effective_truth(robot, truth, trials, sim)
    # the single-limb transitions are the truth file's entries (up to a limb that falls, rises
    # again and falls within one trial: the plant then adds all three of its changes)
    single = [sum(x != y for x, y in zip(robot.transitions.label(a), robot.transitions.label(b))) == 1
              for a, b in zip(robot.transitions.src, robot.transitions.dst)]
    assert np.allclose(eff[single], truth.transitions.reward[single], atol=0.25)
    inside = np.abs(est.dx.mean - eff) <= est.dx.half_width
    assert inside.mean() >= 0.9, (est.dx.mean, eff, est.dx.half_width)


def test_the_gait_from_the_learned_matrix_is_at_least_95_percent_as_fast_as_the_true_optimum(learned):
    robot, truth, trials, sim, tmp = learned
    est = estimate(robot.transitions, trials)
    out = write_learned_robot(robot, est, tmp / "learned.toml", units="mm")
    learned_robot = load_robot(out)
    eff = TransitionTable(robot.levels, robot.transitions.src, robot.transitions.dst,
                          _effective_truth(robot, truth, trials, sim))
    best = optimal_gaits(eff, "rate").value
    def walk(table):
        gait = optimal_gaits(table, "rate").gaits[0]
        return list(gait.states) + ([] if gait.states[-1] == gait.states[0] else [gait.states[0]])

    mean_walk = walk(learned_robot.transitions)
    assert evaluate_sequence(eff, mean_walk).rate >= 0.95 * best
    # The variance-penalised gait trades mean speed for reliability: it is not held to the
    # mean's optimum, but its transitions are no less certain than the mean-optimal gait's.
    t = robot.transitions
    sigma = np.sqrt(est.dx.var)

    def mean_sigma(states):
        return float(np.mean([sigma[t.lookup(a, b)] for a, b in zip(states, states[1:])]))

    assert mean_sigma(walk(penalised_table(est, 1.0))) <= mean_sigma(mean_walk) + 1e-9


def test_an_interrupted_exploration_resumes_from_its_log_and_loses_nothing(tmp_path):
    from proleg.learn.runner import Explorer
    from proleg.learn.simulated import simulated_robot

    robot = load_robot(R1)
    log_path = tmp_path / "trials.jsonl"
    sim, client, pose = simulated_robot(robot, seed=5)
    with client, TrialLog(log_path) as log:
        client.connect()
        first = Explorer(client, robot, log, pose, repeats=2, seed=5).run(max_pieces=2)
    assert 0 < len(first) < 2 * robot.transitions.n_transitions
    before = log_path.read_text().splitlines()
    sim, client, pose = simulated_robot(robot, seed=6)  # a fresh session, as after a crash
    with client, TrialLog(log_path) as log:
        client.connect()
        Explorer(client, robot, log, pose, repeats=2, seed=6).run()
        assert counts(robot.transitions, log.trials).min() >= 2
    after = log_path.read_text().splitlines()
    assert after[: len(before)] == before


def test_manual_entry_asks_once_per_transition_with_the_robot_at_rest(tmp_path):
    from proleg.learn.runner import Explorer
    from proleg.learn.simulated import simulated_robot

    robot = load_robot(R1)
    sim, client, _pose = simulated_robot(robot, seed=7)
    prompts = []

    def ask(prompt):
        prompts.append((prompt, [sim.board.pwm(ch) for ch in (0, 1)]))
        return "" if len(prompts) == 1 else "2.5"  # the first trial is skipped

    with client, TrialLog(tmp_path / "manual.jsonl") as log:
        client.connect()
        added = Explorer(client, robot, log, None, repeats=1, seed=7, ask=ask).run(max_pieces=3)
    assert len(prompts) == 3 and len(added) == 2
    assert all(t.source == "manual" and t.dx == 2.5 for t in added)
    assert prompts[0][0].endswith("(empty = skip): ") and "→" in prompts[0][0]
    assert all(duties == [0.0, 0.0] for _p, duties in prompts)  # stopped: every coil off


def test_a_tracker_run_gets_its_motion_from_the_track_afterwards(tmp_path):
    """Record without a pose, write the plant's path as a camera would (other clock, 30 fps),
    then attach the track: the trials match the ground truth."""
    from proleg.learn.runner import Explorer
    from proleg.learn.simulated import simulated_robot
    from proleg.learn.tracker import Track, attach_track

    robot = load_robot(R1)
    sim, client, _pose = simulated_robot(robot, seed=8)
    path = []
    step = sim.step

    def stepping():
        step()
        path.append((sim.time_s, sim.plant.displacement_mm))

    sim.step = stepping
    with client, TrialLog(tmp_path / "t.jsonl") as log:
        client.connect()
        Explorer(client, robot, log, None, repeats=1, seed=8).run(max_pieces=2)
        trials = list(log.trials)
    # the telemetry saw each new state before the firmware confirmed it settled (STATE_REACHED)
    assert all(tr.t_seen is not None and tr.t_start < tr.t_seen <= tr.t_end for tr in trials)
    # a cooling limb settles late (a limb still unsettled after CTL_HOVER_MS = 300 ms settles on its band edges)
    assert max(tr.t_end - tr.t_seen for tr in trials) > 0.2
    t, x = np.array(path).T
    keep = np.arange(0, len(t), 17)  # ~30 fps
    track = Track(t[keep] + 42.0, x[keep])
    with_motion, offset, outside = attach_track(trials, track)
    assert outside == [] and len(with_motion) == len(trials)
    assert offset == pytest.approx(42.0, abs=0.06)
    for tr, seen in zip(with_motion, plant_changes(with_motion, sim.plant.transitions)):
        assert tr.dx == pytest.approx(sum(p.reward_mm for p in seen), abs=0.2)


def test_trials_the_track_does_not_cover_keep_no_motion_rather_than_zero(tmp_path, capsys):
    """np.interp clamps to a track's ends: a trial after the track's last row got that row's
    pose at both ends, a motion of 0 that was never measured, and a track from another run
    made a matrix of zeros (exit 0)."""
    from proleg.cli.main import main
    from proleg.learn.measure import Trial, TrialLog
    from proleg.learn.tracker import Track, attach_track

    track = Track(np.array([0.0, 1.0, 2.0, 3.0]), np.array([0.0, 1.0, 2.0, 3.0]))
    trials = [Trial("00", "10", 0.2, 1.2), Trial("10", "11", 1.2, 2.5), Trial("11", "01", 2.5, 3.5),
              Trial("01", "00", 3.5, 4.5)]
    got, offset, outside = attach_track(trials, track, 0.0, settle_s=0.0)
    assert offset == 0.0 and [t.dx for t in got] == [pytest.approx(1.0), pytest.approx(1.3)]
    assert [(t.src, t.dst, t.dx) for t in outside] == [("11", "01", None), ("01", "00", None)]

    log = tmp_path / "run.jsonl"
    with TrialLog(log) as tl:
        for tr in trials:
            tl.append(tr)
    csv = tmp_path / "track.csv"
    csv.write_text("time,x,y,theta\n0,0,,\n1,1,,\n2,2,,\n3,3,,\n")
    out = tmp_path / "learned.toml"
    code = main(["learn", str(R1), "--log", str(log), "--track", str(csv), "--tracker-offset", "100000",
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists() and "Traceback" not in err
    assert f"--track {csv}: covers none of the 4 trials without motion: its times 0..3 s" in err
    # the track of this run: two trials get their motion, two are left without (a warning says so)
    code = main(["learn", str(R1), "--log", str(log), "--track", str(csv), "--tracker-offset", "0", "--report"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "2 of 4 trials begin or end outside it and are left without motion" in captured.err


def test_trials_in_a_gap_of_the_track_keep_no_motion_rather_than_an_interpolated_one(tmp_path, capsys):
    """A camera that lost the robot for a while (no rows for 3 s of a 10 Hz track): a pose read
    in that gap was interpolated across it, so a transition whose motion fell there got a Δx
    that was never measured (2.4 mm read as 0.46), exit 0 and no word. It keeps none, as a trial
    outside the track does, and the warning names the gap."""
    from proleg.cli.main import main
    from proleg.learn.measure import Trial, TrialLog
    from proleg.learn.tracker import Track, attach_track

    t = np.round(np.arange(0.0, 10.0, 0.1), 3)
    x = np.where(t < 2.0, 0.0, np.where(t < 6.0, 1.0, 3.0))  # +1 mm at 2 s, +2 mm at 6 s
    gap = (t > 4.5) & (t < 7.5)  # no frame from 4.5 to 7.5 s
    track = Track(t[~gap], x[~gap])
    trials = [Trial("00", "10", 1.0, 3.0), Trial("10", "11", 5.0, 6.5), Trial("11", "01", 3.0, 8.0)]
    got, offset, outside = attach_track(trials, track, 0.0, settle_s=0.0)
    assert [(tr.src, tr.dst, tr.dx) for tr in got] == [("00", "10", pytest.approx(1.0)),
                                                       ("11", "01", pytest.approx(2.0))]
    assert [(tr.src, tr.dst) for tr in outside] == [("10", "11")]
    assert track.covers(4.5) and track.covers(7.5) and not track.covers(6.0)
    assert track.gap_around(6.0) == pytest.approx((4.5, 7.5)) and track.gap_around(3.0) is None

    log = tmp_path / "run.jsonl"
    with TrialLog(log) as tl:
        for tr in trials:
            tl.append(tr)
    csv = tmp_path / "track.csv"
    csv.write_text("time,x,y,theta\n" + "".join(f"{a:g},{b:g},,\n" for a, b in zip(t[~gap], x[~gap])))
    code = main(["learn", str(R1), "--log", str(log), "--track", str(csv), "--tracker-offset", "-0.05", "--report"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "1 of 3 trials fall in a gap of it and are left without motion" in captured.err, captured.err
    assert "no frame from 4.5 to 7.5 s" in captured.err, captured.err


def test_a_coil_that_dies_during_exploration_costs_the_transitions_it_makes_not_the_run(tmp_path, caplog):
    """The right coil dead: each transition that raises the right end faults (SMA_ON_LIMIT or
    STATE_TIMEOUT, named by transition); each is recorded as not made and not asked for again,
    the robot cooled and cleared, and the rest learned. It used to end the run at the first."""
    import logging

    from proleg.learn.runner import Explorer
    from proleg.learn.simulated import simulated_robot

    robot = load_robot(R1)
    t = robot.transitions
    sim, client, pose = simulated_robot(robot, seed=1)
    with client, TrialLog(tmp_path / "t.jsonl") as log, caplog.at_level(logging.WARNING, logger="proleg"):
        client.connect()
        sim.inject("dead-actuator:sma-right")
        Explorer(client, robot, log, pose, repeats=2, seed=1).run()
        failed = {(f.src, f.dst): f.fault for f in log.failures}
        made = counts(t, log.trials)
    raises_right = {("00", "01"), ("10", "01"), ("00", "11"), ("10", "11")}
    assert set(failed) == raises_right
    assert all(re.fullmatch(r"FAULT (SMA_ON_LIMIT on sma-right|STATE_TIMEOUT on right)", f) for f in failed.values())
    assert made[t.lookup(t.index("00"), t.index("10"))] >= 2 and made[t.lookup(t.index("10"), t.index("00"))] >= 2
    said = [r.getMessage() for r in caplog.records]
    assert any(re.search(r"the robot could not make 00->01: FAULT (SMA_ON_LIMIT on sma-right|STATE_TIMEOUT on "
                         r"right); recorded as not made", m) for m in said), said


def test_learning_planar_4_on_the_table_plant_measures_dy_and_dtheta(tmp_path):
    """learn --sim built the table plant without the robot file's planar statistics and its
    pose gave Δx only: on planar-4 every trial had dy and dθ null, and the learned file kept the
    prior's. Now each trial carries all three, and where the file's dy or dθ is clearly nonzero
    the mean learned value has its sign (a trial or two each, with the plant's variance noise;
    a trial that passed through other states is left out: its motion is theirs too)."""
    robot = load_robot(ROOT / "robots" / "planar-4.toml")
    with TrialLog(tmp_path / "p4.jsonl") as log:
        explore_simulated(robot, None, log, repeats=1, seed=2)
        trials = list(log.trials)
    assert trials and all(tr.dy is not None and tr.dtheta_deg is not None for tr in trials)
    t = robot.transitions
    agree = total = 0
    for field in ("dy", "dtheta_deg"):
        want = getattr(t.planar, field)
        for k, (a, b) in enumerate(zip(t.src, t.dst)):
            got = [getattr(tr, field) for tr in trials if not tr.passed
                   and (t.index(tr.src), t.index(tr.dst)) == (int(a), int(b))]
            if got and abs(want[k]) >= 0.5:
                total += 1
                agree += bool(np.sign(np.mean(got)) == np.sign(want[k]))
    assert total >= 20 and agree >= 0.9 * total, (agree, total)
