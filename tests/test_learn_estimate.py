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
    assert "not measured (previous value kept, × 4 from steps to mm): 11->00" in text and "nan" in text
    learned = load_robot(out)
    # kept, in the new unit: R1's matrix is in steps of [plant] step_mm (4 mm by default)
    assert learned.n_trials[skip] == 0 and learned.transitions.reward[skip] == 4.0 * t.reward[skip]
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


def _r1_trials(dx: float = 4.0) -> list[Trial]:
    t = load_robot(R1).transitions
    return [Trial(t.label(a), t.label(b), 0, 1, dx + k, None, None, "sim") for a, b in zip(t.src, t.dst)
            for k in range(2)]


@pytest.mark.parametrize("header", ["[ transitions ]  # the table", '["transitions"]', "['transitions']"])
def test_a_transitions_header_spelled_any_valid_way_is_replaced(tmp_path, header):
    """A spaced or quoted header was not recognised: a second [transitions] was appended and
    the learned file was not valid TOML (exit 0)."""
    robot_file = tmp_path / "r.toml"
    robot_file.write_text(R1.read_text().replace("[transitions]", header))
    robot = load_robot(robot_file)
    out = write_learned_robot(robot, estimate(robot.transitions, _r1_trials()), tmp_path / "l.toml")
    learned = load_robot(out)
    assert np.allclose(learned.transitions.reward, [4.5] * robot.transitions.n_transitions)
    assert f"# {header}" in out.read_text()  # the old table, commented out


def test_a_learned_file_that_would_not_read_back_is_never_written(tmp_path):
    """A [transitions] table the writer cannot replace as text (here an inline table) is
    refused in one line, before anything is written."""
    import tomllib

    from proleg.learn.robotfile import LearnedFileError

    doc = tomllib.loads(R1.read_text())
    t = doc["transitions"]
    inline = "transitions = { " + ", ".join(f"{k} = {_toml(v)}" for k, v in t.items()) + " }"
    text = R1.read_text()
    a = text.index("[transitions]")
    b = text.index("\n[", a + 1)
    robot_file = tmp_path / "r.toml"
    robot_file.write_text(inline + "\n" + text[:a] + text[b:])
    robot = load_robot(robot_file)
    out = tmp_path / "l.toml"
    with pytest.raises(LearnedFileError, match=r"^learn: the learned file from .*r\.toml would not be valid TOML"):
        write_learned_robot(robot, estimate(robot.transitions, _r1_trials()), out)
    assert not out.exists()


def _toml(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return f'"{v}"' if isinstance(v, str) else repr(v)


def test_learned_means_read_back_exactly(tmp_path):
    """Written with .6g, 4000.123456789 came back as 4000.12."""
    robot = load_robot(R1)
    est = estimate(robot.transitions, _r1_trials(4000.123456789))
    learned = load_robot(write_learned_robot(robot, est, tmp_path / "l.toml"))
    assert np.array_equal(learned.transitions.reward, est.dx.mean)
    assert np.array_equal(learned.transitions.planar.var_dx, est.dx.var)


def test_a_learned_file_that_cannot_be_written_leaves_the_old_one_and_names_the_file(tmp_path, monkeypatch):
    """It was written in place: a full disk left a 0-byte file, and the error named none."""
    import errno
    import os

    from proleg.errors import LinkError

    robot = load_robot(R1)
    out = tmp_path / "l.toml"
    out.write_text("old\n")

    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(LinkError, match=rf"^learn: cannot write {out}: No space left on device$"):
        write_learned_robot(robot, estimate(robot.transitions, _r1_trials()), out)
    assert out.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["l.toml"]


def _sim_trials(t, skip=(), dy=True):
    return [Trial(t.label(a), t.label(b), 0, 1, 4.0 * float(r) + 0.1 * k, 0.1 * k if dy else None, None, "sim")
            for e, (a, b, r) in enumerate(zip(t.src, t.dst, t.reward)) if e not in skip for k in range(3)]


def test_a_learned_file_in_mm_drops_the_step_size_and_loads(tmp_path):
    """A robot file in steps with its own [plant] step_mm: learning in mm kept step_mm = 2.5,
    and the learned file did not load ("plant.step_mm: expected 1 ... units mm")."""
    text = R1.read_text(encoding="utf-8")
    assert "[plant]" not in text
    src = tmp_path / "r1-step.toml"
    src.write_text(text + "\n[plant]\nstep_mm = 2.5\n", encoding="utf-8")
    robot = load_robot(src)
    t = robot.transitions
    skip = t.lookup(t.index("11"), t.index("00"))
    out = write_learned_robot(robot, estimate(t, _sim_trials(t, {skip})), tmp_path / "l.toml", units="mm")
    learned = load_robot(out)
    assert learned.units == "mm" and learned.plant.step_mm == 1.0
    assert learned.transitions.reward[skip] == 2.5 * t.reward[skip]  # kept, in mm at 2.5 mm a step
    assert "# step_mm = 2.5   # the matrix is in mm now (learned)" in out.read_text()


def test_planar_statistics_not_learned_are_kept_so_a_library_robot_still_loads(tmp_path):
    """planar-4's [gaits] library weighs dy and dθ: a plant that gives only Δx dropped them
    and the learned file did not load ("gaits.library: ... needs [transitions].var_dy")."""
    robot = load_robot(ROOT / "robots" / "planar-4.toml")
    t = robot.transitions
    assert t.planar is not None and t.planar.dy is not None
    out = write_learned_robot(robot, estimate(t, _sim_trials(t, dy=False)), tmp_path / "l.toml",
                              units=robot.units)
    learned = load_robot(out)
    assert np.allclose(learned.transitions.planar.dtheta_deg, t.planar.dtheta_deg)
    assert np.allclose(learned.transitions.planar.dy, t.planar.dy)
    assert "# dy: not learned here, the previous values kept" in out.read_text()


def test_a_learned_file_that_would_not_load_is_not_written(tmp_path, monkeypatch):
    from proleg.learn import robotfile

    robot = load_robot(R1)
    t = robot.transitions
    monkeypatch.setattr(robotfile, "_matrix", lambda name, values, allowed, prefix="": [f"{prefix}{name} = 5"])
    with pytest.raises(robotfile.LearnedFileError, match="would not load"):
        write_learned_robot(robot, estimate(t, _sim_trials(t)), tmp_path / "l.toml", units="mm")
    assert not (tmp_path / "l.toml").exists()


def test_a_transition_not_measured_keeps_its_planar_statistics_too(tmp_path):
    """planar-4 with one transition not tried: its dy and var_dx became NaN (read as 0 and
    'unknown') while its matrix entry kept the file's value."""
    robot = load_robot(ROOT / "robots" / "planar-4.toml")
    t = robot.transitions
    skip = next(e for e in range(t.n_transitions) if t.planar.dy[e] != 0)
    out = write_learned_robot(robot, estimate(t, _sim_trials(t, {skip})), tmp_path / "l.toml", units=robot.units)
    learned = load_robot(out).transitions
    assert learned.planar.dy[skip] == t.planar.dy[skip]
    assert learned.reward[skip] == t.reward[skip]


def test_the_documented_next_step_gait_with_a_variance_weight_runs_on_a_one_dimensional_learned_file(
        tmp_path, capsys):
    """docs/learning.md step 4: `proleg gait LEARNED --objective rate --variance-weight 1`. One
    λ meant λ on var_dx, var_dy and var_dtheta_deg: a file learned with Δx only failed with
    "planar objective needs [transitions].var_dy". One λ now weighs the variances the file gives."""
    import json

    from proleg.cli import main

    robot = load_robot(R1)
    t = robot.transitions
    trials = [Trial(t.label(a), t.label(b), 0, 1, 2.0 + 0.5 * k * (e % 3), None, None, "sim")
              for e, (a, b) in enumerate(zip(t.src, t.dst)) for k in range(3)]
    out = write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml", units="mm")
    value = {}
    for weight in ("0", "1"):
        assert main(["gait", str(out), "--objective", "rate", "--variance-weight", weight, "--json"]) == 0
        value[weight] = json.loads(capsys.readouterr().out)["results"][0]["value"]
    assert value["1"] < value["0"]  # the variances weigh on it
    assert main(["gait", str(out), "--variance-weight", "1,1,0"]) == 2  # a weight for var_dy, which it lacks
    assert "needs [transitions].var_dy" in capsys.readouterr().err


def test_a_gaits_library_weighs_the_variances_a_one_dimensional_file_gives_as_gait_does(tmp_path):
    """[gaits] variance_weight = 1 in a file measured or learned along x (var_dx only) was refused
    ("variance weight on dy needs [transitions].var_dy") where `proleg gait --variance-weight 1`
    weighed var_dx: one number now weighs what the file gives, in the file as on the command
    line, and the firmware carries the gait the command computes; a list still names each."""
    from proleg.cli.gait import _variance_weights
    from proleg.errors import RobotFileError
    from proleg.gait.library import gait_library

    robot = load_robot(R1)
    t = robot.transitions
    trials = [Trial(t.label(a), t.label(b), 0, 1, 2.0 + 0.5 * k * (e % 3), None, None, "sim")
              for e, (a, b) in enumerate(zip(t.src, t.dst)) for k in range(3)]
    out = write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml", units="mm")
    text = out.read_text().replace("max_climb_deg", "# max_climb_deg")  # the climb guard is not for a library
    for weight, loads in (("1", True), ("[1, 1, 0]", False)):
        path = tmp_path / f"g{loads}.toml"
        path.write_text(text + f"\n[gaits]\nlibrary = [0, 180]\nvariance_weight = {weight}\n")
        if not loads:
            with pytest.raises(RobotFileError, match=r"gaits\.library: .*needs \[transitions\]\.var_dy"):
                load_robot(path)
            continue
        lib = load_robot(path)
        assert lib.library.variance_weight == (1.0, 0.0, 0.0) == _variance_weights(lib, 1.0)
        by_hand = gait_library(lib.transitions, "0,180", variance_weight=_variance_weights(lib, 1.0))
        carried = [e.gait.states for e in lib.library.entries(lib.transitions)]
        assert carried == [e.gait.states for e in by_hand] and all(carried)


def test_per_gait_climb_limits_become_their_smallest_so_the_learned_file_builds(tmp_path):
    """caterpillar-4 with each of its first two gaits of a way given its own climb limit. Learned
    on the physical plant, its matrix ranked one +x gait first and `proleg build`/`sim` of the
    learned file stopped: "control.max_climb_deg.+x: 2 limits, but the firmware carries 1 gait"."""
    from proleg.firmware.gaits import firmware_gaits
    from proleg.robot_climb import check_climb_limit

    text = (ROOT / "robots" / "caterpillar-4.toml").read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("max_climb_deg"))
    src = tmp_path / "c4.toml"
    src.write_text(text.replace(line, 'max_climb_deg = { "+x" = [1.5, 1], "-x" = [3, 3.5] }'), encoding="utf-8")
    robot = load_robot(src)
    t = robot.transitions
    given_limit = robot.control.max_climb_deg
    assert given_limit.plus_x_gaits and given_limit.minus_x_gaits  # the file's lists, per gait
    # one 2-cycle moves the robot each way, nothing else: one gait per way
    moves = {(t.label(a), t.label(b)): 0.0 for a, b in zip(t.src, t.dst)}
    moves[("0121", "0221")] = moves[("0221", "0121")] = 1.0
    moves[("1210", "1220")] = moves[("1220", "1210")] = -1.0
    trials = [Trial(s, d, 0, 1, v, None, None, "sim") for (s, d), v in moves.items() for _k in range(3)]
    out = write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml", units=robot.units)
    learned = load_robot(out)
    gaits = firmware_gaits(learned)
    assert len(gaits["+x"]) < len(given_limit.plus_x_gaits)
    assert check_climb_limit(learned.control.max_climb_deg, gaits) is None
    limit = learned.control.max_climb_deg
    assert (limit.plus_x, limit.minus_x) == (min(given_limit.plus_x_gaits), min(given_limit.minus_x_gaits))
    assert not limit.plus_x_gaits and not limit.minus_x_gaits  # every gait: the smallest
    text = out.read_text()
    assert '# max_climb_deg = { "+x" = [1.5, 1], "-x" = [3, 3.5] }' in text


def test_a_climb_limit_list_learn_cannot_replace_as_text_is_refused_and_nothing_written(tmp_path):
    from proleg.learn.robotfile import LearnedFileError

    text = (ROOT / "robots" / "caterpillar-4.toml").read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("max_climb_deg"))
    src = tmp_path / "c4.toml"  # the same limits as a table of their own
    src.write_text(text.replace(line, "") + '\n[control.max_climb_deg]\n"+x" = [1.5, 1]\n"-x" = [3, 3.5]\n',
                   encoding="utf-8")
    robot = load_robot(src)
    assert robot.control.max_climb_deg.plus_x_gaits == (1.5, 1.0)
    t = robot.transitions
    with pytest.raises(LearnedFileError, match=r"\[control\] max_climb_deg .* one line"):
        write_learned_robot(robot, estimate(t, _sim_trials(t)), tmp_path / "l.toml", units=robot.units)
    assert not (tmp_path / "l.toml").exists()


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 7), st.floats(0.0, 3.0)), min_size=1, max_size=24), st.booleans())
def test_the_learned_file_carries_the_mean_time_each_transition_took(tmp_path_factory, timed, old_durations):
    """durations_s: per transition the mean of its trials' t_end − t_start (a brute-force
    recount), a trial with no time (t_end = t_start, or under the 1 µs a robot file takes) not counted; a transition never timed keeps
    the old table's duration, or gets the longest timed one when the old table had none, and a
    comment names it. Without any timed trial the old durations stay as they were."""
    path = tmp_path_factory.mktemp("dur") / "r.toml"
    text = R1.read_text()  # R1's file gives no durations
    path.write_text(text.replace("[transitions]", "[transitions]\ndefault_duration_s = 0.9") if old_durations else text)
    robot = load_robot(path)
    t = robot.transitions
    assert (t.duration is not None) == old_durations
    edges = list(zip(t.src.tolist(), t.dst.tolist()))
    trials = [Trial(t.label(edges[e % len(edges)][0]), t.label(edges[e % len(edges)][1]), 10.0, 10.0 + d, 1.0)
              for e, d in timed]
    learned = load_robot(write_learned_robot(robot, estimate(t, trials), path.with_name("l.toml"), units="mm"))
    # a duration the robot file takes: 1 µs to an hour (robot_entries), as the clock computes it
    took = {k: [(10.0 + d) - 10.0 for e, d in timed if edges[e % len(edges)] == k and 1e-6 <= (10.0 + d) - 10.0]
            for k in edges}
    longest = max((float(np.mean(v)) for v in took.values() if v), default=None)  # a transition's mean
    text = path.with_name("l.toml").read_text()
    if longest is None:
        assert (learned.transitions.duration is None) == (not old_durations)
        if old_durations:
            assert np.allclose(learned.transitions.duration, t.duration)
        return
    got = dict(zip(edges, learned.transitions.duration.tolist()))
    for e, (k, v) in enumerate(took.items()):
        want = float(np.mean(v)) if v else (t.duration[e] if old_durations else longest)
        assert got[k] == pytest.approx(want, rel=1e-9), k
    untimed = [f"{t.label(a)}->{t.label(b)}" for (a, b), v in took.items() if not v]
    assert ("# durations_s not timed" in text) == bool(untimed)
    assert all(label in text for label in untimed)
