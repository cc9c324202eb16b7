"""Estimates, confidence intervals, extra trials, the learned robot file, penalised gaits."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.gait import optimal_gaits
from proleg.learn.estimate import estimate, extra_trials, penalised_table
from proleg.learn.measure import Trial
from proleg.learn.robotfile import read_learned, write_learned_robot
from proleg.learn.stats import t_quantile
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parent.parent
R1 = ROOT / "robots" / "paper-r1.toml"
TABLE = load_robot(R1).transitions

# Student t 97.5 % points from printed tables (e.g. NIST/SEMATECH e-Handbook, table 1.4.2.3)
T975 = {1: 12.706, 2: 4.303, 4: 2.776, 9: 2.262, 29: 2.045, 100: 1.984}


@pytest.mark.parametrize("df,q", sorted(T975.items()))
def test_t_quantiles_match_the_printed_table(df, q):
    assert t_quantile(0.975, df) == pytest.approx(q, abs=6e-4)


def _trials(rng, table, truth, sigma, n):
    out = []
    for e, (a, b) in enumerate(zip(table.src.tolist(), table.dst.tolist())):
        for _ in range(n):
            out.append(Trial(table.label(a), table.label(b), 0, 1, float(truth[e] + rng.normal(0, sigma)),
                             float(rng.normal(0, 1)), None, "test"))
    return out


def test_means_variances_and_intervals_are_the_textbook_ones():
    table = load_robot(R1).transitions
    trials = [Trial("00", "10", 0, 1, v) for v in (1.0, 2.0, 4.0)] + [Trial("10", "11", 0, 1, 3.0)]
    est = estimate(table, trials)
    e = table.lookup(table.index("00"), table.index("10"))
    assert est.dx.mean[e] == pytest.approx(7 / 3)
    assert est.dx.var[e] == pytest.approx(np.var([1, 2, 4], ddof=1))
    assert est.dx.half_width[e] == pytest.approx(4.303 * math.sqrt(est.dx.var[e] / 3), rel=1e-3)
    f = table.lookup(table.index("10"), table.index("11"))
    assert est.dx.n[f] == 1 and math.isnan(est.dx.var[f])
    assert "10->11" in est.flagged() and "00->10" not in est.flagged()


def test_the_95_percent_intervals_cover_the_truth_about_95_percent_of_the_time():
    rng = np.random.default_rng(1)
    table = load_robot(R1).transitions
    truth = rng.normal(0, 5, table.n_transitions)
    hits = total = 0
    for _ in range(200):
        est = estimate(table, _trials(rng, table, truth, 2.0, 5))
        hits += int(np.sum(np.abs(est.dx.mean - truth) <= est.dx.half_width))
        total += table.n_transitions
    assert 0.93 <= hits / total <= 0.97


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 30), st.floats(0.1, 10), st.floats(0.05, 5))
def test_extra_trials_are_the_fewest_that_reach_the_half_width(n, s, h):
    table = TABLE
    e = table.lookup(table.index("00"), table.index("10"))
    est = estimate(table, [Trial("00", "10", 0, 1, v) for v in np.linspace(-1, 1, n) * s])
    comp = est.dx
    m = int(extra_trials(comp, h)[e])
    var = comp.var[e]

    def width(k):
        return t_quantile(0.975, n + k - 1) * math.sqrt(var / (n + k))

    assert width(m) <= h or m == 100_000  # the documented cap for hopeless requests
    assert m == 0 or width(m - 1) > h
    assert all(x == 2 for k, x in enumerate(extra_trials(comp, h)) if k != e)  # never measured: two to start with


def test_the_learned_file_loads_with_its_statistics_and_keeps_the_old_matrix(tmp_path):
    robot = load_robot(R1)
    rng = np.random.default_rng(3)
    truth = robot.transitions.reward * 4.0
    est = estimate(robot.transitions, _trials(rng, robot.transitions, truth, 0.5, 4))
    out = write_learned_robot(robot, est, tmp_path / "learned.toml", units="mm")
    learned = load_robot(out)
    assert learned.units == "mm"
    assert np.allclose(learned.transitions.reward, est.dx.mean)
    text = out.read_text()
    assert "# previous [transitions]" in text and "#   [ 0, -1,  1,  0]," in text
    assert "[control]" in text and "hold_duty = 0.25" in text  # the rest is copied
    stats = read_learned(out)
    n = robot.n_states
    assert stats["n_trials"].shape == (n, n)
    a, b = robot.transitions.index("00"), robot.transitions.index("10")
    e = robot.transitions.lookup(a, b)
    assert stats["n_trials"][a, b] == 4
    assert stats["var_dx"][a, b] == pytest.approx(est.dx.var[e], rel=1e-5)
    assert stats["dy"][a, b] == pytest.approx(est.components["dy"].mean[e], rel=1e-5, abs=1e-6)
    # the loader takes them as keys: n_trials, and the planar statistics gait selection weighs
    assert "\nn_trials = [" in text and "#learned:" not in text
    assert np.array_equal(learned.n_trials, est.dx.n)
    assert np.allclose(learned.transitions.planar.var_dx, est.dx.var, rtol=1e-5)


def test_a_transition_not_measured_is_nan_and_loads_as_unknown(tmp_path):
    robot = load_robot(R1)
    t = robot.transitions
    skip = t.lookup(t.index("11"), t.index("00"))
    trials = [Trial(t.label(a), t.label(b), 0, 1, float(k) + e, 0.1 * k, None, "sim")
              for e, (a, b) in enumerate(zip(t.src, t.dst)) if e != skip for k in range(3)]
    out = write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml", units="mm")
    text = out.read_text()
    assert "not measured (previous value kept): 11->00" in text and "nan" in text
    learned = load_robot(out)
    assert learned.n_trials[skip] == 0 and learned.transitions.reward[skip] == t.reward[skip]
    var = learned.transitions.planar.var_dx
    assert var[skip] == pytest.approx(var.max())  # unknown spread: not taken for a sure transition
    assert learned.transitions.planar.dy[skip] == 0.0
    commented = write_learned_robot(robot, estimate(t, trials), tmp_path / "c.toml", units="mm", stats_as_keys=False)
    assert load_robot(commented).n_trials is None and read_learned(commented)["n_trials"][3, 0] == 0


def test_learned_keys_that_are_wrong_are_one_clear_line(tmp_path):
    from proleg.errors import RobotFileError

    text = R1.read_text().replace("[transitions]", "[transitions]\nn_trials = [[0, 1, 2, 3], [1, 0, 1, 1], [1, 1, 0, 1.5], [1, 1, 1, 0]]")
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(RobotFileError, match=r"n_trials\[3\]\[4\]: expected a whole number"):
        load_robot(p)
    p.write_text(R1.read_text().replace("[transitions]", "[transitions]\nvar_dx = [[0, nan, 1, 1], [1, 0, 1, 1], [1, 1, 0, -1], [1, 1, 1, 0]]"))
    with pytest.raises(RobotFileError, match=r"var_dx\[3\]\[4\]: expected a variance in \[0, 1e\+18\] or 'x', got -1"):
        load_robot(p)


def test_forbidden_entries_stay_forbidden_in_the_learned_file(tmp_path):
    robot = load_robot(ROOT / "robots" / "paper-r1-one-actuator.toml")
    t = robot.transitions
    trials = [Trial(t.label(a), t.label(b), 0, 1, 1.0 + k) for a, b in zip(t.src, t.dst) for k in range(2)]
    out = write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml")
    again = load_robot(out).transitions
    assert np.array_equal(again.src, t.src) and np.array_equal(again.dst, t.dst)
    assert np.allclose(again.reward, 1.5)


def test_a_variance_penalty_moves_the_gait_to_the_reliable_transitions():
    robot = load_robot(R1)
    t = robot.transitions
    trials = []
    rng = np.random.default_rng(0)
    # 00->10->11->01->00 is fast but noisy on 10->11; 00->10->00 ... is steady
    for a, b, mu, sd in [("00", "10", 4, 0.1), ("10", "11", 8, 6.0), ("11", "01", 0, 0.1), ("01", "00", 4, 0.1),
                         ("10", "00", -1, 0.1), ("00", "01", -1, 0.1), ("01", "11", -1, 0.1), ("11", "10", -1, 0.1),
                         ("00", "11", 0, 0.1), ("11", "00", 0, 0.1), ("01", "10", 0, 0.1), ("10", "01", 3.9, 0.1)]:
        trials += [Trial(a, b, 0, 1, float(mu + d)) for d in rng.normal(0, sd, 20) / max(1e-9, 1) * 1]
    est = estimate(t, trials)
    plain = optimal_gaits(penalised_table(est, 0.0), "rate").gaits[0].states
    careful = optimal_gaits(penalised_table(est, 1.0), "rate").gaits[0].states
    label = [t.label(s) for s in plain]
    assert "11" in label  # through the noisy, big 10->11
    assert "11" not in [t.label(s) for s in careful]


def test_the_extra_trial_plan_makes_every_suggested_trial_in_closed_tours():
    from collections import Counter

    from proleg.learn.plan import adaptive_demand, extra_plan

    rng = np.random.default_rng(4)
    sig = rng.uniform(0.2, 3.0, TABLE.n_transitions)
    trials = []
    for e, (a, b) in enumerate(zip(TABLE.src.tolist(), TABLE.dst.tolist())):
        trials += [Trial(TABLE.label(a), TABLE.label(b), 0, 1, float(v)) for v in rng.normal(0, sig[e], 3)]
    est = estimate(TABLE, trials)
    need, plan = extra_plan(est, 1.0, seed=1)
    assert np.array_equal(need, est.extra_trials(1.0))
    made = Counter(tr for tour in plan.tours for tr in tour.transitions)
    for e, (a, b) in enumerate(zip(TABLE.src.tolist(), TABLE.dst.tolist())):
        assert made[(a, b)] >= need[e]
    pick = adaptive_demand(est, 0.25)
    assert pick.sum() == 3
    assert set(np.nonzero(pick)[0]) == set(np.argsort(-est.dx.half_width)[:3])
