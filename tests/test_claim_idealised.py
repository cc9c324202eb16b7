"""The claim bench's idealised drive reports its own speed under every condition
(``claim.idealised_walk``), so that the bench can tell a condition that slows the gait itself
(whatever drives it) from one the controller handles badly."""

from __future__ import annotations

import math
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st
from proleg.paths import robots_dir
from proleg.report import claim
from proleg.report.claim_summary import summarise
from proleg.robot import load_robot

R1 = robots_dir() / "paper-r1.toml"


def test_the_idealised_drive_walks_the_nominal_robot_forward_and_says_how_fast():
    walk = claim.idealised_walk(load_robot(R1), claim.NOMINAL)
    assert walk.possible and walk.why_not == ""
    assert walk.speed_mm_s is not None and walk.speed_mm_s > 0.1


def test_hot_ambient_slows_the_gait_itself_because_the_coils_cool_slower():
    robot = load_robot(R1)
    nominal = claim.idealised_walk(robot, claim.NOMINAL).speed_mm_s
    hot = claim.idealised_walk(robot, claim.point("hot ambient (strong)")).speed_mm_s
    assert hot is not None and 0 < hot < 0.75 * nominal


def test_a_dead_coil_that_stops_the_gait_has_no_speed_and_a_reason():
    walk = claim.idealised_walk(load_robot(R1), claim.point("dead coil (strong)"))
    assert not walk.possible and walk.speed_mm_s is None
    assert "dead coil" in walk.why_not
    assert claim.physically_possible(load_robot(R1), claim.point("dead coil (strong)")) == (False, walk.why_not)


def _row(i: int, possible: bool, completed: bool, fb: float, ideal: float | None) -> claim.ConditionResult:
    point = claim.GridPoint(f"c{i}", ("m",), "mild")
    out = claim.DriveOutcome(completed, fb, fb * 40)
    return claim.ConditionResult(point, possible, "" if possible else "no", out, out, {}, ideal)


rows = st.lists(st.tuples(st.booleans(), st.booleans(), st.floats(-2, 2), st.none() | st.floats(-2, 2)),
                min_size=1, max_size=12)


@settings(max_examples=200, deadline=None)
@given(rows, st.floats(0.05, 2), st.floats(0.05, 2))
def test_the_summary_counts_rows_the_condition_itself_slows_as_a_recount_does(spec, nom_fb, nom_ideal):
    results = [_row(i, *r) for i, r in enumerate(spec)]
    nominal = _row(-1, True, True, nom_fb, nom_ideal)
    s = summarise(results, nominal)
    # the recount, row by row
    measured = slowed = walked = kept_of_ideal = 0
    slowed_names, barely = [], []
    for r in results:
        if not r.possible or r.idealised_mm_s is None:
            continue
        measured += 1
        if r.idealised_mm_s < 0.75 * nom_ideal:
            slowed += 1
            slowed_names.append(r.point.name)
        if r.idealised_mm_s < 0.05 * nom_ideal:
            barely.append(r.point.name)  # the idealised drive barely moves it: no yardstick
            continue
        walked += 1
        if r.feedback.completed and r.feedback.speed_mm_s >= 0.75 * r.idealised_mm_s:
            kept_of_ideal += 1
    assert s["slowed_by_the_condition_itself"] == slowed_names
    assert s["idealised_kept_75pct_where_possible"] == measured - slowed
    assert s["idealised_walked_where_possible"] == walked
    assert s["idealised_barely_moves"] == barely
    assert s["feedback_kept_75pct_of_idealised_where_it_walks"] == kept_of_ideal
    assert math.isclose(s["idealised_nominal_mm_s"], round(nom_ideal, 4))


@settings(max_examples=300, deadline=None)
@given(rows, st.floats(-2, 2), st.floats(-8, 8), st.sampled_from(["", "stalled: …", "coil overheated (150 °C)"]),
       st.sampled_from(["+x", "-x"]))
def test_the_targets_count_speed_in_the_benchs_direction_only(spec, nom_fb, nom_ol, ol_note, direction):
    """Recount: a firmware that walks the wrong way nominally keeps nothing and is not faster;
    the open loop's bar is its nominal speed that way (none backwards), unless it overheated a
    coil; a stalled run that still moved sets its bar all the same."""
    results = [_row(i, *r) for i, r in enumerate(spec)]
    fb = claim.DriveOutcome(True, nom_fb, nom_fb * 40)
    ol = claim.DriveOutcome(ol_note == "", nom_ol, nom_ol * 40, "", ol_note)
    nominal = claim.ConditionResult(claim.NOMINAL, True, "", fb, ol, {}, None)
    s = summarise(results, nominal, direction)
    sign = 1 if direction == "+x" else -1
    ahead = sign * nom_fb
    kept = sum(1 for r in results if r.possible and r.feedback.completed and ahead > 0
               and sign * r.feedback.speed_mm_s >= 0.75 * ahead)
    bar = 0.0 if ol_note.startswith("coil overheated") else max(0.0, sign * nom_ol)
    assert s["feedback_kept_75pct_where_possible"] == kept
    assert s["targets"]["nominal feedback at least as fast as open loop"] == (ahead > 0 and ahead >= bar)
    assert s["open_loop_bar_mm_s"] == round(bar, 4)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.floats(20, 60), st.floats(20, 200)), min_size=1, max_size=8))
def test_an_impossible_rows_stop_is_clean_only_with_cold_coils_and_none_overheated_on_the_way(spec):
    """Recount of the third target: a fault, every coil below 50 °C 2 s after the stop, and no
    coil past the open loop's line (claim.OVERHEAT_C) on the way."""
    results = []
    for i, (fault, end_c, peak_c) in enumerate(spec):
        out = claim.DriveOutcome(False, 0.0, 0.0, "STATE_TIMEOUT" if fault else "", "", end_c, peak_c)
        results.append(claim.ConditionResult(claim.GridPoint(f"c{i}", ("m",), "mild"), False, "no", out, out, {}, None))
    nominal = _row(-1, True, True, 1.0, 1.0)
    s = summarise(results, nominal)
    clean = sum(1 for f, end_c, peak_c in spec if f and end_c < 50.0 and peak_c <= claim.OVERHEAT_C)
    assert s["impossible_stopped_with_fault_and_cold_coils"] == clean
    assert s["targets"]["impossible conditions stop with a fault and cold coils"] == (clean == len(spec))


def test_a_firmware_run_that_overheats_a_coil_is_not_completed(tmp_path):
    """The one-actuator R1 with the default 4° hold margin (its hold top out of reach: it heats
    its coil toward it at every step) on a supply 1.8× as strong in an enclosure: it walks
    without a fault, but a coil passes the open loop's line (127 °C), so the run is
    "overheated", not completed. (At 1.5× in open air it passed 120 °C until the coil-wide knee
    capped a coil through its transformation at the hold duty: 109 °C since.)"""
    text = (robots_dir() / "paper-r1-one-actuator.toml").read_text()
    path = tmp_path / "one.toml"
    path.write_text(text.replace("hold_margin_deg = 1.0", "hold_margin_deg = 4.0"))
    point = claim.GridPoint("strong supply", ("supply boost",), "strong", ("power=1.8", "convection=0.5"))
    out = claim.feedback_run(load_robot(path), point, gait=[2, 3, 2], duration_s=12.0)
    assert out.speed_mm_s > 0.5 and not out.fault
    assert out.coil_peak_c > claim.OVERHEAT_C and not out.completed
    assert out.note == f"{claim.OVERHEATED} ({out.coil_peak_c:.0f} °C)"
    # with the margin the robot file has, the same run keeps its coil below the line and completes
    out = claim.feedback_run(load_robot(robots_dir() / "paper-r1-one-actuator.toml"), point, gait=[2, 3, 2],
                             duration_s=12.0)
    assert out.completed and out.coil_peak_c <= claim.OVERHEAT_C


def test_a_rise_that_stops_short_is_cut_before_its_coil_overheats_and_a_slow_one_is_not():
    """The one-actuator R1 worn by 30,000 cycles: its far end stops short of ψ*; the firmware
    cuts the coil once the rise stops answering (ctl.h, CTL_REACH_MS), not at its on-time limit
    past 160 °C, and the stop is clean. At a weak supply in a draught the same rise creeps and
    is held off by the envelope's mean-duty window on the way: it still gets there."""
    robot = load_robot(robots_dir() / "paper-r1-one-actuator.toml")
    out = claim.feedback_run(robot, claim.point("fatigue (strong)"), gait=[2, 3, 2], duration_s=12.0)
    assert out.fault and not out.completed and out.coil_peak_c <= claim.OVERHEAT_C, out
    out = claim.feedback_run(robot, claim.point("supply sag + draught (strong)"), gait=[2, 3, 2], duration_s=20.0)
    assert out.completed and out.speed_mm_s > 0.5, out


def test_an_on_limit_hit_the_gait_walks_on_from_is_reported_in_the_note_and_a_latched_one_stops_it():
    """An on-limit hit that does not latch is a report, not a stop (docs/safety.md): the
    one-actuator R1 at a 30 % weaker supply in a strong draught runs into its on-time limit a
    few times and walks on (bench/results/claim-paper-r1-1act.json). The bench calls that run
    completed and lists the hits (``reported``); a fault that latches stops the run (the worn
    coil's rise cut as "cannot reach": STATE_TIMEOUT). (Its first condition, mismatched coils
    behind 8 Ω at a mean-duty budget of 0.5, latches since the plant sags a coil by its full
    current in its PWM on-phase.)"""
    path = robots_dir() / "paper-r1-one-actuator.toml"
    robot = load_robot(path)
    out = claim.feedback_run(robot, claim.point("supply sag + draught (strong)"), duration_s=40.0)
    assert out.completed and not out.fault and out.speed_mm_s > 0.5, out
    assert out.reported.startswith("SMA_ON_LIMIT ×"), out
    out = claim.feedback_run(robot, claim.point("fatigue (strong)"), gait=[2, 3, 2], duration_s=12.0)
    assert not out.completed and out.fault and not out.reported, out


def test_a_state_the_idealised_drive_cannot_reach_is_named_by_its_label():
    """crab-3 (4, 3 and 2 levels): the middle pad raised to level 2 lifts the back pad past its
    edge, so 020 is never reached and the envelope's state timeout latches. `proleg check` said
    "state 4 not reached within state_timeout_ms", the state's index; messages name states by
    their labels (state 4 of this robot is 020, of a binary three-limb one 100)."""
    import pytest
    from proleg.sim.physical.drive import run_sequence
    from proleg.sim.physical.envelope import EnvelopeLatched

    robot = load_robot(Path(__file__).parent / "fixtures" / "crab-3-entry.toml")
    with pytest.raises(EnvelopeLatched, match=r"state timeout: state 020 not reached within state_timeout_ms"):
        run_sequence(robot, robot.transitions.sequence("000,010,020,010,000"), envelope=True)
