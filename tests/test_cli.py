"""The ``proleg`` command line: output formats, exit codes, one-line errors."""

from __future__ import annotations

import re
import json
import subprocess
import sys
from pathlib import Path

import pytest
from build_checks import cli as run

from proleg.cli import main

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def test_gait_json_is_one_object_with_the_documented_shape(capsys):
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--max-transitions", "3", "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["robot"] == "paper-r1"
    assert doc["states"] == ["00", "01", "10", "11"]
    assert [r["direction"] for r in doc["results"]] == ["+x", "-x"]
    for r in doc["results"]:
        assert r["objective"] == "total" and r["max_transitions"] == 3
        for g in r["gaits"]:
            assert set(g) == {"states", "reward", "transitions", "rate", "opposing_steps", "repeats", "problems",
                              "entry_path"}
            assert g["states"][0] == g["states"][-1]
            assert g["transitions"] == len(g["states"]) - 1
            assert g["reward"] * g["repeats"] == pytest.approx(r["value"])
            assert g["problems"] == [] and g["entry_path"] == {"states": ["00"], "gait_step": 0}
            assert g["rate"] == pytest.approx(g["reward"] / g["transitions"])


def test_gait_on_a_larger_robot_takes_the_bound_the_firmware_build_takes(capsys):
    """caterpillar-4 (36 states): `proleg gait` refused the example robot for want of a
    --max-transitions; the build bounds it by one whole-body wave (firmware.gaits)."""
    from proleg.firmware.build import firmware_gaits
    from proleg.robot import load_robot

    path = ROBOTS / "caterpillar-4.toml"
    code, out, err = run(capsys, "gait", str(path), "--direction", "+x", "--json")
    assert code == 0, err
    (result,) = json.loads(out)["results"]
    carried = firmware_gaits(load_robot(path))
    assert result["max_transitions"] == carried.selection.max_transitions == 12
    assert {tuple(g["states"]) for g in result["gaits"]} >= {
        tuple(load_robot(path).transitions.label(s) for s in g.states) for g in carried["+x"]}


def test_gaits_with_a_step_that_raises_one_limb_and_lowers_another_are_flagged(capsys):
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r3.toml"), "--direction", "-x", "--json")
    assert code == 0
    gaits = {"-".join(g["states"]): g["opposing_steps"] for g in json.loads(out)["results"][0]["gaits"]}
    assert gaits == {"00-01-10-11-00": [["01", "10"]], "00-01-11-00": [], "00-01-11-10-00": []}
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r3.toml"), "--direction", "-x")
    assert "note: 00 → 01 → 10 → 11 → 00 raises one limb while lowering another in 01 → 10" in out
    assert out.count("note:") == 1


FIXTURES = Path(__file__).resolve().parent / "fixtures"


def _gait_lines(out: str) -> list[str]:
    return [line for line in out.splitlines() if line.startswith("    ") and "  J=" in line]


def test_gait_text_shows_the_first_ties_and_counts_the_rest(capsys):
    """The sweep's 5: a 256-state robot printed 10,000 ties per direction (20,000 lines with
    their entry lines, 5 MB). The text now shows the first 10 of each answer and a count."""
    code, out, _ = run(capsys, "-q", "gait", str(FIXTURES / "eight-shared.toml"))
    assert code == 0 and "10000 optimal gaits (listing stopped after 10000: more ties exist)" in out
    assert len(_gait_lines(out)) == 20 and len(out.splitlines()) < 300
    assert out.count("    … and 9,990 more ties: --ties N or --all-ties lists them, --json lists every one") == 2
    code, out, _ = run(capsys, "gait", "caterpillar-4", "--direction", "+x")
    assert len(_gait_lines(out)) == 10 and out.rstrip().endswith("… and 100 more ties: --ties N or --all-ties "
                                                                   "lists them, --json lists every one")
    code, out, _ = run(capsys, "gait", "caterpillar-4", "--direction", "+x", "--ties", "3")
    assert len(_gait_lines(out)) == 3 and "… and 107 more ties" in out
    code, out, _ = run(capsys, "gait", "caterpillar-4", "--direction", "+x", "--all-ties")
    assert len(_gait_lines(out)) == 110 and "more tie" not in out
    code, out, _ = run(capsys, "gait", "paper-r3", "--direction", "-x")  # 3 ties: all shown, no count
    assert len(_gait_lines(out)) == 3 and "more tie" not in out


def test_gait_json_lists_every_tie_and_says_how_many_unless_ties_caps_it(capsys):
    code, out, _ = run(capsys, "gait", "caterpillar-4", "--direction", "+x", "--json")
    (r,) = json.loads(out)["results"]
    assert code == 0 and r["ties"] == len(r["gaits"]) == 110 and "truncated" not in r
    code, out, _ = run(capsys, "gait", "caterpillar-4", "--direction", "+x", "--json", "--ties", "3")
    (capped,) = json.loads(out)["results"]
    assert capped["ties"] == 110 and capped["gaits"] == r["gaits"][:3]  # the first 3 in rank order


@pytest.mark.parametrize("argv, words", [
    (["--evaluate", "00,10,11,01,00", "--ties", "3"], "--ties: not with --evaluate"),
    (["--evaluate", "00,10,11,01,00", "--all-ties"], "--all-ties: not with --evaluate"),
    (["--ties", "0"], "argument --ties: expected at least 1, got 0"),
    (["--ties", "3", "--all-ties"], "not allowed with argument"),
])
def test_gait_ties_options_are_refused_where_they_mean_nothing(capsys, argv, words):
    try:
        code = main(["gait", "paper-r1", *argv])
    except SystemExit as e:
        code = e.code
    _, err = capsys.readouterr()
    assert code == 2 and words in err and "Traceback" not in err


def test_the_firmware_carries_one_way_gaits_first(capsys):
    from proleg.firmware.build import firmware_gaits
    from proleg.robot import load_robot

    gaits = firmware_gaits(load_robot(ROBOTS / "paper-r3.toml"))["-x"]
    assert [g.states for g in gaits] == [(0, 1, 3, 0), (0, 1, 3, 2, 0), (0, 1, 2, 3, 0)]


def test_direction_minus_x_is_accepted_as_a_separate_argument(capsys):
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--direction", "-x", "--json")
    assert code == 0
    assert [r["direction"] for r in json.loads(out)["results"]] == ["-x"]


def test_no_gait_in_a_direction_is_null_with_no_gaits(capsys):
    # R1 with its left actuator only: every closed walk has J >= 0 (00->10->00 and
    # 10->11->10 each sum to 0 or +1), so nothing moves it backwards.
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1-one-actuator.toml"), "--direction=-x", "--json")
    assert code == 0
    (result,) = json.loads(out)["results"]
    assert result["value"] is None and result["gaits"] == []
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1-one-actuator.toml"), "--direction=-x")
    assert "no gait moves the robot in -x" in out


def test_table_output_lists_each_gait_with_its_reward(capsys):
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1-one-actuator.toml"), "--direction=+x",
                       "--max-transitions", "4")
    assert code == 0
    # issue 14: 10 → 11 → 10 run twice (J = 2 in 4 transitions) beats 00 → 10 → 11 → 10 → 00 (J = 1)
    assert "best +2" in out and "10 → 11 → 10    J=+1" in out
    assert "00 → 10 → 11 → 10 → 00" not in out


def test_evaluate_scores_a_valid_sequence(capsys):
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--evaluate", "00,10,11,01,00", "--json")
    assert code == 0
    ev = json.loads(out)["evaluation"]
    # T[00][10] + T[10][11] + T[11][01] + T[01][00] = 1 + 1 + 0 + 1
    assert ev["valid"] is True and ev["reward"] == 3 and ev["transitions"] == 4 and ev["rate"] == 0.75


def test_evaluate_shows_the_duration_as_the_listing_does(capsys, tmp_path):
    """With durations in the file the listing shows each gait's T; --evaluate's line did not
    (its --json had duration_s): the same gait read J=-12.5 T=5.4s in one and J=-12.5 in the other."""
    path = tmp_path / "r1.toml"
    path.write_text((ROBOTS / "paper-r1.toml").read_text().replace("[transitions]", "[transitions]\ndefault_duration_s = 0.9", 1))
    code, out, _ = run(capsys, "gait", str(path), "--evaluate", "00,10,11,01,00")
    assert code == 0 and "J=+3  T=3.6s  N=4" in out, out
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--evaluate", "00,10,11,01,00")
    assert code == 0 and "T=" not in out, out  # no durations: nothing assumed


def test_evaluate_names_the_forbidden_transition(capsys):
    code, out, err = run(capsys, "gait", str(ROBOTS / "paper-r1-one-actuator.toml"), "--evaluate", "00,01,00")
    assert code == 2 and out == "" and err.count("\n") == 1  # a bad gait: exit 2, one line on stderr
    assert err.startswith("proleg: error: --evaluate: 00 → 01 → 00 is not a valid gait") and "forbidden" in err
    code, out, err = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--evaluate", "00,10,10,01", "--json")
    assert code == 2 and out == "" and err == (
        "proleg: error: --evaluate: 10 follows itself (entry 3 of '00,10,10,01'); each step of a gait changes "
        "the state\n")  # the README's one line


def _one_coil_paper_r1(tmp_path) -> Path:
    """paper-r1 with both limbs on one coil: 00 -> 01 raises the far limb alone, which the coil
    cannot hold (the near limb rises with it)."""
    text = (ROBOTS / "paper-r1.toml").read_text().replace('actuator = "sma-right"', 'actuator = "sma-left"')
    shared = tmp_path / "shared.toml"
    shared.write_text(text.replace('[[actuator]]\nname = "sma-right"\nchannel = 1\n', ""))
    return shared


def test_evaluate_of_a_gait_the_hardware_cannot_make_exits_2_in_text_and_json(capsys, tmp_path):
    """The sweep's 2.1: --evaluate listed a shared-actuator error in "problems" and exited 0;
    a gait the hardware cannot run is a bad gait (README: exit 2), like one the matrix forbids."""
    shared = _one_coil_paper_r1(tmp_path)
    code, out, err = run(capsys, "gait", str(shared), "--evaluate", "00,01,00", "--json")
    ev = json.loads(out)["evaluation"]
    assert code == 2 and ev["valid"] is True and ev["feasible"] is False
    assert [p["kind"] for p in ev["problems"] if p["severity"] == "error"] == ["shared-actuator"]
    errors = [line for line in err.splitlines() if line.startswith("proleg: error:")]
    assert len(errors) == 1 and "00 → 01 → 00 cannot run on paper-r1's hardware" in errors[0]
    assert "share actuator 'sma-left'" in errors[0]
    code, out, err = run(capsys, "gait", str(shared), "--evaluate", "00,01,00")
    assert code == 2 and "error: gait 00 01 00: step 1 (00 -> 01) raises 'right' but not 'left'" in out
    assert [line for line in err.splitlines() if line.startswith("proleg: error:")]
    # a gait it can make still exits 0, and says it is feasible
    code, out, _ = run(capsys, "gait", str(shared), "--evaluate", "00,10,11,00", "--json")
    assert code == 0 and json.loads(out)["evaluation"]["feasible"] is True
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r3.toml"), "--evaluate", "00,01,10,11,00")
    assert code == 0 and "note: raises one limb while lowering another in 01 → 10" in out  # a warning only


def test_evaluate_rejects_an_unknown_label_in_one_line(capsys):
    code, _, err = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--evaluate", "00,12,00")
    assert code == 2
    assert err.startswith("proleg: error: --evaluate:") and err.count("\n") == 1


def test_bad_robot_file_is_one_line_and_exit_2(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((ROBOTS / "paper-r1.toml").read_text().replace("[20.0]", "[95.0]", 1))
    code, out, err = run(capsys, "gait", str(bad))
    assert code == 2 and out == ""
    assert err.count("\n") == 1
    assert str(bad) in err and "limb 'left': psi_star_deg" in err


def test_speed_without_durations_is_a_clear_error(capsys):
    code, _, err = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--objective", "speed")
    assert code == 2 and "duration" in err


def test_console_script_is_installed():
    exe = Path(sys.executable).with_name("proleg")
    proc = subprocess.run([str(exe), "gait", str(ROBOTS / "paper-r2.toml"), "--json"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["robot"] == "paper-r2"


SIM_JSON_FIELDS = {
    "robot", "board", "direction", "gait", "duration_s", "cycles", "cycle_displacements_mm", "mean_cycle_mm",
    "displacement_mm", "speed_mm_s", "states_reached", "true_transitions", "unexpected_transitions", "faults",
    "telemetry_frames", "telemetry_lost", "telemetry_silent_s", "link_errors", "errors", "start_time_s",
    "matrix_check",  # README: the run against what the matrix promises
    "plant", "conditions", "effective_conditions",  # README: as --measure-matrix --json names them
    "coil_peak_c",  # README: each coil's hottest in the run
}


def test_sim_walks_and_exits_0_with_the_documented_json(capsys):
    code, out, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "20", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert set(doc) == SIM_JSON_FIELDS
    assert doc["cycles"] >= 2 and doc["displacement_mm"] > 0 and doc["errors"] == [] and doc["faults"] == []


def test_sim_reports_a_lost_start_as_an_error_and_exits_1(capsys):
    code, out, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "5", "--json",
                         "--inject", "link-drop:1.0")
    assert code == 1
    doc = json.loads(out)
    assert doc["cycles"] == 0 and doc["errors"][0].startswith("START failed: no reply to START")
    assert "proleg: error: START failed" in err


@pytest.mark.parametrize("spec, text", [
    ("link-drop:2", "link-drop:P (a probability): expected a number in 0..1, got '2'"),
    ("link-corrupt:1.5+1", "link-corrupt:P (a probability): expected a number in 0..1, got '1.5'"),
    ("link-drop:nan", "expected a number in 0..1, got 'nan'"),
    ("drift:all@-1", "drift@RATE (per second of on-time): expected a number ≥ 0, got '-1'"),
    ("drift@abc", "drift@RATE (per second of on-time): expected a number, got 'abc'"),
    ("dead-actuator:sma-right+1e400", "the time after '+' must be a finite number ≥ 0 s, got '1e400'"),
    ("dead-actuator:sma-right+100", "100 s is after the run ends (--duration 2 s), so it would never be injected"),
    # a time just past the end was rounded to it: "2 s is after the run ends (--duration 2 s)"
    ("dead-actuator:sma-right+2.0000001", "2.0000001 s is after the run ends (--duration 2 s)"),
])
def test_an_injection_out_of_its_range_is_refused_before_the_run(capsys, spec, text):
    """A drop probability of 2 used to run and end in 'no reply to START', exit 1."""
    code, _, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "2", "--inject", spec)
    assert code == 2 and text in err and "Traceback" not in err


@pytest.mark.parametrize("spec, coil", [("dead-actuator:leg+2", 1), ("dead-actuator:leg+2+0", 1),
                                        ("dead-actuator:leg", 0)])
def test_a_limb_name_ending_in_plus_a_number_is_a_name_in_inject(capsys, tmp_path, spec, coil):
    """With limbs "leg" and "leg+2", `--inject dead-actuator:leg+2` killed leg's coil 2 s in:
    the '+2' was read as a time although the whole spec names a limb."""
    text = (ROBOTS / "paper-r1.toml").read_text()
    robot = tmp_path / "plus.toml"
    robot.write_text(text.replace('name = "left"', 'name = "leg"').replace('name = "right"', 'name = "leg+2"'))
    code, out, err = run(capsys, "sim", str(robot), "--duration", "5", "--json", "--inject", spec)
    doc = json.loads(out)
    assert code == 1 and [(f["code"], f["detail"]) for f in doc["faults"]] == [("SMA_ON_LIMIT", coil)], err


@pytest.mark.parametrize("limb", ["leg+2", "front+pad"])
def test_a_limb_named_with_a_plus_is_injected_at_once_as_any_other_limb(capsys, tmp_path, limb):
    """A spec naming a limb whole with no +T is 'that limb at once' (README), injected before the
    boot as imu-silent:left is (START refused); it went to START instead, a different run."""
    text = (ROBOTS / "paper-r1.toml").read_text()
    robot = tmp_path / "plus.toml"
    robot.write_text(text.replace('name = "right"', f'name = "{limb}"'))
    runs = []
    for path, spec in ((robot, f"imu-silent:{limb}"), (ROBOTS / "paper-r1.toml", "imu-silent:right")):
        code, out, err = run(capsys, "sim", str(path), "--duration", "2", "--json", "--inject", spec)
        doc = json.loads(out)
        runs.append((code, doc["start_time_s"], [(f["code"], f["detail"]) for f in doc["faults"]]))
    assert runs[0] == runs[1] == (1, None, [("IMU_NO_ACK", 1)]), runs


def test_a_fault_latched_before_start_is_named_with_the_refusal(capsys):
    """An IMU silent from boot latches IMU_NO_ACK before START; START is then refused with
    NOT_ALLOWED, and the report used to show only that, with "faults": []."""
    code, out, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "3", "--json",
                         "--inject", "imu-silent:left")
    doc = json.loads(out)
    assert code == 1 and [f["code"] for f in doc["faults"]] == ["IMU_NO_ACK"]
    assert "NOT_ALLOWED (a fault is latched" in doc["errors"][0]


@pytest.mark.parametrize("argv, text", [
    (("--measure-matrix", "--record", "m.csv"), "--measure-matrix: not with --record"),
    (("--measure-matrix", "--inject", "imu-silent:left"), "--measure-matrix: not with --inject"),
    (("--measure-matrix", "--direction", "-x"), "--measure-matrix: not with --direction"),
    (("--measure-climb", "--gait", "5"), "--measure-climb: not with --gait"),
    (("--measure-climb", "--duration", "5"), "--measure-climb: not with --duration"),
    (("--pty", "--json"), "--pty: not with --json"),
    (("--pty", "--record", "/nonexistent/x.csv"), "--pty: not with --record"),
    (("--speed", "3"), "--speed: only with --pty"),
    (("--all-gaits",), "only with --measure-climb"),
])
def test_an_option_the_sim_mode_would_ignore_is_refused(capsys, tmp_path, argv, text):
    """Each used to be ignored with exit 0 (--measure-matrix --record wrote no file)."""
    code, _, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), *argv)
    assert code == 2 and text in err and "Traceback" not in err


@pytest.mark.parametrize("given, shown", [("1e12", "1e+12"), ("3600.0001", "3600.0001")])
def test_sim_refuses_a_duration_it_would_take_days_to_simulate(capsys, given, shown):
    """The value as given: 3600.0001 was refused as "--duration 3600: expected at most 3600"."""
    code, _, err = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", given)
    assert code == 2 and f"--duration {shown}: expected at most 3600 simulated seconds" in err and err.count("\n") == 1


def test_run_sim_refuses_a_duration_it_would_take_days_to_simulate_flat_out(capsys):
    """run --sim runs the simulated board as fast as it can, as sim does: --duration 1e9 ran
    for ever where sim refuses it. Paced by --speed, it lasts what was asked, in real time."""
    code, _, err = run(capsys, "run", "--sim", str(ROBOTS / "paper-r1.toml"), "--duration", "1e9")
    assert code == 2 and "--duration 1000000000: with --sim, expected at most 3600 simulated seconds" in err
    assert err.count("\n") == 1


@pytest.mark.parametrize("argv", [("gait", "paper-r1"), ("sim", "paper-r1", "--duration", "1"),
                                  ("build", "paper-r1", "--board", "host-sim")])
def test_objective_speed_without_durations_names_the_file_and_the_key(capsys, tmp_path, argv):
    code, _, err = run(capsys, *argv, "--objective", "speed", *(("-o", str(tmp_path / "b")) if argv[0] == "build" else ()))
    assert code == 2 and err.count("\n") == 1
    assert f"--objective speed: {ROBOTS / 'paper-r1.toml'} gives no transition durations" in err
    assert "transitions.durations_s" in err


def test_sim_exits_1_when_the_run_faulted(capsys):
    code, out, _ = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "15",
                       "--inject", "dead-actuator:sma-right+2")
    assert code == 1
    assert "FAULT at" in out


def test_sim_says_when_start_came_so_fault_times_read_from_it(capsys):
    """--calibrated spends ~2.7 s calibrating and resting before START; fault times are on the
    board's clock from boot, and the report says where START was on it."""
    code, out, _ = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "12", "--calibrated", "--json",
                       "--inject", "dead-actuator:sma-left")
    doc = json.loads(out)
    assert code == 1 and doc["faults"]
    assert 2.5 < doc["start_time_s"] < 3.5
    assert all(f["time_s"] > doc["start_time_s"] for f in doc["faults"])
    code, out, _ = run(capsys, "sim", str(ROBOTS / "paper-r1.toml"), "--duration", "12", "--calibrated",
                       "--inject", "dead-actuator:sma-left")
    first = doc["faults"][0]["time_s"]
    assert f"FAULT at {first:.3f} s ({first - doc['start_time_s']:.3f} s after START)" in out


def test_gait_json_says_what_the_text_says_of_repeats_and_problems(capsys, tmp_path):
    """A gait that repeats within the bound (value = reward × repeats) and the hardware's
    problems were only in the text: JSON gave value 2 and a gait of reward 1 with no word why,
    and no 'shared-actuator' error for a gait one coil cannot make."""
    code, out, _ = run(capsys, "gait", str(ROBOTS / "paper-r1-one-actuator.toml"), "--direction", "+x",
                       "--max-transitions", "4", "--json")
    g = json.loads(out)["results"][0]["gaits"][0]
    assert code == 0 and g["repeats"] == 2 and g["reward"] * 2 == json.loads(out)["results"][0]["value"]
    shared = _one_coil_paper_r1(tmp_path)
    code, out, _ = run(capsys, "gait", str(shared), "--direction", "+x", "--max-transitions", "3", "--json")
    kinds = {p["kind"] for g in json.loads(out)["results"][0]["gaits"] for p in g["problems"]}
    assert code == 0 and "shared-actuator" in kinds, out


def test_a_one_limb_robot_is_one_limb_in_the_gait_header(capsys, tmp_path):
    """A single four-level pad: the header said "1 limbs"."""
    path = tmp_path / "solo.toml"
    path.write_text('[robot]\nname = "solo"\n[[limb]]\nname = "pad"\nlevels = 4\npsi_star_deg = [8.0, 16.0, 24.0]\n'
                    'actuator = "a"\n[[actuator]]\nname = "a"\n[transitions]\nmatrix = [\n'
                    '  [0, 1, "x", "x"],\n  [-1, 0, 1, "x"],\n  ["x", -1, 0, 1],\n  ["x", "x", -1, 0],\n]\n')
    code, out, _ = run(capsys, "gait", str(path))
    assert code == 0 and out.startswith("solo: 1 limb, 4 states (0 1 2 3), 6 allowed transitions"), out


def test_build_into_a_folder_that_does_not_exist_is_a_usage_error_and_creates_nothing(capsys, tmp_path):
    """-o A/B/out with A missing built it, creating A and B (a typo at the root made /nonexist);
    every other command's output in a missing folder is exit 2."""
    out = tmp_path / "missing" / "deeper" / "out"
    code, _, err = run(capsys, "build", str(ROBOTS / "paper-r1.toml"), "--board", "host-sim", "-o", str(out))
    assert code == 2 and f"directory {out.parent} does not exist" in err
    assert not (tmp_path / "missing").exists()


def test_build_folds_tens_of_gait_problems_after_the_first_few(capsys, tmp_path):
    """A robot with tens of tied gaits, each with problems: build printed every one (82 lines)."""
    from proleg.cli.main import BUILD_WARNINGS_SHOWN

    robot = Path(__file__).parent / "fixtures" / "shared-coil-strokes-3.toml"
    code, _, err = run(capsys, "build", str(robot), "--board", "host-sim", "-o", str(tmp_path / "b"))
    lines = [x for x in err.splitlines() if x.startswith("proleg: warning: gait ")]
    assert code == 0 and len(lines) == BUILD_WARNINGS_SHOWN
    more = re.search(r"… and (\d+) more like these \(-v shows them", err)
    assert more
    code, _, err = run(capsys, "build", str(robot), "--board", "host-sim", "-o", str(tmp_path / "b"), "-v")
    assert code == 0
    assert len([x for x in err.splitlines() if x.startswith("proleg: warning: gait ")]) == BUILD_WARNINGS_SHOWN + int(more[1])


@pytest.mark.parametrize("seq, words", [
    ("000 100 110 000", "'000 100 110 000' is not one state label: separate the states with commas"),
    ("000;100;000", "'000;100;000' is not one state label: separate the states with commas"),
    ("@0,@4,@0", "'@0' is not a state label: one digit per limb, 3 digits (e.g. 010)"),
])
def test_a_sequence_written_otherwise_is_told_how_to_write_it(capsys, seq, words):
    """'000 100 110' was "state label '000 100 110' has 11 digits, expected 3": it has 9 digits
    and two spaces, and the user needed to hear that states are separated by commas; '@0'
    "has 2 digits"."""
    code, out, err = run(capsys, "gait", str(ROBOTS / "inchworm-3.toml"), "--evaluate", seq)
    assert code == 2 and out == "" and err.count("\n") == 1 and words in err


def test_log_lines_go_to_the_stderr_of_the_moment_not_the_one_main_was_called_with(capsys):
    """main called again in one process with stderr replaced in between (the tests, a lab's
    script): its handler wrote later lines to the stream of the first call, closed by then."""
    import io
    import logging
    import sys

    main(["robots"])
    capsys.readouterr()
    replaced, old = io.StringIO(), sys.stderr
    sys.stderr = replaced
    try:
        logging.getLogger("proleg").warning("a later line")
    finally:
        sys.stderr = old
    assert "proleg: a later line" in replaced.getvalue()


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
@pytest.mark.parametrize("what, argv, says", [
    ("board.toml", ("build", "paper-r1", "--board", "{p}", "-o", "{tmp}/fw"), "{p}: cannot read the board file: "),
    ("run.csv", ("plot", "{p}", "-o", "{tmp}/out.png"), "cannot read record file {p}: "),
    ("run.jsonl", ("plot", "{p}", "-o", "{tmp}/out.png"), "cannot read record file {p}: "),
    ("track.csv", ("learn", "paper-r1", "--log", "{tmp}/t.jsonl", "--source", "tracker", "--track", "{p}", "--report"),
     "learn: {p}: cannot read: "),
    ("t.csv", ("gait", "{tmp}/csv-robot.toml"), "transitions.file: cannot open /dev/zero: "),  # the link followed
])
def test_an_input_that_is_a_device_is_refused_not_read_for_ever(tmp_path, what, argv, says):
    """A board file, transition CSV, recording or track that is /dev/zero (here through a link,
    as a slip of `ln -s` makes one) was read to an end that never comes: the memory filled until
    the kernel killed the process. Run in a child with its memory capped, so that a regression
    fails with a MemoryError traceback, not by taking the machine's memory."""
    import resource

    p = tmp_path / what
    p.symlink_to("/dev/zero")
    (tmp_path / "t.jsonl").write_text('{"trial_log": 1, "robot": "paper-r1", "levels": [2, 2]}\n')
    robot = (ROBOTS / "paper-r1.toml").read_text(encoding="utf-8")
    (tmp_path / "csv-robot.toml").write_text(robot[:robot.index("[transitions]")] + f'[transitions]\nfile = "{p}"\n',
                                             encoding="utf-8")
    args = [a.format(p=p, tmp=tmp_path) for a in argv]

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))

    import os

    import proleg

    env = {**os.environ, "PYTHONPATH": str(Path(proleg.__file__).resolve().parents[1])}  # this proleg
    proc = subprocess.run([sys.executable, "-m", "proleg", *args], capture_output=True, text=True, timeout=120,
                          preexec_fn=cap, cwd=tmp_path, env=env)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.endswith(f"{says.format(p=p)}not a regular file (a device, pipe or socket)\n"), proc.stderr
    assert proc.stderr.startswith("proleg: error: ") and proc.stderr.count("\n") == 1, proc.stderr


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("args", [["--help"], ["--version"], ["gait", "--help"]])
def test_a_help_that_cannot_be_written_fails(args):
    """argparse swallows the OSError of a help it cannot write: ``proleg --help > /dev/full``
    exited 0 with nothing written and nothing said."""
    import os

    import proleg

    env = {**os.environ, "PYTHONPATH": str(Path(proleg.__file__).resolve().parents[1])}  # this proleg
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "proleg", *args], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=60, env=env)
    assert proc.returncode == 1 and proc.stderr == "proleg: error: cannot write: No space left on device\n", proc.stderr


def test_a_help_read_by_head_is_not_an_error():
    import os

    import proleg

    env = {**os.environ, "PYTHONPATH": str(Path(proleg.__file__).resolve().parents[1])}
    proc = subprocess.run(f"'{sys.executable}' -m proleg --help | head -c 10", shell=True, capture_output=True,
                          text=True, timeout=60, env=env)
    assert proc.stdout == "usage: pro" and proc.stderr == "", proc.stderr
