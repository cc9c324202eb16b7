"""``[transitions] matrix = "unmeasured"``: a robot whose rewards are not known yet, its
allowed transitions given by a rule (``allow``) instead of written out, learned from there.

The rule is checked against a brute-force oracle (every pair of states, their limb levels
compared); the rest follows a lab's first day: load, build (no gaits, and why), learn on the
simulated body, walk the learned file."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from build_checks import cli
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg import states
from proleg.errors import RobotFileError
from proleg.robot import load_robot
from proleg.robot_transitions import MAX_UNMEASURED_EDGES, _allowed_by_rule


def _robot_text(levels: list[int], transitions: str, *, friction: bool = True, extra: str = "") -> str:
    parts = ['[robot]\nname = "fresh"\n']
    for i, k in enumerate(levels):
        psi = [12.0 * (j + 1) for j in range(k - 1)]
        pad = ('friction = "D1"\n' if k == 2 else
               f"friction = {json.dumps(['soft' if j % 2 == 0 else 'hard' for j in range(k)])}\n") if friction else ""
        parts.append(f'[[limb]]\nname = "l{i}"\n{"levels = " + str(k) + chr(10) if k != 2 else ""}'
                     f"psi_star_deg = {psi}\n{pad}actuator = \"a{i}\"\n")
    parts += [f'[[actuator]]\nname = "a{i}"\nchannel = {i}\n' for i in range(len(levels))]
    parts.append(extra)
    parts.append(f"[transitions]\n{transitions}\n")
    return "\n".join(parts)


def _write(tmp_path: Path, levels: list[int], transitions: str, **kw) -> Path:
    path = tmp_path / "fresh.toml"
    path.write_text(_robot_text(levels, transitions, **kw), encoding="utf-8")
    return path


def _oracle(rule: str, levels: tuple[int, ...]) -> set[tuple[int, int]]:
    n = states.state_count(levels)
    out = set()
    for a, b in itertools.permutations(range(n), 2):
        la, lb = states.limb_levels(a, levels), states.limb_levels(b, levels)
        moved = [abs(x - y) for x, y in zip(la, lb) if x != y]
        if rule == "any" or (len(moved) == 1 and (rule == "one-limb" or moved[0] == 1)):
            out.add((a, b))
    return out


@settings(max_examples=60, deadline=None)
@given(levels=st.lists(st.integers(2, 4), min_size=1, max_size=4), rule=st.sampled_from(["one-level", "one-limb", "any"]))
def test_the_allow_rules_are_the_brute_force_sets_in_table_order(levels, rule):
    src, dst = _allowed_by_rule(Path("r.toml"), rule, tuple(levels))
    got = list(zip(src.tolist(), dst.tolist()))
    assert set(got) == _oracle(rule, tuple(levels))
    assert len(got) == len(set(got)) and got == sorted(got)  # by from, then to, as a table's edges


def test_an_unmeasured_robot_loads_with_zero_rewards_and_forbidden_marks_taken_out(tmp_path):
    path = _write(tmp_path, [2, 3, 2], 'matrix = "unmeasured"\nallow = "one-level"\nforbidden = ["000->100", "@1->@0"]')
    robot = load_robot(path)
    t = robot.transitions
    edges = {(t.label(a), t.label(b)) for a, b in zip(t.src.tolist(), t.dst.tolist())}
    assert robot.unmeasured and not t.reward.any()
    assert ("000", "100") not in edges and ("001", "000") not in edges and ("100", "000") in edges
    assert ("000", "020") not in edges and ("010", "020") in edges  # one level at a time
    assert len(edges) == len(_oracle("one-level", (2, 3, 2))) - 2
    assert not load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").unmeasured


@pytest.mark.parametrize("transitions, says", [
    ('matrix = "unknown"', 'expected 4 rows of 4 entries, or "unmeasured"'),
    ('matrix = "unmeasured"\nallow = "two"', "transitions.allow: expected one of 'one-level', 'one-limb', 'any'"),
    ('matrix = "unmeasured"\ndurations_s = 1', 'transitions.durations_s: expected no durations_s beside matrix = "unmeasured"'),
    ('matrix = "unmeasured"\nn_trials = 1', "transitions.n_trials: expected no n_trials beside"),
    ('matrix = [[0, 1, 1, "x"], [1, 0, "x", 1], [1, "x", 0, 1], ["x", 1, 1, 0]]\nallow = "any"',
     'transitions.allow: expected matrix = "unmeasured" beside it'),
    ('matrix = "unmeasured"\nforbidden = ["00->00"]', "transitions.forbidden[1]: 00->00 is a state to itself"),
    ('matrix = "unmeasured"\nforbidden = ["00->21"]', "transitions.forbidden[1]"),
])
def test_what_an_unmeasured_table_refuses_names_the_key(tmp_path, transitions, says):
    with pytest.raises(RobotFileError, match="fresh.toml: ") as e:
        load_robot(_write(tmp_path, [2, 2], transitions))
    assert says in str(e.value)


def test_a_rule_too_large_for_a_table_says_what_to_allow(tmp_path):
    """Eight three-level limbs, any pair: 43 million transitions, refused before any is made."""
    with pytest.raises(RobotFileError, match=r"transitions.allow: 'any' lets the robot's 6,561 states make "
                                             r"43,040,160 transitions, more than the 4,194,304") as e:
        load_robot(_write(tmp_path, [3] * 8, 'matrix = "unmeasured"'))
    assert 'allow "one-level"' in str(e.value)
    assert MAX_UNMEASURED_EDGES == 4_194_304


def test_without_friction_the_plant_says_it_cannot_infer_it_from_an_unmeasured_matrix(tmp_path, caplog):
    from proleg.sim.physical.mechanism import limb_mechanisms

    with caplog.at_level("WARNING"):
        robot = load_robot(_write(tmp_path, [2, 2], 'matrix = "unmeasured"', friction=False))
    assert any("the matrix is unmeasured and not every [[limb]] says its friction" in r.getMessage()
               for r in caplog.records)
    mech = limb_mechanisms(robot)
    assert mech.names == ("D1", "D1") and mech.source == "default (not inferred: the matrix is unmeasured)"


def test_the_build_carries_no_gait_and_says_to_learn(tmp_path, capsys):
    path = _write(tmp_path, [2, 2, 2], 'matrix = "unmeasured"\nallow = "one-level"', extra="[control]\ntick_hz = 500\n")
    code, out, err = cli(capsys, "build", path, "--board", "host-sim", "-o", tmp_path / "fw")
    assert code == 0, err
    assert "+x gaits: none (the matrix is unmeasured: learn or measure it, warned above)" in out
    assert "the robot's matrix is unmeasured" in err and "proleg learn ROBOT --sim --log TRIALS.jsonl --out LEARNED.toml" in err
    manifest = json.loads((tmp_path / "fw" / "proleg-build.json").read_text())
    assert manifest["gaits"] == {"+x": [], "-x": []}
    code, _, err = cli(capsys, "sim", path, "--duration", "1")
    assert code == 2 and "--gait 0 of +x" in err and "matrix is unmeasured" in err


def test_learning_an_unmeasured_robot_on_the_simulated_body_gives_a_file_that_walks(tmp_path, capsys):
    """learn --sim takes the physical plant for it (the table plant would move by zeros), and
    the learned file's gait 0 walks the way it promises."""
    path = _write(tmp_path, [2, 2, 2], 'matrix = "unmeasured"\nallow = "one-level"\ndefault_duration_s = 1',
                  extra="[control]\ntick_hz = 500\n")
    code, _, err = cli(capsys, "learn", path, "--sim", "--plant", "table", "--repeats", "1",
                       "--log", tmp_path / "t.jsonl")
    assert code == 2 and "the matrix is unmeasured, and the table plant moves by it" in err
    out_file = tmp_path / "learned.toml"
    code, _, err = cli(capsys, "learn", path, "--sim", "--repeats", "2", "--log", tmp_path / "trials.jsonl",
                       "--out", out_file)
    assert code == 0, err
    learned = load_robot(out_file)
    assert not learned.unmeasured and learned.transitions.reward.any()
    assert learned.transitions.n_transitions == load_robot(path).transitions.n_transitions
    for direction, sign in (("+x", 1), ("-x", -1)):
        code, out, err = cli(capsys, "sim", out_file, "--direction", direction, "--duration", "40", "--json")
        result = json.loads(out)
        assert code == 0 and result["faults"] == [], err
        assert result["cycles"] >= 1 and sign * result["displacement_mm"] > 0


def test_gait_says_why_no_gait_moves_an_unmeasured_robot(tmp_path, capsys):
    code, out, _ = cli(capsys, "gait", _write(tmp_path, [2, 2], 'matrix = "unmeasured"'))
    assert code == 0
    assert out.count("no gait moves the robot in") == 2 and out.count("its matrix is unmeasured: learn it") == 2


def test_measure_matrix_out_writes_the_robot_file_with_the_measured_matrix(tmp_path, capsys):
    """--measure-matrix --out: the file holds what --json measured (mm, samples as n_trials),
    the rest of the robot file as it was, and it walks; --out over ROBOT, into a missing folder
    or without --measure-matrix is refused before anything is measured or written."""
    path = _write(tmp_path, [2, 2], 'matrix = "unmeasured"\nallow = "one-level"', extra="[control]\ntick_hz = 500\n")
    out_file = tmp_path / "measured.toml"
    code, out, err = cli(capsys, "sim", path, "--measure-matrix", "--json", "--out", out_file)
    assert code == 0, err
    measured = json.loads(out)
    robot = load_robot(out_file)
    assert not robot.unmeasured and robot.units == "mm"
    dense, allowed = robot.transitions.dense()
    for a, row in enumerate(measured["matrix"]):
        for b, mm in enumerate(row):
            if a != b and mm is not None:
                assert allowed[a][b] and abs(dense[a][b] - mm) < 1e-4  # --json rounds to 0.1 µm
    assert [lb.friction for lb in robot.limbs] == [lb.friction for lb in load_robot(path).limbs]
    assert 'matrix = "unmeasured"' in out_file.read_text()  # the old table, commented out below
    # the time each transition took is written too: the speed objective and the state-timeout
    # checks need it, and an unmeasured file had none to keep
    table = robot.transitions
    took = {(a, b): d for a, b, d in zip(table.src.tolist(), table.dst.tolist(), table.duration.tolist())}
    for a, row in enumerate(measured["duration_s"]):
        for b, s in enumerate(row):
            if a != b and s is not None:
                assert abs(took[(a, b)] - s) < 1e-3  # --json rounds to 1 ms
    code, out, err = cli(capsys, "gait", out_file, "--objective", "speed", "--json")
    assert code == 0, err
    code, out, err = cli(capsys, "sim", out_file, "--duration", "30", "--json")
    assert code == 0 and json.loads(out)["displacement_mm"] > 0, err
    for argv, says in (((path, "--measure-matrix", "--out", path), "is the ROBOT file this command reads"),
                       ((path, "--measure-matrix", "--out", tmp_path / "no" / "m.toml"), "does not exist"),
                       ((path, "--out", tmp_path / "m.toml"), "--out: only with --measure-matrix")):
        code, out, err = cli(capsys, "sim", *argv)
        assert code == 2 and says in err and out == ""
    assert not (tmp_path / "m.toml").exists()


def test_learn_sim_takes_the_physical_plant_unless_a_truth_is_given(tmp_path):
    """--sim learns what the simulated body does; the table plant is the default only with
    --truth (a matrix to hide from the learner), as the issue's simulator has it."""
    from proleg.cli.learn import _check_options
    from proleg.cli.main import build_parser

    r1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"
    for extra, plant in (((), "physical"), (("--truth", str(r1)), "table"), (("--plant", "table"), "table")):
        args = build_parser().parse_args(["learn", str(r1), "--sim", "--log", str(tmp_path / "t.jsonl"), *extra])
        _check_options(args, linked=True)
        assert args.plant == plant, extra


def test_a_forbidden_mark_the_rule_already_leaves_out_is_warned_of(tmp_path, caplog):
    """000->020 (one-level moves a limb one level: no such transition) takes nothing out: a typo
    for 000->010 would go unseen."""
    with caplog.at_level("WARNING"):
        robot = load_robot(_write(tmp_path, [2, 3, 2], 'matrix = "unmeasured"\nallow = "one-level"\n'
                                                       'forbidden = ["000->010", "000->020"]'))
    said = [r.getMessage() for r in caplog.records if "forbidden[" in r.getMessage()]
    assert len(said) == 1 and "transitions.forbidden[2]: 000->020 is not a transition allow = 'one-level'" in said[0]
    t = robot.transitions
    assert t.lookup(t.index("000"), t.index("010")) is None


def test_the_load_warnings_of_an_unmeasured_file_say_forbidden_not_x(tmp_path, caplog):
    """caterpillar-4 unmeasured, one level a step: the states its body cannot hold are warned
    of as for the written matrix, but there is no entry to mark "x": forbidden is the fix."""
    text = (Path(__file__).resolve().parents[1] / "robots" / "caterpillar-4.toml").read_text()
    start = text.index("[transitions]")
    end = text.index("\n[", start + 1)
    path = tmp_path / "cat.toml"
    path.write_text(text[:start] + '[transitions]\nmatrix = "unmeasured"\nallow = "one-level"\n' + text[end:])
    with caplog.at_level("WARNING"):
        load_robot(path)
    said = [r.getMessage() for r in caplog.records if "cannot be held;" in r.getMessage()]
    assert said and all("list the transitions into it in [transitions] forbidden" in m for m in said)
    assert not any('"x"' in r.getMessage() for r in caplog.records)


def test_an_unmeasured_matrix_is_learned_in_mm_and_a_leftover_step_mm_is_said_and_dropped(tmp_path, caplog):
    """An unmeasured table counted in steps by default: a hand's ruler or a tracker gives mm, and
    --source manual asked for "Δx [steps]", so a learned file read 4 mm a step into what was
    measured in mm. It is mm now; a step_mm left from a written matrix is said not to be used
    (the table plant, its only reader, cannot drive an unmeasured matrix) and the learned file
    leaves it out, so that it loads; units = "steps" given keeps steps."""
    from proleg.learn.estimate import estimate
    from proleg.learn.measure import Trial
    from proleg.learn.robotfile import write_learned_robot

    path = _write(tmp_path, [2, 2], 'matrix = "unmeasured"\nallow = "one-level"', extra="[plant]\nstep_mm = 3.0\n")
    with caplog.at_level("WARNING"):
        robot = load_robot(path)
    assert robot.units == "mm" and robot.plant.step_mm == 1.0
    assert any("plant.step_mm is not used: an unmeasured matrix is learned in mm" in r.getMessage()
               for r in caplog.records)
    t = robot.transitions
    trials = [Trial(t.label(a), t.label(b), 0, 1, 2.5, None, None, "manual") for a, b in zip(t.src, t.dst)]
    learned = load_robot(write_learned_robot(robot, estimate(t, trials), tmp_path / "l.toml"))
    assert learned.units == "mm" and (learned.transitions.reward == 2.5).all()
    assert "# step_mm = 3.0   # the matrix is in mm now (learned)" in (tmp_path / "l.toml").read_text()
    steps = _write(tmp_path, [2, 2], 'matrix = "unmeasured"\nallow = "one-level"\nunits = "steps"',
                   extra="[plant]\nstep_mm = 3.0\n")
    assert load_robot(steps).units == "steps" and load_robot(steps).plant.step_mm == 3.0


def test_a_transition_the_simulated_body_did_not_make_is_forbidden_in_the_measured_file(tmp_path):
    """--measure-matrix --out of an unmeasured file: a transition the idealised drive did not make
    kept its 'old value', the unmeasured table's 0, and a gait went through it (a state the body
    cannot hold, with a warning). It is "x" now, named in a comment, as learning writes what it
    left out; every made one keeps its measurement."""
    import numpy as np

    from proleg.learn.robotfile import write_measured_robot
    from proleg.sim.physical.measure import MeasuredMatrix

    robot = load_robot(_write(tmp_path, [2, 2], 'matrix = "unmeasured"\nallow = "one-level"'))
    t = robot.transitions
    n = t.n_states
    mean, samples = np.full((n, n), np.nan), np.zeros((n, n), dtype=int)
    skip = (t.index("01"), t.index("11"))
    for k, (a, b) in enumerate(zip(t.src.tolist(), t.dst.tolist())):
        if (a, b) != skip:
            mean[a, b], samples[a, b] = 0.5 + k, 2
    m = MeasuredMatrix(t.labels(), mean, np.where(samples > 0, 0.1, np.nan), samples,
                       np.where(samples > 0, 0.8, np.nan), ("D1", "D1"), "test")
    out = write_measured_robot(robot, m, tmp_path / "m.toml")
    measured = load_robot(out).transitions
    assert measured.lookup(*skip) is None
    assert measured.n_transitions == t.n_transitions - 1
    for a, b in zip(measured.src.tolist(), measured.dst.tolist()):
        assert measured.reward[measured.lookup(a, b)] == mean[a, b]
    assert '# forbidden ("x") now: the idealised drive did not make them on the simulated body' in out.read_text()
    assert "01->11" in out.read_text()


@pytest.mark.parametrize("transitions", [
    'matrix = "unmeasured"\nallow = "one-level"\nforbidden = ["00->01", "00->10", "01->00", "10->00", "01->11", '
    '"10->11", "11->01", "11->10"]',
    'matrix = [["x", "x", "x", "x"], ["x", "x", "x", "x"], ["x", "x", "x", "x"], ["x", "x", "x", "x"]]',
], ids=["unmeasured-all-forbidden", "all-x"])
def test_measure_matrix_of_a_file_that_allows_no_transition_is_refused_and_writes_nothing(tmp_path, capsys,
                                                                                        transitions):
    """As learn refuses it: a robot file whose table forbids every transition has nothing to
    measure. --measure-matrix printed a table of dashes and wrote --out with an all-"x"
    matrix, exit 0."""
    path = _write(tmp_path, [2, 2], transitions)
    out_file = tmp_path / "measured.toml"
    code, out, err = cli(capsys, "sim", path, "--measure-matrix", "--out", out_file)
    assert code == 2 and out == ""
    assert "the robot file allows no transition" in err and "nothing to measure" in err
    assert not out_file.exists()


@pytest.mark.parametrize("transitions, says", [
    ('matrix = "unmeasured"\nallow = "one-level"', "the robot's matrix is unmeasured"),
    ('matrix = [["x", "x", "x", "x"], ["x", "x", "x", "x"], ["x", "x", "x", "x"], ["x", "x", "x", "x"]]',
     "fresh has no gait in +x or -x"),
], ids=["unmeasured", "all-x"])
def test_measure_climb_without_any_gait_is_refused_not_a_measurement(tmp_path, capsys, transitions, says):
    """A firmware that carries no gait has nothing to climb with: --measure-climb printed its
    header and "no gait moves: no max_climb_deg to suggest", exit 0, as if it had measured."""
    path = _write(tmp_path, [2, 2], transitions)
    code, out, err = cli(capsys, "sim", path, "--measure-climb")
    assert code == 2 and out == ""
    assert "--measure-climb: " in err and "the firmware carries no gait to climb with" in err and says in err


def test_the_build_says_an_unmeasured_robot_has_no_fallbacks_because_its_matrix_is_unmeasured(tmp_path):
    from proleg.firmware.gaits import fallback_lines

    unmeasured = load_robot(_write(tmp_path, [2, 2, 2], 'matrix = "unmeasured"\nallow = "one-level"'))
    assert fallback_lines(unmeasured) == [
        "fallback gaits: none (the matrix is unmeasured: no gait moves the robot yet, with or without a coil)"]
    one = Path(__file__).resolve().parents[1] / "robots" / "paper-r1-one-actuator.toml"
    assert fallback_lines(load_robot(one)) == ["fallback gaits: none (one actuator only)"]
