"""``proleg sim`` compares the run with what the matrix promises for its gait
(report/matrix_check.py): a run that walks the other way or not at all gets a NOTE (exit 0:
the simulation itself worked) and ``matrix_check`` in --json."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from proleg.cli.main import main
from proleg.report.matrix_check import check
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def run_json(capsys, *argv: str) -> tuple[int, dict]:
    rc = main(["sim", *argv, "--json"])
    return rc, json.loads(capsys.readouterr().out)


def test_r1_walks_the_way_its_matrix_says_and_gets_no_remark(capsys):
    rc, report = run_json(capsys, str(ROBOTS / "paper-r1.toml"), "--duration", "20")
    assert rc == 0 and report["cycles"] >= 2
    c = report["matrix_check"]
    assert c["agrees"] and c["remark"] is None
    assert c["units"] == "steps" and c["promised_mm"] is None  # steps on the physical plant: a sign only
    assert c["promised_per_cycle"] > 0 and report["mean_cycle_mm"] > 0


def test_a_gait_the_body_walks_backwards_is_remarked_on(capsys):
    """R3's +x gait walks -x on the physical plant (docs/plant.md, "R3")."""
    rc, report = run_json(capsys, str(ROBOTS / "paper-r3.toml"), "--duration", "30")
    assert rc == 0 and report["mean_cycle_mm"] < 0
    assert report["matrix_check"]["remark"] == "walked the other way"
    main(["sim", str(ROBOTS / "paper-r3.toml"), "--duration", "30"])
    text = capsys.readouterr().out
    assert "NOTE: the matrix promises +" in text and "walked the other way" in text and "--measure-matrix" in text


def test_on_the_table_plant_a_step_is_step_mm_and_the_robot_walks_it(capsys):
    robot = load_robot(ROBOTS / "paper-r1.toml")
    rc, report = run_json(capsys, str(ROBOTS / "paper-r1.toml"), "--plant", "table", "--duration", "10")
    c = report["matrix_check"]
    assert rc == 0 and c["agrees"]
    assert c["promised_mm"] == pytest.approx(c["promised_per_cycle"] * robot.plant.step_mm)
    assert report["mean_cycle_mm"] == pytest.approx(c["promised_mm"], rel=0.05)


@pytest.mark.parametrize("cycles, remark", [
    ([0.0, 1e-15, -1e-15], "did not move"),       # the 3-level robot of the sweep: +0.3 and back each cycle
    ([-2.0, -2.1], "walked the other way"),
    ([0.2, 0.3], "walked less than 10% of it"),  # 12 mm promised in mm units
    ([11.0, 12.5], None),
    ([5.0], None),                               # one cycle is too few to say: no check at all
])
def test_the_remark_follows_the_cycles(cycles, remark):
    robot = load_robot(ROBOTS / "paper-r1-stroke.toml")  # units = "mm"
    c = check(robot, "physical", 12.0, cycles)
    if len(cycles) < 2:
        assert c is None
    else:
        assert c.promised_mm == 12.0 and c.remark == remark


@pytest.mark.parametrize("cycles, remark", [
    ([12.0, 12.0], None),
    ([9.5, 9.5], None),     # within a quarter of it
    ([8.5, 8.5], "walked 71% of it on the table plant, which moves by the matrix: the plant made other "
                 "transitions than the gait's"),  # R1 at full strokes before passes: 12.0 of 25.1
    ([-12.0, -12.0], "walked the other way"),
])
def test_on_the_table_plant_a_cycle_far_from_the_matrix_is_remarked_on(cycles, remark):
    robot = load_robot(ROBOTS / "paper-r1-stroke.toml")  # units = "mm", no noise
    assert check(robot, "table", 12.0, cycles, 2).remark == remark
    assert check(robot, "physical", 12.0, cycles, 2).remark == (None if cycles[0] > 0 else remark)


def test_a_promise_under_a_micrometre_kept_exactly_on_the_table_plant_is_no_remark(capsys, tmp_path):
    """[plant] step_mm = 1e-9 (any step in (0, 1000] is valid): the table plant walked exactly the
    3e-9 mm a cycle the matrix promises, and the run was remarked on as "did not move"."""
    tiny = tmp_path / "tiny.toml"
    tiny.write_text((ROBOTS / "paper-r1.toml").read_text(encoding="utf-8") + "\n[plant]\nstep_mm = 1e-9\n",
                    encoding="utf-8")
    rc, report = run_json(capsys, str(tiny), "--plant", "table", "--duration", "10")
    c = report["matrix_check"]
    assert rc == 0 and report["mean_cycle_mm"] == pytest.approx(c["promised_mm"], rel=1e-6)
    assert c["agrees"] and c["remark"] is None
    robot = load_robot(tiny)
    assert check(robot, "table", 3.0, [1e-15, -1e-15]).remark == "did not move"  # still still
