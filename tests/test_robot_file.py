"""Robot files: the paper's robots load as written; every malformed file is rejected with
one line naming the file, the field and what was expected."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from build_checks import R1_MATRIX, TWO_LIMBS

from proleg.errors import RobotFileError
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"

R1 = TWO_LIMBS + f"[transitions]\n{R1_MATRIX}\n"


def write(tmp_path: Path, text: str, name: str = "robot.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def rejects(tmp_path: Path, text: str, *fragments: str) -> str:
    path = write(tmp_path, text)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    msg = str(info.value)
    assert "\n" not in msg, msg
    assert str(path) in msg, msg
    for f in fragments:
        assert f in msg, f"{f!r} not in {msg!r}"
    return msg


def test_paper_matrices_load_row_from_column_to():
    r1 = load_robot(ROBOTS / "paper-r1.toml")
    reward, allowed = r1.transitions.dense()
    assert r1.transitions.labels() == ["00", "01", "10", "11"]
    expected = np.array([[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]])
    assert (reward == expected).all()
    assert allowed.sum() == 12 and not allowed.diagonal().any()
    # T[00][10] is the paper's T_13: from dec2bin(0) to dec2bin(2)
    assert reward[r1.transitions.index("00"), r1.transitions.index("10")] == 1


def test_one_actuator_robot_forbids_what_the_paper_strikes_out():
    r = load_robot(ROBOTS / "paper-r1-one-actuator.toml")
    t = r.transitions
    allowed = {(t.label(a), t.label(b)) for a, b in zip(t.src, t.dst)}
    assert allowed == {("00", "10"), ("10", "00"), ("10", "11"), ("11", "10")}
    assert {limb.actuator for limb in r.limbs} == {"sma-left"}


@pytest.mark.parametrize("name", ["paper-r1", "paper-r2", "paper-r3", "paper-r1-one-actuator"])
def test_every_shipped_robot_loads(name):
    r = load_robot(ROBOTS / f"{name}.toml")
    assert r.levels == (2, 2)
    assert r.safety.max_duty >= r.control.drive_duty


def test_wrong_matrix_size_names_expected_row_count(tmp_path):
    rejects(tmp_path, R1.replace(", [0, 0, 0, 0]]", "]"), "transitions.matrix", "expected 4 rows", "got 3")


def test_short_row_names_the_row(tmp_path):
    rejects(tmp_path, R1.replace("[1, 0, 0, -1]", "[1, 0, 0]"), "row 2", "expected 4 entries")


def test_non_numeric_entry_names_row_and_column(tmp_path):
    rejects(tmp_path, R1.replace("[1, 0, 0, -1]", '[1, "up", 0, -1]'), "transitions.matrix[2][2]", "'up'")


@pytest.mark.parametrize("old, new, shown", [
    ("[1, 0, 0, -1]", "[1, true, 0, -1]", "got true"),                 # a matrix cell
    ("psi_star_deg = [20.0]", "psi_star_deg = [false]", "got [false]"),  # a field's list
    ("psi_star_deg = [20.0]", "psi_star_deg = {left = 3}", "got {left = 3}"),
])
def test_a_wrong_value_is_shown_as_it_was_written_in_toml(tmp_path, old, new, shown):
    """Not Python's True, [False] or {'left': 3}."""
    msg = rejects(tmp_path, R1.replace(old, new, 1), shown)
    assert "True" not in msg and "False" not in msg and "{'left'" not in msg


def test_unknown_key_is_rejected_with_the_known_ones(tmp_path):
    msg = rejects(tmp_path, R1.replace('name = "left"', 'name = "left"\npsi_star = 3'), "limb 'left': unknown key", "'psi_star'")
    assert "psi_star_deg" in msg


def test_unknown_top_level_table(tmp_path):
    rejects(tmp_path, R1 + "\n[motors]\nx = 1\n", "unknown key 'motors'")


def test_duplicate_limb(tmp_path):
    rejects(tmp_path, R1.replace('name = "right"', 'name = "left"'), "limb 'left': name", "duplicate limb")


@pytest.mark.parametrize("angle", ["95.0", "-90.0", "90"])
def test_psi_star_out_of_range(tmp_path, angle):
    rejects(tmp_path, R1.replace("psi_star_deg = [20.0]", f"psi_star_deg = [{angle}]", 1), "limb 'left': psi_star_deg",
            "between -90 and 90")


@pytest.mark.parametrize("angle", ["89.5", "-89.5"])
def test_a_band_around_psi_star_past_90_degrees_is_refused_when_the_file_is_read(tmp_path, angle):
    """ψ* 89.5° with the default 2° band reaches 90.5°: the file loaded and gait answered, and
    only the build refused it, naming neither the file nor the key."""
    rejects(tmp_path, R1.replace("psi_star_deg = [20.0]", f"psi_star_deg = [{angle}]", 1),
            "limb 'left': psi_star_deg", "hysteresis_deg/2 (2/2) lie strictly inside (-90, 90)")


@pytest.mark.parametrize("value, expected", [
    ("nan", "expected a finite number in [0.0, 20.0], got nan"),  # it said "expected a number, got nan"
    ("inf", "expected a finite number in [0.0, 20.0], got inf"),
    ('"two"', "expected a number, got 'two'"),
    ("25", "expected a number in [0.0, 20.0], got 25"),
])
def test_a_hysteresis_that_is_not_a_finite_number_says_so(tmp_path, value, expected):
    text = R1.replace('name = "left"', f'name = "left"\nhysteresis_deg = {value}', 1)
    msg = rejects(tmp_path, text)
    assert msg.endswith(f": limb 'left': hysteresis_deg: {expected}"), msg


def test_psi_star_count_must_match_levels(tmp_path):
    rejects(tmp_path, R1.replace('name = "left"', 'name = "left"\nlevels = 3', 1), "limb 'left': psi_star_deg",
            "2 critical angle")


def test_two_angles_without_levels_say_that_levels_defaults_to_two(tmp_path):
    """A three-level limb written without ``levels`` (its two angles given): the error said
    "expected a list of 1 critical angle(s) in degrees (levels - 1)" and nothing of levels,
    which the file does not mention."""
    msg = rejects(tmp_path, R1.replace("psi_star_deg = [20.0]", "psi_star_deg = [12.0, 24.0]", 1),
                  "limb 'left': psi_star_deg")
    assert msg.endswith("(levels - 1, and levels is 2 when not given), got [12.0, 24.0]: "
                        "for 2 angles say levels = 3"), msg


def test_forbidden_mark_on_a_rewarded_transition_says_what_forbidden_is_for_and_the_fix(tmp_path):
    """It said "(expected 'x' there)", which means nothing for a CSV table, nor says why."""
    text = R1.replace("[transitions]", '[transitions]\nforbidden = ["01->11"]')
    msg = rejects(tmp_path, text, "transitions.forbidden[1]: 01->11 is marked forbidden, but transitions.matrix[2][4] "
                  "gives it a reward (-1): forbidden lists the transitions the robot cannot make, to check that the "
                  'table allows none of them; write "x" there, or drop the mark')
    assert "expected 'x'" not in msg
    (tmp_path / "t.csv").write_text("from,to,reward\n00,10,1\n10,11,2.5\n11,01,1\n01,00,1\n")
    head = R1.split("[transitions]")[0]
    msg = rejects(tmp_path, head + '[transitions]\nfile = "t.csv"\nforbidden = ["10->11"]\n',
                  "transitions.forbidden[1]: 10->11 is marked forbidden, but the table t.csv gives it a reward "
                  "(2.5): forbidden lists the transitions the robot cannot make", "; delete its row, or drop the mark")
    assert "'x'" not in msg and '"x"' not in msg


def test_the_transitions_keys_behave_as_robot_file_md_says(tmp_path):
    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot-file.md").read_text(encoding="utf-8")
    for key in ("forbidden", "states", "durations_s", "default_duration_s", "units"):
        assert re.search(rf"^\| `{key}` \| .+ \| .+ \|$", doc, re.M), key  # a row of the table explaining it
    t = "[transitions]\n"
    rejects(tmp_path, R1.replace(t, t + 'states = ["00", "10", "01", "11"]\n'),
            "transitions.states: expected the state order ['00', '01', '10', '11']")
    assert load_robot(write(tmp_path, R1.replace(t, t + 'states = ["00", "01", "10", "11"]\n')))
    rejects(tmp_path, R1.replace(t, t + "durations_s = 1.5\n"), "transitions.durations_s: expected 4 rows like the matrix")
    r = load_robot(write(tmp_path, R1.replace(t, t + "default_duration_s = 1.5\n")))
    assert list(r.transitions.duration) == [1.5] * len(r.transitions.src)
    marked = R1.replace("[1, 0, 0, -1]", '[1, 0, 0, "x"]').replace(t, t + 'forbidden = ["@1->@3"]\n')
    assert load_robot(write(tmp_path, marked)).transitions.lookup(1, 3) is None  # an index mark, agreeing


def test_a_state_label_with_a_bad_digit_names_the_limb(tmp_path, capsys):
    """'not a level of limb #2' where the limb has a name (docs/robot-file.md: messages use it)."""
    from proleg.cli import main

    text = R1.replace("[transitions]", '[transitions]\nforbidden = ["00->02"]')
    msg = rejects(tmp_path, text, "transitions.forbidden[1]", "digit 2 ('2') is not a level of limb 'right', 0..1")
    assert "limb #" not in msg
    assert main(["gait", str(write(tmp_path, R1, "ok.toml")), "--evaluate", "00,10,20"]) == 2
    assert "digit 1 ('2') is not a level of limb 'left', 0..1" in capsys.readouterr().err


def test_forbidden_mark_of_a_state_to_itself(tmp_path):
    text = R1.replace("[transitions]", '[transitions]\nforbidden = ["01->11", "00->00"]')
    rejects(tmp_path, text.replace("[1, 0, 0, -1]", '[1, 0, 0, "x"]'), "transitions.forbidden[2]",
            "00->00 is a state to itself, never a transition")


def test_forbidden_mark_agreeing_with_the_matrix_is_fine(tmp_path):
    text = R1.replace("[1, 0, 0, -1]", '[1, 0, 0, "x"]').replace("[transitions]", '[transitions]\nforbidden = ["01->11"]')
    r = load_robot(write(tmp_path, text))
    assert r.transitions.lookup(1, 3) is None


def test_actuator_that_no_limb_names(tmp_path):
    rejects(tmp_path, R1 + '\n[[actuator]]\nname = "c"\nchannel = 2\n', "actuator 'c' drives no limb")


def test_limb_naming_an_unknown_actuator(tmp_path):
    rejects(tmp_path, R1.replace('actuator = "b"', 'actuator = "z"'), "limb 'right': actuator", "'z'")


def test_an_unnamed_limb_is_counted_from_one(tmp_path):
    rejects(tmp_path, R1.replace('name = "right"\n', ""), "limb #2: name: expected a string (required)")


def test_hold_duty_above_drive_duty(tmp_path):
    text = R1 + "\n[control]\ndrive_duty = 0.5\nhold_duty = 0.6\n"
    rejects(tmp_path, text, "control.hold_duty", "at most control.drive_duty")


@pytest.mark.parametrize("extra", ["[control]\ndrive_duty = 0.3\nhold_duty = 0.25\n",
                                   "[safety]\nmax_mean_duty = 0.5\n[control]\ndrive_duty = 0.5\nhold_duty = 0.5\n",
                                   "[safety]\nmax_mean_duty = 0.5\nhold_max_duty = 0.45\n[control]\ndrive_duty = 0.45\n"])
def test_a_drive_duty_at_or_below_the_hold_ceiling_is_refused(tmp_path, extra):
    """At or below the hold ceiling heating is holding, never on-time (docs/safety.md): a robot
    file with drive_duty = hold_duty = 0.5 loaded, walked, and held a coil its threshold was
    moved past at 0.5 for 177 s above 120 °C with no fault (the on-time rules never applied)."""
    rejects(tmp_path, R1 + "\n" + extra, "control.drive_duty", "above the hold ceiling",
            "never as on-time")


def test_hold_duty_negative(tmp_path):
    text = R1 + "\n[control]\nhold_duty = -0.1\n"
    rejects(tmp_path, text, "control.hold_duty", "a number in [0.0, 1.0]")


@pytest.mark.parametrize("ms, fragment", [(50, "0 (off) or 100 .. 4000 ms"), (4001, "an integer in 0..4000, got 4001"),
                                           (-1, "an integer in 0..4000, got -1"), (0.5, "an integer")])
def test_boost_ms_is_off_or_between_a_dead_time_and_the_stall(tmp_path, ms, fragment):
    rejects(tmp_path, R1 + f"\n[control]\nboost_ms = {ms}\n", "control.boost_ms", fragment)


def test_boost_ms_is_on_by_default_off_at_0_and_left_out_where_the_drive_is_at_the_ceiling(tmp_path):
    from core_configs import SIM_BOARD
    from proleg.firmware.render import render_config
    from proleg.robot_reach import boost_ms_of
    from proleg.robot_settings import BOOST_DEFAULT_MS

    default = load_robot(write(tmp_path, R1, "default.toml"))
    off = load_robot(write(tmp_path, R1 + "\n[control]\nboost_ms = 0\n", "off.toml"))
    on = load_robot(write(tmp_path, R1 + "\n[control]\nboost_ms = 1200\n", "on.toml"))
    # R1's file: drive_duty 0.6 under max_duty 0.8; at the ceiling a boost has nothing to add
    ceiling = load_robot(write(tmp_path, R1 + "\n[control]\ndrive_duty = 0.8\nboost_ms = 700\n", "ceiling.toml"))
    assert (default.control.boost_ms, off.control.boost_ms, on.control.boost_ms) == (None, 0, 1200)
    assert [boost_ms_of(r) for r in (default, off, on, ceiling)] == [BOOST_DEFAULT_MS, 0, 1200, 0]
    gaits = {"+x": [], "-x": []}
    config = {name: render_config(r, gaits, SIM_BOARD)["robot_config.h"]
              for name, r in (("default", default), ("off", off), ("on", on), ("ceiling", ceiling))}
    assert f"#define CTL_BOOST_MS {BOOST_DEFAULT_MS}u" in config["default"]
    assert "#define CTL_BOOST_MS 1200u" in config["on"]
    assert "CTL_BOOST_MS" not in config["off"] and "CTL_BOOST_MS" not in config["ceiling"]


def test_the_thermal_budget_keys_are_robot_file_keys_that_reach_the_firmware(tmp_path):
    """docs/safety.md listed hold_max_duty, max_mean_duty, duty_window_ms and on_limit_latch as
    [safety] keys, and a robot file giving one was refused as an unknown key."""
    from core_configs import SIM_BOARD
    from proleg.firmware.render import render_config

    text = R1 + "\n[safety]\nhold_max_duty = 0.2\nmax_mean_duty = 0.4\nduty_window_ms = 5000\non_limit_latch = 5\n"
    robot = load_robot(write(tmp_path, text, "budget.toml"))
    s = robot.safety
    assert (s.hold_max_duty, s.max_mean_duty, s.duty_window_ms, s.on_limit_latch) == (0.2, 0.4, 5000, 5)
    config = render_config(robot, {"+x": [], "-x": []}, SIM_BOARD)["robot_config.h"]
    for line in ("#define CFG_HOLD_MAX_DUTY_PM 2000u", "#define CFG_MEAN_DUTY_PM 4000u",
                 "#define CFG_DUTY_WINDOW_MS 5000UL", "#define CFG_ON_LIMIT_LATCH 5u"):
        assert line in config
    default = load_robot(write(tmp_path, R1, "default.toml")).safety
    assert (default.hold_max_duty, default.max_mean_duty, default.duty_window_ms, default.on_limit_latch) == (
        None, 0.45, 10_000, 3)
    rejects(tmp_path, R1 + "\n[safety]\nhold_max_duty = 0.6\n",
            "safety.hold_max_duty: expected at most max_mean_duty and max_duty (0.45)", "got 0.6")
    rejects(tmp_path, R1 + "\n[safety]\nduty_window_ms = 4\n", "safety.duty_window_ms: expected an integer in 8..600000")
    rejects(tmp_path, R1 + "\n[safety]\non_limit_latch = 0\n", "safety.on_limit_latch: expected an integer in 1..247")


def test_the_coil_heat_ceiling_is_opt_in_and_off_leaves_the_firmware_config_without_it(tmp_path):
    """[safety] coil_heat_ceiling (docs/safety.md, "The coil's heat ceiling"): off by default, and
    off the rendered robot_config.h has no CFG_COIL_TAU_MS (core/sma.c compiles none of its code:
    every example robot's firmware is what it was before the key). On, the config is the same but
    for that one line, the coils' time constant. Anything but a boolean is refused by name."""
    from core_configs import SIM_BOARD
    from proleg.firmware.render import render_config

    gaits = {"+x": [], "-x": []}
    off = load_robot(write(tmp_path, R1, "off.toml"))
    said_off = load_robot(write(tmp_path, R1 + "\n[safety]\ncoil_heat_ceiling = false\n", "said-off.toml"))
    on = load_robot(write(tmp_path, R1 + "\n[safety]\ncoil_heat_ceiling = true\n", "on.toml"))
    assert (off.safety.coil_heat_ceiling, said_off.safety.coil_heat_ceiling, on.safety.coil_heat_ceiling) == (
        False, False, True)

    def config(robot) -> list[str]:  # but the lines that name the robot file and hash its text
        return [line for line in render_config(robot, gaits, SIM_BOARD)["robot_config.h"].splitlines()
                if "sha256" not in line and "CFG_BUILD_ID" not in line]

    off_h = config(off)
    assert not any("COIL_TAU" in line or "coil_heat" in line for line in off_h)
    assert config(said_off) == off_h
    on_h = config(on)
    added = [line for line in on_h if line not in off_h]
    assert len(added) == 1 and added[0].startswith("#define CFG_COIL_TAU_MS 1259UL"), added
    assert [line for line in on_h if line not in added] == off_h
    for bad, shown in (("1", "got 1"), ('"yes"', "got 'yes'"), ("0.5", "got 0.5")):
        rejects(tmp_path, R1 + f"\n[safety]\ncoil_heat_ceiling = {bad}\n",
                "safety.coil_heat_ceiling: expected true or false", shown)
    rejects(tmp_path, R1 + "\n[safety]\nheat_ceiling = true\n", "unknown key 'heat_ceiling'",
            "did you mean 'coil_heat_ceiling'?")


def test_a_mean_duty_below_the_default_hold_ceiling_lowers_it_and_a_hold_duty_above_it_is_refused(tmp_path):
    """max_mean_duty = 0.25 (in its range) loaded, then failed at build on the default hold
    ceiling max(0.3, hold_duty), a key the file did not contain, without its path. The default
    now stays within the window; a hold duty that cannot is refused at load, naming both keys."""
    from core_configs import SIM_BOARD
    from proleg.firmware.render import render_config

    robot = load_robot(write(tmp_path, R1 + "\n[safety]\nmax_mean_duty = 0.25\n", "mean.toml"))
    assert robot.safety.hold_ceiling(robot.control.hold_duty) == 0.25
    config = render_config(robot, {"+x": [], "-x": []}, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_HOLD_MAX_DUTY_PM 2500u" in config
    assert load_robot(write(tmp_path, R1, "default.toml")).safety.hold_ceiling(0.25) == 0.3
    rejects(tmp_path, R1 + "\n[safety]\nmax_mean_duty = 0.4\n[control]\nhold_duty = 0.45\n",
            "control.hold_duty: expected at most safety.max_mean_duty (0.4)", "got 0.45")
    # with a hold ceiling of its own, a hold duty above it is on-time, not refused
    load_robot(write(tmp_path, R1 + "\n[safety]\nmax_mean_duty = 0.4\nhold_max_duty = 0.2\n[control]\nhold_duty = 0.45\n",
                     "own.toml"))


def test_drive_duty_above_safety_ceiling(tmp_path):
    text = R1 + "\n[safety]\nmax_duty = 0.5\n[control]\ndrive_duty = 0.6\n"
    rejects(tmp_path, text, "control.drive_duty", "at most safety.max_duty")


def test_a_cooldown_of_256_on_times_is_refused_255_builds(tmp_path):
    # the firmware pays on-time back at max_on/min_cooldown in steps of 1/256 (sma.c)
    text = R1 + "\n[safety]\nmax_on_ms = 100\nmin_cooldown_ms = {}\n"
    rejects(tmp_path, text.format(25_501), "safety.min_cooldown_ms", "at most 255 × safety.max_on_ms (25500)")
    p = tmp_path / "ok.toml"
    p.write_text(text.format(25_500))
    assert load_robot(p).safety.min_cooldown_ms == 25_500


def test_tick_rate_below_200_hz(tmp_path):
    rejects(tmp_path, R1 + "\n[control]\ntick_hz = 100\n", "control.tick_hz", "200..10000")


def test_invalid_toml_is_one_line(tmp_path):
    rejects(tmp_path, R1 + "\n[[limb\n", "not valid TOML")


def test_missing_file():
    with pytest.raises(RobotFileError, match="no such robot file"):
        load_robot("/nonexistent/robot.toml")


@pytest.mark.parametrize("arg, hint", [
    ("Paper-R1", "Paper-R1: no such robot file (nor a bundled robot: did you mean paper-r1? `proleg robots` lists them)"),
    ("zzz-robot", "zzz-robot: no such robot file (nor a bundled robot: `proleg robots` lists them)"),
    ("/nonexistent/paper-r1", "/nonexistent/paper-r1: no such robot file"),
])
def test_a_name_that_is_no_bundled_robot_points_to_the_closest_and_to_proleg_robots(capsys, arg, hint):
    """A user typing a bundled robot's name with the wrong case was told only that no such file exists."""
    from proleg.cli import main

    assert main(["gait", arg]) == 2
    assert capsys.readouterr().err == f"proleg: error: {hint}\n"


def test_durations_and_speed_data(tmp_path):
    d = "durations_s = [[0, 1.5, 1.0, 2], [1, 0, 2, 1], [1, 1, 0, 1], [2, 2, 2, 0]]"
    r = load_robot(write(tmp_path, R1.replace("[transitions]", "[transitions]\n" + d)))
    t = r.transitions
    assert t.duration is not None
    assert t.duration[t.lookup(0, 1)] == 1.5


def test_duration_for_a_forbidden_transition_is_rejected(tmp_path):
    text = R1.replace("[1, 0, 0, -1]", '[1, 0, 0, "x"]').replace(
        "[transitions]", "[transitions]\ndurations_s = [[0, 1, 1, 1], [1, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0]]"
    )
    rejects(tmp_path, text, "durations_s[2][4]", "forbidden")


def test_a_duration_past_an_hour_is_refused_in_the_matrix_and_the_csv_as_default_duration_s_is(tmp_path):
    """default_duration_s was bounded to (0, 3600] but durations_s and a CSV's duration_s took any
    finite number: 1.7e308 on two steps of a gait overflowed its summed duration (a traceback)."""
    huge = "durations_s = [[0, 1.7e308, 1, 1], [1, 0, 1, 1.7e308], [1, 1, 0, 1], [1, 1, 1, 0]]"
    rejects(tmp_path, R1.replace("[transitions]", "[transitions]\n" + huge),
            "transitions.durations_s[1][2]: expected a duration in [1e-06, 3600] seconds or 'x', got 1.7e+308")
    hour = huge.replace("1.7e308", "3600")
    assert load_robot(write(tmp_path, R1.replace("[transitions]", "[transitions]\n" + hour))).transitions.duration.max() == 3600
    with pytest.raises(RobotFileError, match=r"t\.csv:3: duration_s: expected a number in \[1e-06, 3600\] seconds, got '3601'"):
        load_robot(csv_robot(tmp_path, "from,to,reward,duration_s\n00,10,1,3\n10,00,1,3601\n"))


def test_a_duration_under_a_microsecond_is_refused_everywhere_and_the_shortest_keeps_speed_finite(tmp_path):
    """Durations took anything above 0: 1e9 steps in 1e-300 s is past float64, so --objective
    speed printed numpy's overflow warnings and answered 'no gait moves the robot' for R1. The
    shortest duration is a microsecond (the fastest tick is 100 µs), where J / T stays finite
    and the speed search agrees with the brute-force oracle."""
    from proleg.gait import optimal_gaits
    from proleg.gait.bruteforce import brute_force_gaits

    tiny = "durations_s = [[0, 1e-300, 1, 1], [1, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0]]"
    rejects(tmp_path, R1.replace("[transitions]", "[transitions]\n" + tiny),
            "transitions.durations_s[1][2]: expected a duration in [1e-06, 3600] seconds or 'x', got 1e-300")
    rejects(tmp_path, R1.replace("[transitions]", "[transitions]\ndefault_duration_s = 1e-300"),
            "transitions.default_duration_s: expected a number in [1e-06, 3600.0], got 1e-300")
    with pytest.raises(RobotFileError, match=r"t\.csv:2: duration_s: expected a number in \[1e-06, 3600\] seconds, got '1e-7'"):
        load_robot(csv_robot(tmp_path, "from,to,reward,duration_s\n00,10,1,1e-7\n10,00,1,3\n"))
    extreme = R1.replace("[[0, -1, 1, 0], [1, 0, 0, -1]", "[[0, 1e9, -1e9, 0], [1e9, 0, 0, -1e9]")
    assert extreme != R1
    robot = load_robot(write(tmp_path, extreme.replace("[transitions]", "[transitions]\ndefault_duration_s = 1e-6")))
    for direction in ("+x", "-x"):
        result = optimal_gaits(robot.transitions, "speed", direction)
        value, ties = brute_force_gaits(robot.transitions, "speed", direction)
        assert value is not None and result.value == pytest.approx(value, rel=1e-9)
        assert {g.states for g in result.gaits} == ties


def test_multi_level_limb_labels(tmp_path):
    text = R1.replace('name = "left"\npsi_star_deg = [20.0]', 'name = "left"\nlevels = 3\npsi_star_deg = [10.0, 25.0]')
    text = text.replace(
        "matrix = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]",
        "matrix = [" + ", ".join("[" + ", ".join("1" for _ in range(6)) + "]" for _ in range(6)) + "]",
    )
    r = load_robot(write(tmp_path, text))
    assert r.levels == (3, 2)
    assert r.transitions.labels() == ["00", "01", "10", "11", "20", "21"]
    assert r.transitions.n_transitions == 30


def three_level_left(psi: str, control: str = "") -> str:
    """R1 with a three-level left limb of critical angles ``psi`` (and a [control] table)."""
    text = R1.replace('name = "left"\npsi_star_deg = [20.0]', f'name = "left"\nlevels = 3\npsi_star_deg = {psi}')
    text = text.replace(
        "matrix = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]",
        "matrix = [" + ", ".join("[" + ", ".join("1" for _ in range(6)) + "]" for _ in range(6)) + "]",
    )
    return text + (f"\n[control]\n{control}\n" if control else "")


def hold_warnings(path: Path) -> list[str]:
    """The warnings loading ``path`` logs about levels that cannot be held, caught on the
    loader's own logger (the CLI's stops propagating to caplog once a test has run ``main``)."""
    import logging

    lines: list[str] = []
    handler = logging.Handler(logging.WARNING)
    handler.emit = lambda record: lines.append(record.getMessage())  # type: ignore[method-assign]
    logger = logging.getLogger("proleg.robot")
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.WARNING)
    try:
        load_robot(path)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    return [line for line in lines if "so level" in line]


def test_thresholds_too_close_to_hold_the_lower_level_warn_naming_file_limb_angles_and_spacing(tmp_path):
    # held at level 1 between 10 + 1 + 4 = 15° and 16°: level 2's band starts at 16 - 1 = 15°
    path = write(tmp_path, three_level_left("[10.0, 16.0]"))
    (line,) = hold_warnings(path)
    assert line.startswith(f"warning: {path}: limb 'left': psi_star_deg 10° and 16° are 6° apart")
    assert "up to 16°" in line and "level 2's band (from 15°)" in line and "level 1 cannot be held" in line
    assert "more than 7° apart (hysteresis_deg 2 + hold_margin_deg 4 + 1)" in line
    # a smaller hold margin makes room: 10 + 1 + 1 + 1 = 13° < 15°
    path = write(tmp_path, three_level_left("[10.0, 16.0]", "hold_margin_deg = 1.0"))
    assert hold_warnings(path) == []


def test_thresholds_far_enough_apart_do_not_warn(tmp_path):
    path = write(tmp_path, three_level_left("[10.0, 17.5]"))  # hold top 16°, next band from 16.5°
    assert hold_warnings(path) == []


@pytest.mark.parametrize("path", sorted(ROBOTS.glob("*.toml")), ids=lambda p: p.stem)
def test_no_example_robot_has_a_level_it_cannot_hold(path):
    assert hold_warnings(path) == []


def csv_robot(tmp_path: Path, rows: str) -> Path:
    (tmp_path / "t.csv").write_text(rows)
    head = R1.split("[transitions]")[0]
    return write(tmp_path, head + '[transitions]\nfile = "t.csv"\n')


def test_csv_table_with_labels_and_indices(tmp_path):
    r = load_robot(csv_robot(tmp_path, "from,to,reward\n# comment line\n00,10,1\n10,11,0.5\n@3,@0,-2\n"))
    t = r.transitions
    assert t.n_transitions == 3
    assert t.reward[t.lookup(3, 0)] == -2 and t.reward[t.lookup(2, 3)] == 0.5


def test_csv_errors_name_file_and_line(tmp_path):
    path = csv_robot(tmp_path, "from,to,reward\n00,10,1\n10,2x,1\n")
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert re.search(r"t\.csv:3: to: expected a state label", str(info.value))


@pytest.mark.parametrize("text, message", [
    # the header was skipped unread: a 4th column was taken for duration_s whatever it said
    ("from,to,reward,extra\n00,10,1,3\n10,00,1,4\n",
     r"t\.csv:1: expected the header from,to,reward\[,duration_s\] \(in this order\), got 'from,to,reward,extra'"),
    ("to,from,reward\n10,00,1\n", r"t\.csv:1: expected the header .*got 'to,from,reward'"),
    ("from,to,reward\n00,10,1,3\n10,00,1,4\n",
     r"t\.csv:2: expected 3 fields as the header names \(from,to,reward\), got 4"),
])
def test_a_csv_header_is_read_not_skipped(tmp_path, text, message):
    with pytest.raises(RobotFileError, match=message):
        load_robot(csv_robot(tmp_path, text))


def test_a_csv_header_that_names_durations_gives_them(tmp_path):
    r = load_robot(csv_robot(tmp_path, "# c\nfrom,to,reward,duration_s\n00,10,1,3\n10,00,1,4\n"))
    assert sorted(r.transitions.duration.tolist()) == [3.0, 4.0]
    r = load_robot(csv_robot(tmp_path, "00,10,1\n10,00,1\n"))  # no header at all: as before
    assert r.transitions.n_transitions == 2


def test_csv_duplicate_transition(tmp_path):
    with pytest.raises(RobotFileError, match=r"t\.csv:3: transition 00 -> 10 is given twice"):
        load_robot(csv_robot(tmp_path, "from,to,reward\n00,10,1\n00,10,2\n"))


def test_robot_name_goes_into_firmware_so_it_is_restricted(tmp_path):
    rejects(tmp_path, R1.replace('name = "t"', 'name = "My Robot"'), "robot.name", "lowercase")


# -- [plant]: checked with the rest of the file, not when the simulator starts ---------------


@pytest.mark.parametrize(
    "plant, fragments",
    [
        ('supply_volts = 5.0', ["plant.supply_volts: unknown key", "did you mean 'supply_v'"]),
        ('zzz = 5.0', ["plant.zzz: unknown key", "expected one of: resistance_ohm"]),
        ('supply_v = "five"', ["plant.supply_v: expected a number in (0, 60] V", "'five'"]),
        ('supply_v = 0', ["plant.supply_v: expected a number in (0, 60] V, got 0"]),
        ('resistance_ohm = [30.0]', ["plant.resistance_ohm: expected one number or a list of 2 (one per actuator)"]),
        ('resistance_ohm = [30.0, -3]', ["plant.resistance_ohm[2]: expected a number in (0, 10000] Ω, got -3"]),
        ('psi_rest_deg = [0, 95]', ["plant.psi_rest_deg[2]: expected a number in (-90, 90) °"]),
        ('as_c = 90.0', ["plant: actuator 'a': expected as_c (90) below af_c (82)"]),
        ('coupling_deg = [[1, 2, 3], [4, 5, 6]]', ["plant.coupling_deg: expected 2 rows (limbs) of 2 numbers"]),
        ('coupling_deg = [[1, 2], [4, true]]', ["plant.coupling_deg[2][2]: expected a number"]),
        ('mech_tau_s = 0.0', ["plant.mech_tau_s: expected a number in (0, 10] s, got 0.0"]),
        ('noise_mm = -1', ["plant.noise_mm: expected a number in [0, 1000] mm"]),
        ('true_matrix = [[0, 1], [1, 0]]', ["plant.true_matrix: expected 4 rows of 4 entries"]),
        ('true_matrix = [[0, 1, "y", 0], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]',
         ["plant.true_matrix[1][3]: expected a number", "'y'"]),
    ],
)
def test_a_bad_plant_key_is_one_line_naming_file_key_and_range(tmp_path, plant, fragments):
    rejects(tmp_path, R1 + "\n[plant]\n" + plant + "\n", *fragments)


def test_plant_values_are_resolved_per_actuator_and_per_limb(tmp_path):
    robot = load_robot(write(tmp_path, R1 + """
[plant]
supply_v = 3.7
resistance_ohm = [30.0, 40.0]
psi_rest_deg = [2.0, -1.0]
step_mm = 5
true_matrix = [[0, 2, 1, "x"], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]
"""))
    p = robot.plant
    assert p.actuator["supply_v"] == (3.7, 3.7)
    assert p.actuator["resistance_ohm"] == (30.0, 40.0)
    assert p.actuator["as_c"] == (64.0, 64.0)  # default
    assert p.psi_rest_deg == (2.0, -1.0)
    assert p.step_mm == 5.0 and p.noise_mm == 0.0
    assert p.true_matrix[0, 1] == 2.0 and np.isnan(p.true_matrix[0, 3])
    assert p.given == {"supply_v", "resistance_ohm", "psi_rest_deg", "step_mm", "true_matrix"}


def test_every_plant_key_is_documented_with_unit_and_range():
    from proleg.robot_plant import PLANT_KEYS

    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot-file.md").read_text()
    for key, spec in PLANT_KEYS.items():
        row = next((line for line in doc.splitlines() if line.startswith(f"| `{key}` |")), None)
        assert row is not None, f"{key} is not in docs/robot-file.md"
        assert spec.range_text() in row, (key, spec.range_text(), row)


# -- hostile files: one line, never a traceback ------------------------------------------------


@pytest.mark.parametrize("opening, closing", [("[", "]"), ("{b = ", "}")])
def test_a_file_nested_500_deep_is_one_line_not_a_recursion_error(tmp_path, opening, closing):
    rejects(tmp_path, R1 + "\n[plant]\nx = " + opening * 500 + "1" * (opening == "{b = ") + closing * 500 + "\n",
            "nested 500 deep, expected at most 32")


def test_brackets_inside_strings_and_comments_do_not_count_as_nesting(tmp_path):
    text = R1.replace('name = "t"', 'name = "t"\ndescription = "' + "[" * 100 + '"  # ' + "{" * 100)
    assert load_robot(write(tmp_path, text)).description == "[" * 100


def test_a_huge_robot_file_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    import proleg.robot as robot_module

    monkeypatch.setattr(robot_module, "MAX_FILE_BYTES", 4096)
    rejects(tmp_path, R1 + "#" * 5000 + "\n", "robot file of", "bytes, expected at most 4,096")


def test_the_real_size_limit_refuses_a_17_mb_file(tmp_path):
    rejects(tmp_path, R1 + ("# padding" + " " * 1000 + "\n") * 17_000, "expected at most 16,777,216")


def test_absurd_state_counts_are_refused_before_anything_is_allocated(tmp_path):
    limbs = "".join(
        f'[[limb]]\nname = "l{i}"\nlevels = 10\npsi_star_deg = [{", ".join(str(-80 + 17 * k) for k in range(9))}]\n'
        f'hysteresis_deg = 1\nactuator = "a"\n'
        for i in range(8)
    )
    text = f'[robot]\nname = "t"\n{limbs}[[actuator]]\nname = "a"\n[transitions]\nmatrix = []\n'
    rejects(tmp_path, text, "100,000,000 states", "expected at most 1,048,576")


def test_a_csv_with_a_giant_field_is_one_line_naming_the_csv_line(tmp_path):
    (tmp_path / "t.csv").write_text("from,to,reward\n00,10," + "1" * 200_000 + "\n")
    text = R1.replace("matrix = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]", 'file = "t.csv"')
    with pytest.raises(RobotFileError, match=r"t\.csv:2: not a readable CSV row: field larger than field limit"):
        load_robot(write(tmp_path, text))


@pytest.mark.parametrize(("old", "new", "fragments"), [
    ('name = "t"', 'name = "t\\n"', ("robot.name: expected lowercase", r"got 't\n'")),
    ('name = "a"', 'name = "a\\n"', (r"actuator 'a\n': name: expected lowercase", r"got 'a\n'")),
    ('name = "left"', 'name = "left\\n"', (r"limb 'left\n': name: expected a name of printable characters", r"got 'left\n'")),
    ('name = "left"', 'name = ""', ("limb #1: name: expected a name of printable characters, at least one, got ''",)),
])
def test_a_name_with_a_newline_or_an_empty_limb_name_is_refused(tmp_path, old, new, fragments):
    # a robot or actuator name goes into the firmware's C; "$" matched before a final newline
    rejects(tmp_path, R1.replace(old, new, 1), *fragments)


def test_robot_names_longer_than_the_firmwares_15_characters_are_accepted(tmp_path):
    # the firmware reports the first 15 characters in GET_INFO; the name itself may be longer
    name = "terresoro-4-limb-freeman-2025"
    assert load_robot(write(tmp_path, R1.replace('name = "t"', f'name = "{name}"'))).name == name
    rejects(tmp_path, R1.replace('name = "t"', f'name = "{"a" * 64}"'), "robot.name", "1 to 63 characters")


def test_a_name_of_the_right_characters_but_too_long_says_how_long_it_is(tmp_path):
    """A lab's 64-character robot name (a-very-long-robot-name-for-our-lab-crawler-prototype-
    number-0042) was told "1 to 63 characters, got '…'", left to count the characters."""
    name = "a-very-long-robot-name-for-our-lab-crawler-prototype-number-0042"
    msg = rejects(tmp_path, R1.replace('name = "t"', f'name = "{name}"'), "robot.name", "1 to 63 characters")
    assert msg.endswith(f"got '{name}' (64 characters)"), msg
    msg = rejects(tmp_path, R1.replace('name = "t"', 'name = "My Robot"'), "robot.name")
    assert msg.endswith("got 'My Robot'"), msg  # the wrong characters: no count


# -- planar statistics in [transitions] (issue 17) ----------------------------------------------

PLANAR = R1 + """dy = [[0, 0.5, -0.5, 0], [0, 0, 0, 0.1], [0.2, 0, 0, 0], [0, 0, 0, 0]]
dtheta_deg = [[0, 2, -2, 0], [0, 0, 0, 1], [1, 0, 0, 0], [0, 0, 0, 0]]
var_dx = [[0, 0.1, 0.1, 0.1], [0.1, 0, 0.1, 0.1], [0.1, 0.1, 0, 0.1], [0.1, 0.1, 0.1, 0]]
"""


def test_planar_statistics_are_read_per_transition_beside_the_matrix(tmp_path):
    t = load_robot(write(tmp_path, PLANAR)).transitions
    assert t.planar is not None and set(t.planar.given()) == {"dy", "dtheta_deg", "var_dx"}
    pos = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(t.src, t.dst))}
    assert t.planar.dy[pos[(0, 1)]] == 0.5 and t.planar.dtheta_deg[pos[(2, 0)]] == 1.0
    assert t.planar.var_dy is None
    assert load_robot(write(tmp_path, R1)).transitions.planar is None


@pytest.mark.parametrize(
    "replace, fragments",
    [
        ("dy = [[0, 0.5, -0.5, 0], [0, 0, 0, 0.1]]", ["transitions.dy: expected 4 rows like the matrix, got 2"]),
        ("dy = [[0, 0.5, -0.5, 0], [0, 0, 0, 0.1], [0.2, 0, 0, 0], [0, 0, 0, 0]]\n"
         "var_dy = [[0, 1, 1, 1], [1, 0, 1, 1], [1, 1, 0, -1], [1, 1, 1, 0]]",
         ["transitions.var_dy[3][4]: expected a variance in [0, 1e+18] or 'x', got -1"]),
        ('dy = [[0, "x", -0.5, 0], [0, 0, 0, 0.1], [0.2, 0, 0, 0], [0, 0, 0, 0]]',
         ["transitions.dy[1][2]: transition is allowed in the matrix, expected a number in [-1e+09, 1e+09], got 'x'"]),
    ],
)
def test_bad_planar_statistics_name_the_field_row_and_column(tmp_path, replace, fragments):
    head = PLANAR.split("dy = ")[0]
    text = head + replace + "\n"
    rejects(tmp_path, text, *fragments)


def test_planar_statistics_must_mark_the_same_forbidden_transitions(tmp_path):
    text = R1.replace("matrix = [[0, -1, 1, 0]", 'matrix = [[0, -1, 1, "x"]') + (
        "dy = [[0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]\n"
    )
    rejects(tmp_path, text, "transitions.dy[1][4]: transition is forbidden in the matrix, expected 'x', got 1")


@pytest.mark.parametrize("ref", ["¹", "١"])
def test_a_state_index_is_ascii_digits_only(tmp_path, ref):
    # "¹".isdigit() is true but int() refuses it; int("١") is 1: both are refused, in one line
    text = R1.replace("[0, 0, 0, 0]]", '[0, 0, 0, "x"]]').replace("[transitions]", f'[transitions]\nforbidden = ["{ref}->00"]')
    rejects(tmp_path, text, "transitions.forbidden[1]", "a state index @0..@3", repr(ref))
    with pytest.raises(RobotFileError, match=r"t\.csv:2: from: expected a state label"):
        load_robot(csv_robot(tmp_path, f"from,to,reward\n{ref},01,-1\n"))


@pytest.mark.parametrize("entry", ["1e308", "-1e10"])
def test_matrix_entries_are_bounded_like_the_true_matrix(tmp_path, entry):
    # 1e308 overflowed the gait sums to inf and the search answered wrongly
    rejects(tmp_path, R1.replace("[0, -1, 1, 0]", f"[0, -1, {entry}, 0]"),
            "transitions.matrix[1][3]: expected a number in [-1e+09, 1e+09]")
    with pytest.raises(RobotFileError, match=r"t\.csv:2: reward: expected a number in \[-1e\+09, 1e\+09\], got"):
        load_robot(csv_robot(tmp_path, f"from,to,reward\n00,10,{entry}\n"))
    assert load_robot(write(tmp_path, R1.replace("[0, -1, 1, 0]", "[0, -1, 1e9, 0]"))).transitions.reward.max() == 1e9


def test_planar_means_and_variances_are_bounded(tmp_path):
    head = PLANAR.split("dy = ")[0]
    rejects(tmp_path, head + "dy = [[0, 1e308, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]\n",
            "transitions.dy[1][2]: expected a number in [-1e+09, 1e+09] or 'x', got 1e+308")
    rejects(tmp_path, head + "var_dx = [[0, 1e300, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]\n",
            "transitions.var_dx[1][2]: expected a variance in [0, 1e+18] or 'x', got 1e+300")


@pytest.mark.parametrize("entry, shown", [("1e300", "1e+300"), ("-1", "-1"), ("nan", "nan"), ("1.5", "got 1.5")])
def test_n_trials_are_whole_numbers_in_range_named_as_trials(tmp_path, entry, shown):
    # 1e300 became a garbage int64; -1 and nan were called "a variance"; 1.5 showed np.float64(1.5)
    text = R1.replace("[transitions]", f"[transitions]\nn_trials = [[0, {entry}, 1, 1], [1, 0, 1, 1], [1, 1, 0, 1], "
                                       "[1, 1, 1, 0]]")
    msg = rejects(tmp_path, text, "transitions.n_trials[1][2]: expected a whole number of trials in [0, 1e+09]", shown)
    assert "variance" not in msg and "np." not in msg


def test_csv_lines_are_file_lines_not_rows(tmp_path):
    # a quoted cell spanning lines: the bad row is on line 6, it was reported as row 3
    with pytest.raises(RobotFileError, match=r"t\.csv:6: reward: expected a number, got 'zz'"):
        load_robot(csv_robot(tmp_path, 'from,to,reward\n"00\n\n\n",01,-1\n00,10,zz\n'))
    with pytest.raises(RobotFileError, match=r"t\.csv:3: from: expected a state label"):
        load_robot(csv_robot(tmp_path, 'from,to,reward\n00,01,-1\n"0\n1x",10,1\n'))


def test_a_csv_that_is_not_utf8_names_the_line(tmp_path):
    (tmp_path / "t.csv").write_bytes(b"from,to,reward\n00,01,-1\n# caf\xe9\n00,10,1\n")
    head = R1.split("[transitions]")[0]
    with pytest.raises(RobotFileError, match=r"t\.csv:3: not UTF-8 text \(invalid continuation byte\)"):
        load_robot(write(tmp_path, head + '[transitions]\nfile = "t.csv"\n'))


def test_a_csv_with_a_bom_or_a_comment_before_its_header_loads(tmp_path):
    rows = "from,to,reward\n00,10,1\n10,11,0.5\n"
    assert load_robot(csv_robot(tmp_path, "\ufeff" + rows)).transitions.n_transitions == 2
    assert load_robot(csv_robot(tmp_path, "# my table\n" + rows)).transitions.n_transitions == 2
    with pytest.raises(RobotFileError, match=r"t\.csv:4: from: expected a state label"):
        load_robot(csv_robot(tmp_path, rows + "from,to,reward\n"))  # a header among the rows is a bad row


def test_a_robot_file_with_a_bom_loads_and_one_not_utf8_names_the_line(tmp_path):
    assert load_robot(write(tmp_path, "\ufeff# saved by Notepad\n" + R1)).name == "t"
    path = tmp_path / "latin1.toml"
    path.write_bytes(R1.encode() + b"# caf\xe9\n")
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    line = R1.count("\n") + 1
    assert str(info.value) == (f"{path}: line {line}: not UTF-8 text (byte 0xe9: invalid continuation byte); "
                               "save it as UTF-8")


def test_a_csv_label_with_a_digit_missing_is_refused_naming_line_and_column(capsys):
    # "0010" on five limbs was read as state index 10 (01010): the best gait walked through it
    from proleg.cli.main import main

    fixture = Path(__file__).parent / "fixtures" / "five-typo-label.toml"
    assert main(["gait", str(fixture)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.endswith("five-typo-label.csv:2: to: '0010' is not a state label of 5 digits (one per limb, "
                        "e.g. 00000; a state index is written @0..@31)"), err


@pytest.mark.parametrize("ref", ["1", "001", "0001"])
def test_digits_of_the_wrong_length_are_never_a_state_index(tmp_path, ref):
    with pytest.raises(RobotFileError, match=rf"t\.csv:2: from: '{ref}' is not a state label of 2 digits"):
        load_robot(csv_robot(tmp_path, f"from,to,reward\n{ref},10,1\n"))
    text = R1.replace("[0, 0, 0, 0]]", '[0, 0, 0, "x"]]').replace("[transitions]", f'[transitions]\nforbidden = ["11->{ref}"]')
    rejects(tmp_path, text, "transitions.forbidden[1]", f"'{ref}' is not a state label of 2 digits")


@pytest.mark.parametrize("ref", ["@4", "@", "@-1", "@x"])
def test_a_state_index_is_at_and_in_range(tmp_path, ref):
    with pytest.raises(RobotFileError, match=rf"t\.csv:2: to: expected a state label of 2 digits or a state index "
                                             rf"@0\.\.@3, got '{ref}'"):
        load_robot(csv_robot(tmp_path, f"from,to,reward\n00,{ref},1\n"))


def test_a_limb_key_typo_gets_a_did_you_mean_like_plant_keys(tmp_path):
    msg = rejects(tmp_path, R1.replace("psi_star_deg = [20.0]", "psi_star_degs = [20.0]", 1),
                  "limb 'left': unknown key 'psi_star_degs' (did you mean 'psi_star_deg'?)")
    assert "expected one of" not in msg
    rejects(tmp_path, R1 + "\n[safety]\nmax_on_msec = 3000\n",
            "safety: unknown key 'max_on_msec' (did you mean 'max_on_ms'?)")
    rejects(tmp_path, R1.replace('name = "left"', 'name = "left"\nzzz = 3'),
            "limb 'left': unknown key 'zzz' (expected one of: actuator, friction,")


def test_the_documented_psi_star_range_is_the_loaders(tmp_path):
    # robot-file.md said "angles in (−90, 90)"; the loader wants ψ* ± hysteresis/2 inside it
    doc = (Path(__file__).resolve().parents[1] / "docs" / "robot-file.md").read_text(encoding="utf-8")
    assert "ψ* ± hysteresis_deg/2 must lie inside (−90, 90): with the default 2° of hysteresis, ψ* in (−89, 89)" in doc
    rejects(tmp_path, R1.replace("psi_star_deg = [20.0]", "psi_star_deg = [89.5]", 1), "limb 'left': psi_star_deg",
            "psi* ± hysteresis_deg/2 (2/2) lie strictly inside (-90, 90)")
    assert load_robot(write(tmp_path, R1.replace("psi_star_deg = [20.0]", "psi_star_deg = [88.9]", 1)))


def test_a_table_plant_limb_that_rests_in_its_level_1_is_warned_of(tmp_path, caplog):
    """psi_rest_deg = [30, 0] loaded silently and every --plant table run timed out."""
    import logging

    path = write(tmp_path, R1 + "\n[plant]\npsi_rest_deg = [30, 0]\n")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    lines = [r.getMessage() for r in caplog.records]
    assert any("plant.psi_rest_deg: limb 'left' rests at 30°, in its level 1 or above (from 19°" in ln
               and "--plant table" in ln for ln in lines), lines
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(write(tmp_path, R1 + "\n[plant]\npsi_rest_deg = [10, 0]\n", "ok.toml"))
    assert not [r for r in caplog.records if "psi_rest_deg" in r.getMessage()]


def test_a_debounce_longer_than_the_state_timeout_is_refused(tmp_path):
    """A step changes a limb's level after debounce_ticks samples and settles it after as many
    again, under the state timeout: 1000 ticks at 200 Hz (5 s, both keys in range) with a 2 s
    timeout loaded and built, and every step ended in STATE_TIMEOUT ("one would not settle")."""
    slow = "\n[safety]\nstate_timeout_ms = 2000\n[control]\ntick_hz = 200\ntelemetry_hz = 20\ndebounce_ticks = {}\n"
    rejects(tmp_path, R1 + slow.format(1000), "control.debounce_ticks: expected under half the 400 ticks "
            "safety.state_timeout_ms lasts at 200 Hz", "1000 ticks take 5000 ms, twice that 10000 ms",
            "STATE_TIMEOUT after 2000 ms", "got 1000")
    rejects(tmp_path, R1 + slow.format(200), "200 ticks take 1000 ms, twice that 2000 ms")
    assert load_robot(write(tmp_path, R1 + slow.format(199))).control.debounce_ticks == 199
    assert load_robot(write(tmp_path, R1 + slow.format(50))).control.debounce_ticks == 50
    assert load_robot(write(tmp_path, R1 + "\n[control]\ndebounce_ticks = 1000\n")).control.debounce_ticks == 1000


@pytest.mark.parametrize("old, new, where", [
    ('name = "t"', 'name = "-"', "robot.name"),
    ('name = "t"', 'name = "-r1"', "robot.name"),
    ('name = "a"', 'name = "-a"', "actuator '-a': name"),
])
def test_a_name_starting_with_a_dash_is_told_it_must_not(tmp_path, old, new, where):
    """'-' was refused as "expected lowercase letters, digits and '-', 1 to 63 characters,
    got '-'": every character was one the message allows. The first may not be a '-'."""
    rejects(tmp_path, R1.replace(old, new, 1), where, "lowercase letters, digits and '-' (not first)")


def test_a_stroke_on_a_limb_held_past_the_largest_stroke_says_no_stroke_fits(tmp_path):
    """ψ* 80° is held at 85° without a stroke, and a stroke may be at most 85°: the message was
    "expected an angle from 86 (…) to 85 degrees, got 85", a range with nothing in it. It now
    says no stroke fits that limb and what would make room."""
    text = R1.replace('psi_star_deg = [20.0]\nactuator = "a"', 'psi_star_deg = [80.0]\nactuator = "a"\nstroke_deg = 85')
    err = rejects(tmp_path, text, "limb 'left': stroke_deg:")
    assert "from 86" not in err and "no stroke fits this limb" in err and "85" in err


@pytest.mark.parametrize("psi, hyst, words", [
    ("[86.0]", 2.0, "the controller holds it raised between 91° and 92° (psi* + hysteresis/2 + "
                    "control.hold_margin_deg, and 1° above), but the firmware's angles stop at 89°"),
    ("[-86.0]", 2.0, "lowered, it counts as settled only below -91° (psi* - hysteresis/2 - "
                     "control.hold_margin_deg), but the firmware's angles stop at -89°"),
])
def test_a_hold_or_settle_edge_past_the_firmwares_89_degrees_is_warned_of(tmp_path, caplog, psi, hyst, words):
    """ψ* 86° loaded without a word: the firmware clamps every hold, hold-top and settle edge to
    ±89° (psi.c), so the file's 4° hold margin became 2° and the hold band [89°, 89°] nothing."""
    import logging

    caplog.set_level(logging.WARNING)
    load_robot(write(tmp_path, R1.replace("psi_star_deg = [20.0]", f"psi_star_deg = {psi}", 1)))
    lines = [r.getMessage() for r in caplog.records if "89°" in r.getMessage()]
    assert len(lines) == 1 and "limb 'left'" in lines[0] and words in lines[0], lines
    caplog.clear()
    load_robot(write(tmp_path, R1.replace("psi_star_deg = [20.0]", "psi_star_deg = [84.0]", 1)
                     .replace("[transitions]", "[control]\nhold_margin_deg = 1.0\n\n[transitions]")))
    assert not [r for r in caplog.records if "89°" in r.getMessage()]


@pytest.mark.parametrize("table", ["limb", "actuator"])
def test_a_repeated_single_bracket_limb_or_actuator_says_to_write_double_brackets(tmp_path, table):
    """Two limbs written [limb] (one bracket, a table, not an array of tables) were "not valid
    TOML: Cannot declare ('limb',) twice (at line 10, column 6)": the parser's words, not
    the fix. The line adds that each one is a [[limb]]."""
    text = R1.replace("[[limb]]", "[limb]") if table == "limb" else R1.replace("[[actuator]]", "[actuator]")
    rejects(tmp_path, text, "not valid TOML", f"write each one as [[{table}]] (two brackets)")


@pytest.mark.parametrize("text, line", [
    ("from;to;reward\n00;10;1\n10;00;-1\n", 1),
    ("00;10;1\n10;00;-1\n", 1),
    ("from,to,reward\n00,10,1\n10;00;-1\n", 3),
    ("from\tto\treward\n00\t10\t1\n", 1),
])
def test_a_csv_table_separated_by_semicolons_or_tabs_says_so(tmp_path, text, line):
    """A spreadsheet set to a European locale exports ';' (and a tab-separated export tabs):
    such a table was "expected the header from,to,reward[,duration_s] (in this order), got
    '00;10;1'" (a data row read as a header) or "expected 3 fields". It now says the fields
    are separated by another character and that the table takes commas."""
    with pytest.raises(RobotFileError, match=rf"t\.csv:{line}: fields separated by '(;|\\t)', not commas"):
        load_robot(csv_robot(tmp_path, text))


@pytest.mark.parametrize("window_ms, drive, warned", [
    (100, 0.6, True), (2000, 0.6, True), (3000, 0.6, False), (10_000, 0.6, False), (100, 0.45, False),
])
def test_a_mean_duty_window_shorter_than_an_on_period_is_warned_of(tmp_path, window_ms, drive, warned):
    """duty_window_ms = 100 loaded without a word, and R1's rises ran into SMA_ON_LIMIT: the
    mean-duty limit (0.45) held within each on-period, under the drive duty (0.6)."""
    from proleg.robot_settings import window_warning

    path = write(tmp_path, R1 + f"\n[safety]\nduty_window_ms = {window_ms}\n\n[control]\ndrive_duty = {drive}\n")
    robot = load_robot(path)
    line = window_warning(path, robot.safety, robot.control)
    assert (line is not None) == warned
    if warned:
        assert f"safety.duty_window_ms {window_ms} is shorter than max_on_ms 3000" in line
        assert f"once it has been on about {window_ms * 0.45 / drive:.0f} ms of a window" in line
