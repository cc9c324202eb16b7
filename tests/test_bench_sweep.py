"""bench/bench_sweep.py's pieces: its random rows (``proleg.report.sweep``, which ``proleg check``
draws too) are conditions every example robot's plant takes (a draw out of a key's range or naming an end a robot lacks would stop the bench
mid-run), the same seed draws the same rows, and its summary counts what its rows say."""

from __future__ import annotations

import importlib.util
import logging
from pathlib import Path

import pytest
from proleg.paths import robots_dir
from proleg.report import sweep as draws
from proleg.robot import load_robot
from proleg.sim.closed_loop import make_plant

ROOT = Path(__file__).resolve().parents[1]


def _bench():
    spec = importlib.util.spec_from_file_location("bench_sweep", ROOT / "bench" / "bench_sweep.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


sweep = _bench()


@pytest.mark.parametrize("name", sweep.ROBOTS)
def test_every_draw_is_a_condition_the_robots_plant_takes(name):
    robot = load_robot(robots_dir() / f"{name}.toml")
    logging.disable(logging.WARNING)  # the plant's overheat advice for hot draws
    try:
        for row in draws.draw_rows(40, seed=3):
            assert len(row) == draws.KEYS_PER_ROW
            assert len({c.split("=")[0] for c in row}) == draws.KEYS_PER_ROW, row
            make_plant(robot, "physical", list(row))  # SimError on a bad key, value or end
    finally:
        logging.disable(logging.NOTSET)


def test_the_seed_decides_the_rows():
    assert draws.draw_rows(10, seed=5) == draws.draw_rows(10, seed=5)
    assert draws.draw_rows(10, seed=5) != draws.draw_rows(10, seed=6)
    keys = {c.split("=")[0] for row in draws.draw_rows(200, seed=1) for c in row}
    assert keys == set(draws.DRAWS)  # every key gets drawn


def _row(possible, completed, peak, *, idealised=0.4, fault="", note=""):
    return draws.Row(("power=1",), possible, "" if possible else "the coils cannot", idealised if possible else None,
                     completed, 0.4 if completed else -0.001, fault, note, peak, "")


def test_the_summary_counts_its_rows():
    rows = [_row(True, True, 80.0), _row(True, False, 130.0), _row(False, False, 90.0),
            _row(False, False, 125.0), _row(False, True, 70.0)]
    s = sweep.summary(sweep.judged(rows, 0.4))
    assert (s["rows"], s["possible"], s["completed_where_possible"]) == (5, 2, 1)
    assert (s["impossible"], s["impossible_completed_by_the_firmware"], s["impossible_stopped_below_120c"]) == (3, 1, 1)
    assert (s["overheated"], s["hottest_c"]) == (2, 130.0)
    assert (s["missed"], s["drifted"], s["hot_stops"]) == (1, 0, 1)


def test_a_row_the_gait_barely_moves_is_drifted_as_proleg_check_says_not_missed():
    """A row where the idealised drive makes under 5 % of its nominal speed, and the firmware
    drifts back without a fault and cool, is 'drifted' in proleg check; the bench, with no
    nominal speed, counted it missed. Its verdicts are now check's own (report.sweep)."""
    wrong_way = "walks the wrong way: -0.001 mm/s"
    rows = [
        _row(True, False, 70.0, idealised=0.01, note=wrong_way),                  # drifted: 2.5 % of 0.4
        _row(True, False, 70.0, idealised=0.3, note=wrong_way),                   # missed: the gait walks there
        _row(True, False, 70.0, idealised=0.01, fault="STATE_TIMEOUT", note=""),  # missed: a fault stop
        _row(True, False, 125.0, idealised=0.01, note=wrong_way),                 # missed: a coil past 120 °C
        _row(True, True, 70.0, idealised=0.01),                                   # ok
    ]
    judged = sweep.judged(rows, 0.4)
    assert [r.verdict for r in judged] == ["drifted", "missed", "missed", "missed", "ok"]
    s = sweep.summary(judged)
    assert (s["missed"], s["drifted"]) == (3, 1)
    out = [sweep.row_json("paper-r1", i, r) for i, r in enumerate(judged)]
    assert [(r["missed"], r["drifted"], r["verdict"]) for r in out][:2] == [(False, True, "drifted"),
                                                                              (True, False, "missed")]
    # the one classification: what proleg check's own pass gives
    assert judged == draws.barely_moving(rows, 0.4)
    assert sweep.judged(rows, None)[0].verdict == "missed"  # no nominal speed to measure against
