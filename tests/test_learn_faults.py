"""Learning and the transitions the robot cannot make: those the body model says it cannot hold
are not asked for (unless --try-unholdable), and one the robot faults on while making it, predicted
or not, is recorded as not made, the robot cooled and cleared, and the rest learned; only a fault
that is not a transition's (an E-stop, no transition under way, several in a row) stops learning.

On the simulated physical plant: tri-mixed (tests/fixtures) enters 101, which its body cannot hold
(a load warning says so; asked for, the firmware ends the step in STATE_TIMEOUT), and R1 with a
weak right coil (``[plant] power_scale``, no load warning) cannot raise its right end alone
(SMA_ON_LIMIT). Before, either ended ``proleg learn`` with exit 1 at the first fault."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from types import SimpleNamespace

import pytest
from build_checks import cli as run

from proleg.learn.makeable import not_asked, unholdable
from proleg.learn.measure import Failure, Trial, TrialLog
from proleg.learn.runner import FAULTS_IN_A_ROW, ExplorationError, Explorer
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
TRI = ROOT / "tests" / "fixtures" / "tri-mixed.toml"
R1 = ROOT / "robots" / "paper-r1.toml"
INTO_101 = {("001", "101"), ("100", "101"), ("111", "101")}
OUT_OF_101 = {("101", "001"), ("101", "100"), ("101", "111")}


def _records(log: Path) -> tuple[list[dict], list[dict]]:
    """(trials, failures) of a trial log, as JSON objects."""
    rows = [json.loads(line) for line in log.read_text().splitlines()[1:]]
    return [r for r in rows if "fault" not in r], [r for r in rows if "fault" in r]


def _matrix(path: Path) -> dict[tuple[str, str], object]:
    learned = tomllib.loads(path.read_text())["transitions"]
    labels = learned["states"]
    return {(a, b): learned["matrix"][i][j] for i, a in enumerate(labels) for j, b in enumerate(labels) if i != j}


def _weak_r1(tmp_path: Path, scale: float = 0.5) -> Path:
    """R1 whose right coil heats at ``scale`` of its power: it cannot raise the right end alone."""
    path = tmp_path / "r1-weak.toml"
    path.write_text(R1.read_text().replace("[safety]", f"[plant]\npower_scale = [1.0, {scale}]\n\n[safety]"))
    return path


def test_learning_leaves_out_the_transitions_of_a_state_the_body_cannot_hold_and_writes_them_x(tmp_path, capsys):
    log, out = tmp_path / "t.jsonl", tmp_path / "learned.toml"
    code, report, err = run(capsys, "learn", str(TRI), "--sim", "--plant", "physical", "--repeats", "2",
                            "--log", str(log), "--out", str(out))
    assert code == 0, err
    assert ("40 allowed transitions, 6 of them into or out of states the body cannot hold, not asked for (001->101, "
            "100->101, 101->001, 101->100, 101->111, … (1 more); 001->101: goes to state 101, which the simulated "
            "body cannot hold: in 101 'mid' (level 0) sits at 13.5°, past its level-1 edge 8.8°") in err
    assert "; --try-unholdable asks for them): 34 × 2 = 68 trials" in err
    trials, failures = _records(log)
    assert not failures and not [r for r in trials if "101" in (r["from"], r["to"])]  # never asked for
    assert "001->101   0         -        -         cannot hold" in report
    assert ('into or out of states the body cannot hold, not asked for (marked "x" in the learned file): 6 of 40: '
            in report)
    assert "too few trials" not in report
    learned = _matrix(out)
    assert all(learned[x] == "x" for x in INTO_101 | OUT_OF_101)
    assert isinstance(learned["000", "100"], float)
    assert "proleg learn --try-unholdable asks for them): 001->101, 100->101, 101->001" in out.read_text()


def test_try_unholdable_asks_for_them_and_a_fault_there_is_recorded_cooled_cleared_and_learning_goes_on(
        tmp_path, capsys):
    log, out = tmp_path / "t.jsonl", tmp_path / "learned.toml"
    code, report, err = run(capsys, "learn", str(TRI), "--sim", "--plant", "physical", "--repeats", "2",
                            "--log", str(log), "--out", str(out), "--try-unholdable")
    assert code == 0, err
    assert "40 allowed transitions × 2 = 80 trials" in err
    trials, failures = _records(log)
    failed = {(f["from"], f["to"]) for f in failures}
    assert failed and failed <= INTO_101 and all(f["fault"] == "FAULT STATE_TIMEOUT on mid" for f in failures)
    assert len(failures) == len(failed)  # a transition that faulted is never asked for again
    for f in failures:  # each asked for once, and not made
        assert not [r for r in trials if (r["from"], r["to"]) == (f["from"], f["to"])]
        assert f"the robot could not make {f['from']}->{f['to']}: FAULT STATE_TIMEOUT on mid; recorded" in err
        # the robot rested its cool-down (the rest between pieces, 2.2 s, and min_cooldown_ms, 0.8 s, at
        # least) before the fault was cleared and the next piece began
        after = min(r["t_start"] for r in trials if r["t_start"] > f["t_fault"])
        assert after - f["t_fault"] >= 3.0
    # everything else a closed tour can still reach was learned
    counts: dict[tuple[str, str], int] = {}
    for r in trials:
        counts[r["from"], r["to"]] = counts.get((r["from"], r["to"]), 0) + 1
    t = load_robot(TRI).transitions
    allowed = {(t.label(int(a)), t.label(int(b))) for a, b in zip(t.src, t.dst)}
    assert all(counts.get(x, 0) >= 2 for x in allowed - INTO_101 - OUT_OF_101)
    assert f"the robot faulted making {len(failed)} transition" in err and "exploration done" in err
    assert "no warning at load predicts" not in err  # the model predicted these
    assert "faulted on the robot, not asked for again (marked \"x\" in the learned file): " in report
    assert "FAULT STATE_TIMEOUT on mid at firmware time" in report
    learned = _matrix(out)
    assert all(learned[x] == "x" for x in failed)
    assert "# forbidden (\"x\") now: the robot faulted making them" in out.read_text()


def test_a_transition_a_weak_coil_cannot_make_is_marked_and_the_rest_learned_then_not_asked_for_again(
        tmp_path, capsys):
    """No load warning predicts it: the right coil at 30 % of its power, boosted to max_duty 0.8
    (as much heat as 40 % at the drive duty 0.6), cannot raise the right end (STATE_TIMEOUT, its
    on-time hits not latched: it cools and tries again until the step's time is up). At half
    power it makes every transition, late: the first on-time hit used to be taken for a fault of
    the transition (learn/runner.py: an unlatched hit is none)."""
    robot, log, out = _weak_r1(tmp_path, 0.3), tmp_path / "t.jsonl", tmp_path / "learned.toml"
    code, report, err = run(capsys, "learn", str(robot), "--sim", "--plant", "physical", "--repeats", "2",
                            "--log", str(log), "--out", str(out))
    assert code == 0, err
    assert "warning: " + str(robot) not in err  # nothing predicted at load
    trials, failures = _records(log)
    failed = {(f["from"], f["to"]) for f in failures}
    assert failed == {("00", "01"), ("10", "01"), ("00", "11"), ("10", "11")}  # every raise of the right end
    assert all(f["fault"] == "FAULT STATE_TIMEOUT on right" for f in failures)
    assert f"no warning at load predicts {', '.join(f'{a}->{b}' for a, b in sorted(failed))}" in err
    assert "00->01   0         -        -             faulted" in report
    rows = {ln.split()[0]: ln.split() for ln in report.splitlines() if ln.split()[:1] and "->" in ln.split()[0]}
    assert all(int(rows[f"{a}->{b}"][1]) >= 2 for a, b in {("00", "10"), ("10", "00")})
    learned = _matrix(out)
    assert learned["00", "01"] == "x" and isinstance(learned["10", "00"], float)

    # the same log again: the faulted transitions are not asked for, and said so
    code, _report, err = run(capsys, "learn", str(robot), "--sim", "--plant", "physical", "--repeats", "3",
                             "--log", str(log))
    assert code == 0, err
    assert f"12 allowed transitions, {len(failed)} of them faulted on the robot before, not asked for again " in err
    assert "--retry-faulted asks for them again)" in err
    again, refailed = _records(log)
    assert refailed == failures and not [r for r in again if (r["from"], r["to"]) in failed]

    # --retry-faulted asks again: the coil is still weak, so they fault again, once each
    code, _report, err = run(capsys, "learn", str(robot), "--sim", "--plant", "physical", "--repeats", "3",
                             "--log", str(log), "--retry-faulted")
    assert code == 0, err
    _trials, refailed = _records(log)
    assert len(refailed) == 2 * len(failures)


def test_a_transition_measured_before_it_faulted_keeps_its_measurement(tmp_path, capsys):
    log = tmp_path / "t.jsonl"
    with TrialLog(log, robot="paper-r1") as tl:
        for k in range(2):
            tl.append(Trial("00", "01", 2.0 * k, 2.0 * k + 1, -4.0, source="manual"))
        tl.append(Failure("00", "01", 9.0, "FAULT STATE_TIMEOUT on right"))
        tl.append(Failure("10", "11", 19.0, "FAULT STATE_TIMEOUT on right"))
    code, report, err = run(capsys, "learn", str(R1), "--log", str(log), "--report")
    assert code == 0, err
    assert "00->01   2     -4.00" in report and "10->11   0         -        -             faulted" in report
    assert "1 of 12: 10->11; 10->11: FAULT STATE_TIMEOUT on right at firmware time 19 s" in report
    reread = TrialLog(log, append=False)
    assert len(reread.trials) == 2 and [f.src + f.dst for f in reread.failures] == ["0001", "1011"]


def test_the_body_models_unholdable_transitions_are_asked_for_with_try_unholdable_only():
    tri = load_robot(TRI)
    t = tri.transitions
    names = {(t.label(int(t.src[e])), t.label(int(t.dst[e]))) for e in unholdable(tri)}
    assert names == INTO_101 | OUT_OF_101
    assert {left.kind for left in not_asked(tri).values()} == {"unholdable"}
    assert not_asked(tri, try_unholdable=True) == {}


# ---------------------------------------------------------------- the loop's decisions, offline
class _Faulting(Explorer):
    """An Explorer whose pieces fault as ``faults`` says (one per piece, None: the piece goes
    well and makes its transitions), recording what it sends and rests."""

    def __init__(self, robot, log, faults, **kw):
        self.did: list[str] = []
        client = SimpleNamespace(info=None, link=SimpleNamespace(clock=lambda: 0.0),
                                 set_telemetry_rate=lambda hz: None,
                                 clear=lambda what: self.did.append(f"clear {int(what)}"))
        super().__init__(client, robot, log, None, rest=lambda s: self.did.append(f"rest {s:g}"), **kw)
        self.faults = list(faults)
        self.asked: list[tuple[int, int]] = []

    def measured_state(self) -> int:
        return 0

    def run_piece(self, piece, record=True):
        t = self.robot.transitions
        self.asked += piece.transitions
        kind = self.faults.pop(0) if self.faults else None
        if kind is None:
            made = [Trial(t.label(a), t.label(b), 0.0, 1.0, 1.0) for a, b in piece.transitions]
            for tr in made:
                self.log.append(tr)
            return made
        a, b = piece.transitions[0]
        raise ExplorationError("the robot stopped", transition=(t.label(a), t.label(b)), fault=True,
                               making_failed=kind == "timeout", what=f"FAULT {kind}", t_fault=5.0)


def test_a_fault_while_making_a_transition_is_recorded_cooled_cleared_and_never_asked_for_again(tmp_path):
    robot = load_robot(R1)
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Faulting(robot, log, ["timeout"], repeats=1, seed=1)
        ex.run()
        first = ex.asked[0]
        assert [(f.src, f.dst) for f in log.failures] == [tuple(map(robot.transitions.label, first))]
        assert ex.asked.count(first) == 1
        rest = ex.limits.rest_s + robot.safety.min_cooldown_ms / 1000
        assert ex.did[:2] == [f"rest {rest:g}", "clear 1"]  # cooled first, then the fault cleared
        assert ex.fault_rest_s(12.0) == pytest.approx(12.0 * (1 / 0.8 - 1) + 0.8)
        assert ex.tally()[1] == 0


class _Cooling(_Faulting):
    """A robot measured in ``first`` (a limb still up, its coil cooling) and at rest after that."""

    def __init__(self, robot, log, first, **kw):
        super().__init__(robot, log, [], **kw)
        self.seen = [first]

    def measured_state(self) -> int:
        return self.seen.pop(0) if self.seen else 0


def test_a_robot_measured_where_no_piece_starts_is_looked_at_again_until_it_rests(tmp_path):
    """crab-3 (its 010 cannot be held: no transition into or out of it is asked for) measured
    in 010, as a robot whose middle coil still cools after a fault: learning stopped with
    "from 010, where the robot rests, no piece … reaches" every transition left, the robot on
    its way to 000 (a six-limb robot 0.6 s after a STATE_TIMEOUT). It looks again until the
    state stops changing, and goes on from there."""
    from proleg.learn import runner

    robot = load_robot(ROOT / "tests" / "fixtures" / "crab-3-entry.toml")
    t = robot.transitions
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Cooling(robot, log, t.index("010"), repeats=1, seed=1)
        ex.run(max_pieces=1)
        assert ex.asked and t.label(ex.asked[0][0]) == "000"
        look = f"rest {runner.SETTLE_LOOK_S:g}"
        assert ex.did[:2] == [look, look]  # 000, then 000 again
    with TrialLog(tmp_path / "u.jsonl") as log:  # a robot that stays where no piece starts: the error, as before
        ex = _Cooling(robot, log, t.index("010"), repeats=1, seed=1)
        ex.seen = [t.index("010")] * 3
        ex.measured_state = lambda: t.index("010")
        with pytest.raises(ExplorationError, match="from 010, where the robot rests, no piece"):
            ex.run(max_pieces=1)


@pytest.mark.parametrize("faults, why", [
    (["estop"], "the robot stopped"),  # not a transition's fault: stops as before
    (["timeout"] * FAULTS_IN_A_ROW, f"the robot faulted on {FAULTS_IN_A_ROW} transitions in a row"),
])
def test_a_fault_that_is_not_one_transitions_stops_learning_and_leaves_the_fault_latched(tmp_path, faults, why):
    robot = load_robot(R1)
    with TrialLog(tmp_path / "t.jsonl") as log:
        ex = _Faulting(robot, log, faults, repeats=1, seed=1)
        with pytest.raises(ExplorationError, match=why) as stop:
            ex.run()
        assert stop.value.fault
        assert ex.did.count("clear 1") == len(faults) - 1  # the last fault is left for the lab to look at
        assert len(log.failures) == len(faults) - (faults == ["estop"])


def test_an_on_time_hit_that_does_not_latch_is_no_fault_of_the_transition(tmp_path, capsys):
    """R1 with max_on_ms 600: a rise hits the on-time limit, the firmware reports it (EVENT
    FAULT SMA_ON_LIMIT, not latched: the coil cools and the gait goes on, docs/safety.md) and
    the gait walks. Learning took each such report for a fault that ended the transition: the
    first three transitions were marked not made and learning stopped ('3 in a row')."""
    path = tmp_path / "r1-short-on.toml"
    path.write_text(R1.read_text().replace("max_on_ms = 3000", "max_on_ms = 600")
                    .replace('units = "steps"', 'units = "steps"\ndefault_duration_s = 0.3'))
    _code, out, _ = run(capsys, "sim", path, "--duration", "20", "--json")  # exit 1: it reports faults
    walked = json.loads(out)
    assert walked["cycles"] >= 2 and walked["displacement_mm"] > 0, walked  # the gait walks ...
    assert any("SMA_ON_LIMIT" in str(f) for f in walked["faults"])  # ... through unlatched on-time hits
    log = tmp_path / "t.jsonl"
    code, _, err = run(capsys, "learn", path, "--sim", "--repeats", "2", "--log", log)
    trials, failures = _records(log)
    assert code == 0 and failures == [], err
    assert {(t["from"], t["to"]) for t in trials} == {(a, b) for a, b in _matrix(R1) if _matrix(R1)[a, b] != "x"}
