"""``proleg sim ROBOT --measure-matrix --hold-range --jobs N``: the hold margins measured at once
in worker processes give the numbers measured one after another, whatever N; a bad N is a usage
mistake (exit 2, one line), and so is --jobs where there is nothing to measure at once."""

from __future__ import annotations

from pathlib import Path

import pytest
from build_checks import cli as run

ROOT = Path(__file__).resolve().parents[1]
R1 = ROOT / "robots" / "paper-r1.toml"


def test_hold_range_margins_measured_in_workers_are_byte_for_byte_those_measured_one_after_another(capsys):
    outs = {}
    for jobs in ("1", "2", "3"):
        code, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--hold-range", "--json", "--jobs", jobs)
        assert code == 0 and "Traceback" not in err, err
        outs[jobs] = out
    assert outs["1"] == outs["2"] == outs["3"] and '"hold_margins_deg": [2.0, 4.0, 8.0]' in outs["1"]


def test_hold_range_in_workers_says_how_far_it_has_got_over_every_margin():
    """The workers' counts reach the progress line summed over the margins, as one after another."""
    from proleg.robot import load_robot
    from proleg.sim.physical.measure import measure_matrix_range

    said: list[tuple[int, int, int]] = []
    measure_matrix_range(load_robot(R1), repeats=1, jobs=3, on_step=lambda *x: said.append(x))
    assert said[-1] == (36, 36, 36) and all(n == 36 for _, _, n in said)
    assert [t for t, _, _ in said] == sorted(t for t, _, _ in said) and len(said) == 36


@pytest.mark.parametrize("value, expected", [("0", "expected at least 1, got 0"), ("-2", "expected at least 1, got -2"),
                                             ("x", "expected a whole number, got 'x'"),
                                             ("1.5", "expected a whole number, got '1.5'")])
def test_a_bad_jobs_value_is_a_usage_mistake_in_one_line(capsys, value, expected):
    from proleg.cli.main import main

    with pytest.raises(SystemExit) as e:   # argparse's usage error, before anything is measured
        main(["sim", str(R1), "--measure-matrix", "--hold-range", f"--jobs={value}"])
    out, err = capsys.readouterr()
    assert e.value.code == 2 and out == "" and "Traceback" not in err
    assert err.splitlines()[-1] == f"proleg sim: error: argument --jobs: {expected}"


@pytest.mark.parametrize("mode", [["--measure-matrix"], ["--measure-climb"], []], ids=["matrix", "climb", "run"])
def test_jobs_without_hold_range_is_refused_not_ignored(capsys, mode):
    """One matrix is one chain of transitions on one body: nothing to measure at once, and a
    --jobs that changed nothing would look like one that did."""
    code, out, err = run(capsys, "sim", str(R1), *mode, "--jobs", "2")
    assert code == 2 and out == "" and "Traceback" not in err
    assert "--jobs: only with --measure-matrix --hold-range" in err


def test_the_six_limb_bench_body_loads_quietly_with_one_pad_per_transition(caplog):
    """tests/fixtures/caterpillar-6.toml, bench/bench_plant.py's large --measure-matrix: 64 states,
    each transition raising or lowering one pad (384), no load warning a lab would have to read past."""
    import logging

    from proleg.robot import load_robot

    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(ROOT / "tests" / "fixtures" / "caterpillar-6.toml")
    _, allowed = robot.transitions.dense()
    assert len(allowed) == 64 and robot.transitions.n_transitions == 384 and not caplog.records
    assert all(bin(a ^ b).count("1") == 1 for a in range(64) for b in range(64) if allowed[a][b])
