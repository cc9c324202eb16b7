"""``proleg gait --evaluate`` and ``proleg load-gait`` read a gait through one parser
(``TransitionTable.cycle``): the closed spelling (the start repeated at the end) and the open
one are the same gait for both. ``--evaluate`` needed the repeat ("sequence must return to its
start") where ``load-gait`` did not."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from proleg.cli import main
from proleg.robot import load_robot

R1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("closed, open_", [("00,10,01,00", "00,10,01"), ("00,10,11,01,00", "00,10,11,01"),
                                            ("00,01,00", "00,01"), ("10,00,01,10", "10,00,01")])
def test_the_closed_and_the_open_spelling_are_one_gait_for_the_parser(closed, open_):
    t = load_robot(R1).transitions
    assert t.cycle(closed) == t.cycle(open_) == [t.index(s) for s in open_.split(",")]


@pytest.mark.parametrize("closed, open_", [("00,10,01,00", "00,10,01"), ("00,10,11,01,00", "00,10,11,01")])
def test_evaluate_scores_both_spellings_alike(capsys, closed, open_):
    answers = []
    for seq in (closed, open_):
        code, out, err = run(capsys, "gait", R1, "--evaluate", seq, "--json")
        assert code == 0, err
        answers.append(json.loads(out))
    assert answers[0] == answers[1]
    texts = [run(capsys, "gait", R1, "--evaluate", seq) for seq in (closed, open_)]
    assert texts[0] == texts[1] and texts[0][0] == 0


@pytest.mark.parametrize("closed, open_", [("00,10,01,00", "00,10,01"), ("00,10,11,01,00", "00,10,11,01")])
def test_load_gait_loads_both_spellings_alike(capsys, closed, open_):
    a = run(capsys, "load-gait", "paper-r1", "--sim", closed)
    b = run(capsys, "load-gait", "paper-r1", "--sim", open_)
    assert a == b and a[0] == 0, a[2]
    assert f"loaded {' → '.join(closed.split(','))} as the user gait" in a[1]


@pytest.mark.parametrize("seq, words", [
    ("00", "'00' is not a gait: it needs at least two states"),
    ("00,00", "'00,00' is not a gait: it needs at least two states"),
    ("00,10,10,01", "10 follows itself (entry 3 of '00,10,10,01')"),
    ("00,10,00,00", "00 follows itself (entry 4 of '00,10,00,00')"),
    ("00,,10", "entry 2 of '00,,10' is empty"),
    ("00,12,00", "state label '12': digit 2 ('2') is not a level of limb 'right'"),
])
@pytest.mark.parametrize("command, argument", [(("gait", R1, "--evaluate"), "--evaluate"),
                                               (("load-gait", "paper-r1", "--sim"), "STATES")])
def test_a_sequence_that_is_neither_spelling_exits_2_naming_the_argument(capsys, seq, words, command, argument):
    code, out, err = run(capsys, *command, seq)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"proleg: error: {argument}: ") and words in err
