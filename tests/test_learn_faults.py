"""Learning and the transitions the robot cannot make: those the body model says it cannot hold
are not asked for (unless --try-unholdable).

On the simulated physical plant: tri-mixed (tests/fixtures) enters 101, which its body cannot hold
(a load warning says so; asked for, the firmware ends the step in STATE_TIMEOUT, which ended
``proleg learn`` with exit 1)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from build_checks import cli as run

from proleg.learn.makeable import not_asked, unholdable
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


def test_the_body_models_unholdable_transitions_are_asked_for_with_try_unholdable_only():
    tri = load_robot(TRI)
    t = tri.transitions
    names = {(t.label(int(t.src[e])), t.label(int(t.dst[e]))) for e in unholdable(tri)}
    assert names == INTO_101 | OUT_OF_101
    assert {left.kind for left in not_asked(tri).values()} == {"unholdable"}
    assert not_asked(tri, try_unholdable=True) == {}
