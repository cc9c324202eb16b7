"""``proleg sim``'s plant options: --plant, --condition, --measure-matrix, the robot file's
[plant] conditions, and ``speed_mm_s`` in --json."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from build_checks import cli as run
from hypothesis import given as for_all
from hypothesis import strategies as st

from proleg.cli.main import main
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot, plant_conditions
from proleg.sim.physical import PhysicalPlant

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
R1 = ROBOTS / "paper-r1.toml"


def test_the_physical_plant_is_the_default_and_json_adds_speed(capsys):
    rc, out, _ = run(capsys, "sim", str(R1), "--duration", "20", "--json")
    report = json.loads(out)
    assert rc == 0 and report["faults"] == []
    # the physical plant's R1 makes ~1.5 mm per cycle; the table plant's matrix says 3 × 4 mm
    assert 0.5 < report["mean_cycle_mm"] < 3.0
    assert report["speed_mm_s"] == pytest.approx(report["displacement_mm"] / report["duration_s"])
    for field in ("faults", "cycles", "displacement_mm", "duration_s", "states_reached", "true_transitions"):
        assert field in report


def test_plant_table_is_the_lookup_of_the_robot_matrix(capsys):
    rc, out, _ = run(capsys, "sim", str(R1), "--plant", "table", "--duration", "10", "--json")
    report = json.loads(out)
    assert rc == 0 and report["mean_cycle_mm"] == pytest.approx(12.0)  # (1 + 1 + 1) × step_mm 4


def test_a_condition_changes_the_run(capsys):
    _, base, _ = run(capsys, "sim", str(R1), "--duration", "20", "--json")
    _, hot, _ = run(capsys, "sim", str(R1), "--duration", "20", "--json", "--condition", "incline_deg=8",
                    "--condition", "friction=0.5")
    assert json.loads(hot)["displacement_mm"] != pytest.approx(json.loads(base)["displacement_mm"], abs=0.05)


def test_sim_json_echoes_the_conditions_given_and_those_in_effect(capsys, tmp_path):
    """The sweep's 3.7: sim --json did not say which conditions the run had (measure-matrix
    --json echoed the --condition strings). Now every report has ``conditions`` (as given) and
    ``effective_conditions`` (the robot file's [plant] with them on top, as --condition takes)."""
    path = tmp_path / "paper-r1.toml"
    path.write_text(R1.read_text() + "\n[plant]\nsupply_v = [8.0, 4.0]\nambient_c = 30.0\n")
    given = ["--condition", "ambient_c=20", "--condition", "imu_bias_deg=right:3"]
    rc, out, _ = run(capsys, "sim", str(path), "--duration", "2", "--json", *given)
    report = json.loads(out)
    assert rc == 0 and report["plant"] == "physical"
    assert report["conditions"] == ["ambient_c=20", "imu_bias_deg=right:3"]
    # supply_v per coil: each coil's own (it was the highest and a power_scale of (V / V_max)²)
    assert report["effective_conditions"] == ["supply_v=sma-left:8.0", "supply_v=sma-right:4.0", "ambient_c=20.0",
                                              "imu_bias_deg=right:3.0"]
    # the strings are what --condition takes: the same plant
    again = plant_conditions(load_robot(R1), report["effective_conditions"])
    assert again == plant_conditions(load_robot(path), report["conditions"])
    rc, out, _ = run(capsys, "sim", str(path), "--measure-matrix", "--json", *given)
    assert json.loads(out)["effective_conditions"] == report["effective_conditions"]
    rc, out, _ = run(capsys, "sim", str(R1), "--plant", "table", "--duration", "2", "--json")
    report = json.loads(out)
    assert report["plant"] == "table" and report["conditions"] == report["effective_conditions"] == []


def test_effective_conditions_name_each_limb_and_coil_once_and_can_be_given_back(capsys, tmp_path):
    """A robot file's overlap_mm = 20 and imu_bias_deg = [1, 2] under --condition overlap_mm=right:14
    and imu_bias_deg=0:3 (the right limb's coil, the first limb): effective_conditions listed
    'overlap_mm=sma-right:20.0' and 'overlap_mm=right:14.0', 'imu_bias_deg=left:1.0' and
    'imu_bias_deg=0:3.0', each item twice, and given back as --condition (which the docs promise)
    they were refused: "both name actuator 'sma-right'". Each is listed once now, by the name its
    value was last given by (the value the plant uses), and the same run comes out of R1 with them."""
    path = tmp_path / "paper-r1.toml"
    path.write_text(R1.read_text() + "\n[plant]\noverlap_mm = 20.0\nimu_bias_deg = [1.0, 2.0]\n")
    rc, out, _ = run(capsys, "sim", str(path), "--duration", "5", "--json", "--condition", "overlap_mm=right:14",
                     "--condition", "imu_bias_deg=0:3")
    report = json.loads(out)
    assert rc == 0 and sorted(report["effective_conditions"]) == [
        "imu_bias_deg=0:3.0", "imu_bias_deg=right:2.0", "overlap_mm=right:14.0", "overlap_mm=sma-left:20.0"]
    given = [a for c in report["effective_conditions"] for a in ("--condition", c)]
    rc, out, err = run(capsys, "sim", str(R1), "--duration", "5", "--json", *given)
    assert rc == 0, err
    assert json.loads(out)["displacement_mm"] == report["displacement_mm"]


@pytest.mark.parametrize("args, words", [
    (["--condition", "speed=3"], "condition 'speed': unknown key"),
    # the robot's own body and coils are the robot file's: "unknown key" did not say where they go
    (["--condition", "working_strain=0.03"], "condition 'working_strain': a key of the robot file's [plant] table only"),
    (["--condition", "coil_diameter_mm=0.6"], "condition 'coil_diameter_mm': a key of the robot file's [plant] table"),
    (["--condition", "power=9"], "condition power: 9 is outside [0.2, 2] ×"),
    # the value as given: it read "2 is outside [0.2, 2]", "20 is outside [-20, 20]"
    (["--condition", "power=2.0000001"], "condition power: 2.0000001 is outside [0.2, 2] ×"),
    (["--condition", "imu_bias_deg=left:20.0000001"], "condition imu_bias_deg: 20.0000001 is outside [-20, 20] °"),
    # "expected a number in ×" read oddly, "nan is outside" as if nan were a number
    (["--condition", "power=abc"], "condition power: expected a number (a factor, ×), got 'abc'"),
    (["--condition", "ambient_c=warm"], "condition ambient_c: expected a number (in °C), got 'warm'"),
    (["--condition", "coil_mismatch=abc"], "condition coil_mismatch: expected a number, got 'abc'"),
    (["--condition", "power=nan"], "condition power: expected a finite number in [0.2, 2] ×, got 'nan'"),
    (["--condition", "imu_bias_deg=middle:2"], "no limb 'middle'"),
    (["--plant", "table", "--condition", "power=0.9"], "conditions apply to the physical plant"),
    (["--condition", "incline_deg=5", "--condition", "incline_deg=-5"],
     "condition incline_deg: given twice ('incline_deg=5' and 'incline_deg=-5'); give it once"),
    (["--condition", "imu_offset_deg=left:8", "--condition", "imu_offset_deg=left:-8"],
     "condition imu_offset_deg for 'left': given twice"),
    # one limb or coil under two of its names: the last one was silently taken
    (["--condition", "imu_bias_deg=rear:3", "--condition", "imu_bias_deg=left:4"],
     "condition imu_bias_deg: 'imu_bias_deg=rear:3' and 'imu_bias_deg=left:4' both name limb 'left'; give it once"),
    (["--condition", "imu_bias_deg=1:3", "--condition", "imu_bias_deg=front:4"], "both name limb 'right'"),
    (["--condition", "power_scale=right:0.8", "--condition", "power_scale=sma-right:0.9"],
     "both name actuator 'sma-right'"),
])
def test_a_bad_condition_is_one_line_without_traceback(capsys, args, words):
    rc, out, err = run(capsys, "sim", str(R1), "--duration", "1", *args)
    assert rc != 0 and words in err and err.count("\n") == 1 and "Traceback" not in err


def test_condition_help_lists_every_key_with_its_range(capsys):
    from proleg.sim.physical import CONDITION_KEYS

    rc, out, _ = run(capsys, "sim", str(R1), "--condition", "help")
    assert rc == 0
    for key, spec in CONDITION_KEYS.items():
        line = next(x for x in out.splitlines() if x.startswith(key + " "))
        assert spec.range_text() in line


def test_measure_matrix_json_has_states_matrix_in_mm_and_sample_counts(capsys):
    rc, out, _ = run(capsys, "sim", str(R1), "--measure-matrix", "--json")
    m = json.loads(out)
    assert rc == 0 and m["states"] == ["00", "01", "10", "11"] and m["units"] == "mm"
    paper = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]
    for a in range(4):
        for b in range(4):
            if a != b:
                assert m["samples"][a][b] >= 1
                if paper[a][b]:
                    assert m["matrix"][a][b] * paper[a][b] > 0, (a, b)


def test_measure_matrix_says_each_coils_hottest_and_warns_past_120_c(capsys, tmp_path):
    """A supply that cooks the coils while measuring (R1 at 60 V: 145 °C) was said nowhere;
    ``proleg sim`` fails a firmware run past 120 °C. The JSON gives each coil's hottest."""
    rc, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--json")
    peaks = json.loads(out)["coil_peak_c"]
    assert rc == 0 and set(peaks) == {"sma-left", "sma-right"} and all(25 < t < 120 for t in peaks.values())
    assert "wears NiTi out" not in err
    rc, out, _ = run(capsys, "sim", str(R1), "--measure-matrix")
    assert rc == 0 and "coils, hottest while measuring: sma-left " in out
    learned = tmp_path / "hot.toml"
    rc, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--json", "--condition", "supply_v=60",
                       "--out", str(learned))
    peaks = json.loads(out)["coil_peak_c"]
    assert all(t > 120 for t in peaks.values()), peaks
    assert "warning: --measure-matrix: coil sma-left reached" in err and "past the 120 °C that wears NiTi out" in err


@for_all(st.lists(st.dictionaries(st.sampled_from(["a", "b", "c"]), st.floats(-50, 500)), min_size=1, max_size=4))
def test_the_hottest_of_several_measurements_is_each_coils_highest(peaks):
    from proleg.sim.physical.measure import MeasuredMatrix, hottest

    empty = np.zeros((1, 1))
    got = hottest([MeasuredMatrix(["0"], empty, empty, empty.astype(int), empty, (), "", p) for p in peaks])
    assert got == {k: max(p[k] for p in peaks if k in p) for k in set().union(*peaks)}


def test_measure_matrix_tells_an_allowed_transition_the_body_did_not_make_from_a_forbidden_one(capsys):
    """A three-level rear pad (ψ* 10°, 22°) beside a binary front one: the raised front end
    lifts the rear pad past 10°, so 01 is never reached. Its four allowed transitions were
    shown '-', like the forbidden ones ("entries without a sample"); they are '?' now, named
    in a line, and --json lists them as not_made."""
    path = Path(__file__).parent / "fixtures" / "l3-l2.toml"
    rc, out, _ = run(capsys, "sim", str(path), "--measure-matrix", "--json")
    m = json.loads(out)
    assert rc == 0 and m["not_made"] == ["00->01", "01->00", "01->11", "11->01"]
    assert all(m["samples"][1][b] == 0 and m["matrix"][1][b] is None for b in range(6))
    rc, out, _ = run(capsys, "sim", str(path), "--measure-matrix")
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines() if line[:2] in ("00", "01")}
    assert rc == 0 and rows["00"][:3] == [".", "?", rows["00"][2]] and rows["00"][3:] == ["-", "-", "-"]
    assert rows["01"] == ["?", ".", "-", "?", "-", "-"]
    assert "'?': allowed, but not made on the simulated body (4 of 14: 00->01, 01->00, 01->11, 11->01)" in out


def test_measure_matrix_does_not_point_at_load_warnings_that_were_never_printed(capsys):
    """The same pads with a narrower band and hold margin: the load checks pass 11 -> 01, yet
    the held front coil overshoots its hold and keeps the rear pad past its edge, so the step
    never ends. The line said "see the warnings when the robot file was loaded", and there were
    none."""
    path = Path(__file__).parent / "fixtures" / "l3-l2-narrow.toml"
    rc, out, err = run(capsys, "sim", str(path), "--measure-matrix")
    assert rc == 0 and "warning" not in err, err
    line = next(x for x in out.splitlines() if x.startswith("'?'"))
    assert "(1 of 14: 11->01)" in line
    assert "see the warnings" not in line and "no warning when the robot file was loaded foresaw it" in line
    assert f"proleg sim {path} --record run.csv" in line
    rc, out, _ = run(capsys, "sim", str(Path(__file__).parent / "fixtures" / "l3-l2.toml"), "--measure-matrix")
    assert "(see the warnings when the robot file was loaded)" in out  # there, 11→01 was warned of


def test_measure_matrix_says_how_far_it_has_got(capsys, monkeypatch):
    """A 96-state robot measured for ten minutes without a word on stderr; it says how many
    transitions it has tried, of how many, every PROGRESS_EVERY_S."""
    from proleg.cli import sim_plant

    monkeypatch.setattr(sim_plant, "PROGRESS_EVERY_S", 0.0)
    rc, _, err = run(capsys, "sim", str(R1), "--measure-matrix")
    said = [x.removeprefix("proleg: ") for x in err.splitlines() if x.startswith("proleg: measure-matrix: ")]
    assert rc == 0 and said[0].startswith("measure-matrix: 1/24 trials, about ") and len(said) == 23, said
    assert said[-1].startswith("measure-matrix: 23/24 trials")


def test_measure_matrix_hold_range_brackets_the_4_degree_matrix_and_says_its_margins(capsys):
    rc, out, _ = run(capsys, "sim", str(R1), "--measure-matrix", "--json")
    plain = json.loads(out)
    rc, out, _ = run(capsys, "sim", str(R1), "--measure-matrix", "--hold-range", "--json")
    m = json.loads(out)
    assert rc == 0 and m["hold_margins_deg"] == [2.0, 4.0, 8.0]
    assert m["matrix"] == plain["matrix"] and m["samples"] == plain["samples"]  # the 4° measurement
    spans = []
    for a in range(4):
        for b in range(4):
            if a != b:
                assert m["low"][a][b] <= m["matrix"][a][b] <= m["high"][a][b], (a, b)
                spans.append(m["high"][a][b] - m["low"][a][b])
    assert max(spans) > 0.1  # the hold moves R1's entries (docs/plant.md)


def test_measure_matrix_hold_range_prints_each_entrys_low_and_high(capsys, monkeypatch):
    from proleg.sim.physical import measure as measure_mod

    rng = measure_mod.MatrixRange((2.0, 4.0, 8.0), (None, measure_mod.measure_matrix(load_robot(R1), repeats=1), None),
                                  np.full((4, 4), -0.25), np.full((4, 4), 1.5))
    monkeypatch.setattr(measure_mod, "measure_matrix_range", lambda *a, **k: rng)
    rc, out, _ = run(capsys, "sim", str(R1), "--measure-matrix", "--hold-range")
    lines = out.splitlines()
    at = lines.index(next(x for x in lines if "range over hold margins 2/4/8° past psi*" in x))
    assert rc == 0 and lines[at + 2].split() == ["00", ".", "-0.25..+1.50", "-0.25..+1.50", "-0.25..+1.50"]


def test_measure_matrix_history_range_pools_three_orders_and_writes_that_matrix(capsys, tmp_path):
    """--history-range: the matrix made in three orders; --json's matrix is their pooled mean
    (three times the samples), bracketed by each entry's range over them, and --out writes it:
    the file a lab builds from averages over what came before each step, and its var_dx shows
    how much that moves it."""
    out_file = tmp_path / "pooled.toml"
    rc, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--history-range", "--jobs", "2", "--json",
                       "--out", str(out_file))
    m = json.loads(out)
    assert rc == 0 and m["orders"] == ["rows", "reversed", "shuffled"], err
    rc, plain_out, _ = run(capsys, "sim", str(R1), "--measure-matrix", "--json")
    plain = json.loads(plain_out)
    learned = load_robot(out_file)
    dense, _ = learned.transitions.dense()
    var = learned.transitions.planar.var_dx
    for a in range(4):
        for b in range(4):
            if a != b:
                assert m["samples"][a][b] == 3 * plain["samples"][a][b]
                assert m["low"][a][b] - 1e-4 <= m["matrix"][a][b] <= m["high"][a][b] + 1e-4, (a, b)
                assert m["low"][a][b] - 1e-4 <= plain["matrix"][a][b] <= m["high"][a][b] + 1e-4, (a, b)
                assert abs(dense[a][b] - m["matrix"][a][b]) < 1e-4
    spread = max(var[learned.transitions.lookup(0, 3)], var[learned.transitions.lookup(3, 0)])
    assert spread > 0.05  # 00↔11: (≥ 0.5 mm between orders)² / several, where one order's samples agree
    for argv, says in ((("--measure-matrix", "--history-range", "--hold-range"), "one range at a time"),
                       (("--history-range",), "--history-range: it is an option of --measure-matrix"),
                       (("--measure-matrix", "--jobs", "2"), "--jobs: only with --measure-matrix --hold-range or "
                                                             "--history-range")):
        rc, out, err = run(capsys, "sim", str(R1), *argv)
        assert rc == 2 and says in err and out == "", (argv, err)


def test_hold_range_without_measure_matrix_is_a_one_line_error(capsys):
    rc, _, err = run(capsys, "sim", str(R1), "--hold-range")
    assert rc != 0 and "--hold-range: it is an option of --measure-matrix" in err and "Traceback" not in err


def test_the_robot_file_plant_table_sets_conditions_and_the_command_line_goes_on_top(tmp_path):
    text = R1.read_text() + "\n[plant]\npower = 0.8\nimu_bias_deg = [1.0, -2.0]\nsupply_v = [7.0, 6.0]\n"
    path = tmp_path / "r1-tired.toml"
    path.write_text(text)
    robot = load_robot(path)
    cond = plant_conditions(robot, ["power=1.1", "imu_bias_deg=right:3"])
    names = [lb.name for lb in robot.limbs]
    acts = [a.name for a in robot.actuators]
    assert cond.get("power") == 1.1
    assert cond.for_index("imu_bias_deg", 0, names) == 1.0 and cond.for_index("imu_bias_deg", 1, names) == 3.0
    assert cond.for_index("supply_v", 0, acts) == 7.0 and cond.for_index("supply_v", 1, acts) == 6.0
    assert cond.for_index("power_scale", 1, acts) == 1.0


def test_a_physical_key_out_of_range_in_the_robot_file_is_one_line(tmp_path):
    from proleg.errors import RobotFileError

    path = tmp_path / "bad.toml"
    path.write_text(R1.read_text() + "\n[plant]\nincline_deg = 30\n")
    with pytest.raises(RobotFileError, match=r"bad\.toml: plant\.incline_deg: expected a number in \[-12, 12\] °, got 30$"):
        load_robot(path)


def test_simulated_robot_takes_the_plant_choice():
    robot = load_robot(R1)
    assert isinstance(SimulatedRobot(robot).plant, PhysicalPlant)
    assert SimulatedRobot(robot, plant="table").plant_kind == "table"
    sim = SimulatedRobot(robot, conditions=["ambient_c=30"])
    assert sim.plant.conditions.get("ambient_c") == 30.0


def test_each_end_once_and_all_limbs_beside_one_are_not_a_repeat(capsys):
    """rear and front are two limbs; a value for all limbs and one for a single limb is how
    to set all but one."""
    rc, out, err = run(capsys, "sim", str(R1), "--duration", "1", "--json", "--condition", "imu_bias_deg=rear:3",
                       "--condition", "imu_bias_deg=front:-2", "--condition", "power_scale=0.9",
                       "--condition", "power_scale=left:0.8")
    assert rc == 0, err
    assert json.loads(out)["effective_conditions"] == [
        "power_scale=0.9", "power_scale=left:0.8", "imu_bias_deg=rear:3.0", "imu_bias_deg=front:-2.0"]


def test_a_bare_condition_goes_on_top_of_the_robot_files_per_limb_values(capsys, tmp_path):
    """[plant] imu_bias_deg = [1, -2] and power_scale per coil, then --condition
    imu_bias_deg=15 / power_scale=0.5 (a bare value: every limb, every coil): the file's
    per-limb values still won, and the run had ±1–2° of bias and full power while its report
    listed imu_bias_deg=15.0 beside them. A bare value on the command line replaces them; a
    named one beside it still names its own."""
    path = tmp_path / "paper-r1.toml"
    path.write_text(R1.read_text() + "\n[plant]\nimu_bias_deg = [1.0, -2.0]\npower_scale = [1.0, 0.9]\n")
    robot = load_robot(path)
    c = plant_conditions(robot, ["imu_bias_deg=15", "power_scale=0.5"])
    assert [c.for_index("imu_bias_deg", i, ["left", "right"]) for i in range(2)] == [15.0, 15.0]
    assert [c.for_index("power_scale", j, ["sma-left", "sma-right"]) for j in range(2)] == [0.5, 0.5]
    for given in (["imu_bias_deg=right:3", "imu_bias_deg=15"], ["imu_bias_deg=15", "imu_bias_deg=right:3"]):
        c = plant_conditions(robot, given)
        assert [c.for_index("imu_bias_deg", i, ["left", "right"]) for i in range(2)] == [15.0, 3.0], given
    c = plant_conditions(robot, [])
    assert [c.for_index("imu_bias_deg", i, ["left", "right"]) for i in range(2)] == [1.0, -2.0]
    rc, out, _ = run(capsys, "sim", str(path), "--duration", "1", "--json", "--condition", "imu_bias_deg=15")
    effective = json.loads(out)["effective_conditions"]
    assert rc == 0 and "imu_bias_deg=15.0" in effective and not any(
        e.startswith("imu_bias_deg=left") or e.startswith("imu_bias_deg=right") for e in effective), effective
    assert plant_conditions(load_robot(R1), effective) == plant_conditions(robot, ["imu_bias_deg=15"])


def test_a_measured_entry_that_rounds_to_zero_prints_without_a_sign_it_does_not_have():
    from proleg.cli.sim_plant import _mm

    assert _mm(-0.001) == "+0.00" and _mm(0.001) == "+0.00" and _mm(0.0) == "+0.00"
    assert _mm(-0.02) == "-0.02" and _mm(12.3) == "+12.30"


def test_a_run_without_a_cycle_or_a_fault_says_why(capsys, tmp_path):
    """R1 holding each state 30 s (control.hold_ms) completes no cycle in 20 s and nothing goes
    wrong: the report says the holds are why; a run with a cycle has no such note."""
    slow = tmp_path / "slow.toml"
    slow.write_text((ROBOTS / "paper-r1.toml").read_text(encoding="utf-8").replace("hold_ms = 100", "hold_ms = 30000"),
                    encoding="utf-8")
    assert main(["sim", str(slow), "--duration", "20"]) == 0
    out = capsys.readouterr().out
    assert "cycles completed: 0" in out
    assert "NOTE: no cycle completed in 20 s, and no fault: each step holds its state control.hold_ms = 30000 ms" in out
    assert main(["sim", str(ROBOTS / "paper-r1.toml"), "--duration", "20"]) == 0
    assert "NOTE: no cycle" not in capsys.readouterr().out


ONE_LIMB = """[robot]
name = "one"

[[limb]]
name = "only"
psi_star_deg = [20.0]
actuator = "sma"

[[actuator]]
name = "sma"

[transitions]
matrix = [[0, 1], [-0.5, 0]]
"""


@pytest.mark.parametrize("argv", [["check", "--rows", "1"], ["sim", "--measure-matrix"], ["sim", "--duration", "2"]])
def test_a_one_limb_robot_on_the_physical_plant_is_told_what_can_simulate_it(tmp_path, capsys, argv):
    """It was "physical plant: one has one limb; … (--plant table simulates it from its
    matrix)": no robot file named, and `proleg check` (and --measure-matrix) take no --plant
    table. The line names the file and the command that simulates such a robot."""
    robot = tmp_path / "one.toml"
    robot.write_text(ONE_LIMB)
    code, out, err = run(capsys, argv[0], str(robot), *argv[1:])
    assert code == 2 and out == ""
    assert err.startswith(f"proleg: error: {robot}: the physical plant needs two limbs at least") and \
        "proleg sim --plant table" in err and len(err.strip().splitlines()) == 1


def test_measure_matrix_that_makes_no_transition_fails_and_writes_no_file(capsys, tmp_path):
    """At ambient_c=100 R1's coils are past Af before any heat (Ms 56 °C: they never come back),
    so the idealised drive makes none of its 12 transitions. --measure-matrix printed a table of
    '?', exit 0, and --out wrote the robot file as measured with every entry kept (an unmeasured
    file's zeros became a measured table of zeros). Now: exit 1, one error line, no file; the
    table is still printed (it says what was not made)."""
    out_file = tmp_path / "hot.toml"
    rc, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--condition", "ambient_c=100",
                       "--out", str(out_file), "--json")
    m = json.loads(out)
    assert rc == 1 and len(m["not_made"]) == 12 and not any(map(any, m["samples"]))
    assert "made none of the 12 allowed transitions" in err and f"--out {out_file} not written" in err, err
    assert not out_file.exists()
    rc, out, err = run(capsys, "sim", str(R1), "--measure-matrix", "--condition", "ambient_c=35", "--out", str(out_file))
    assert rc == 0 and out_file.exists() and "error" not in err, err
