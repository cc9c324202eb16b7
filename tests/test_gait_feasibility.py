"""Feasibility of a gait on the robot's hardware, and the entry path from rest."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.errors import GaitError
from proleg.gait import optimal_gaits
from proleg.gait.feasibility import check_gait, entry_path, gait_problems
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"

ONE_ACTUATOR = """
[robot]
name = "t"

[[limb]]
name = "front"
psi_star_deg = [20.0]
actuator = "coil"

[[limb]]
name = "back"
psi_star_deg = [20.0]
actuator = "coil"

[[actuator]]
name = "coil"

[transitions]
matrix = [[0, "x", 1, "x"], [1, 0, "x", 1], [-1, 2, 0, 1], ["x", 0, 1, 0]]
"""


def robot_from(tmp_path: Path, text: str):
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return load_robot(path)


def idx(robot, *labels: str) -> list[int]:
    return [robot.transitions.index(s) for s in labels]


def kinds(robot, *labels: str) -> list[str]:
    return [p.kind for p in gait_problems(robot, idx(robot, *labels))]


def test_the_paper_r1_forward_gait_runs_as_is():
    r1 = load_robot(ROBOTS / "paper-r1.toml")
    best = optimal_gaits(r1.transitions, "total", "+x", 4).gaits[0]
    assert gait_problems(r1, best.states) == []
    check_gait(r1, best.states)
    assert entry_path(r1, best.states).states == (0,)


def test_a_step_raising_one_limb_while_lowering_another_is_flagged_as_opposing():
    r1 = load_robot(ROBOTS / "paper-r1.toml")
    problems = gait_problems(r1, idx(r1, "00", "10", "01", "00"))
    assert [(p.kind, p.severity) for p in problems] == [("opposing", "warning")]
    assert problems[0].message == (
        "gait 00 10 01 00: step 2 (10 -> 01) raises 'right' while lowering 'left' "
        "(a heating and a cooling crossing must coincide)"
    )
    check_gait(r1, idx(r1, "00", "10", "01", "00"))  # a warning does not refuse the gait


def test_limbs_on_one_actuator_cannot_move_in_opposite_directions(tmp_path):
    robot = robot_from(tmp_path, ONE_ACTUATOR)
    assert kinds(robot, "00", "10", "01", "00") == ["shared-actuator"]
    with pytest.raises(GaitError, match=(
        r"^gait 00 10 01 00: step 2 \(10 -> 01\) limbs 'back' and 'front' share actuator 'coil' "
        r"but would move in opposite directions$"
    )):
        check_gait(robot, idx(robot, "00", "10", "01", "00"))


def test_a_coil_holding_its_limb_up_through_the_whole_gait_is_not_on_time():
    # docs/safety.md: holding is not on-time; the one-coil gait 10 -> 11 -> 10 runs for ever
    one = load_robot(ROBOTS / "paper-r1-one-actuator.toml")
    assert kinds(one, "10", "11", "10") == []


def test_the_optimal_inchworm_3_gaits_are_not_flagged_for_held_limbs():
    # the bug: 001 011 111 110 100 101 001 was "sma-tail stays on for at least 3200 ms";
    # the tail is held raised there, and holding pays the debt back
    worm = load_robot(ROBOTS / "inchworm-3.toml")
    for g in optimal_gaits(worm.transitions, "total", "+x", 8).gaits:
        assert [p for p in gait_problems(worm, g.states) if p.kind in ("on-time", "never-cools")] == []
    check_gait(worm, idx(worm, "001", "011", "111", "110", "100", "101", "001"))


def test_a_drive_longer_than_max_on_ms_is_cut_by_the_firmware_and_refused(tmp_path):
    text = (ROBOTS / "paper-r1.toml").read_text().replace("max_on_ms = 3000", "max_on_ms = 150")
    robot = robot_from(tmp_path, text.replace("min_cooldown_ms = 800", "min_cooldown_ms = 20"))
    # no durations: each raise drives DEFAULT_DRIVE_S = 1 s, far above 150 ms (a quick
    # cool-down pays it back within the cycle, so this is the peak, not growth)
    problems = gait_problems(robot, idx(robot, "00", "10", "11", "01", "00"))
    assert [p.kind for p in problems] == ["on-time", "on-time"]
    assert problems[0].message == (
        "gait 00 10 11 01 00: actuator 'sma-left' carries 1000 ms of on-time debt on reaching state 10, "
        "above safety.max_on_ms = 150: the firmware cuts it (SMA_ON_LIMIT)"
    )
    with pytest.raises(GaitError, match="carries 1000 ms of on-time debt"):
        check_gait(robot, idx(robot, "00", "10", "11", "01", "00"))


def test_a_coil_driving_more_than_the_cycle_pays_back_is_refused(tmp_path):
    # raises of 2.5 s each under max_on_ms 3000 (each fits), cool-down 30 s: 0.1 s of debt
    # paid per s, so a cycle of 2 × 2.5 s drive and ~2.7 s not on gains ~4.7 s every cycle
    text = (ROBOTS / "paper-r1.toml").read_text().replace("min_cooldown_ms = 800", "min_cooldown_ms = 30000")
    text = text.replace("[transitions]", "[transitions]\ndefault_duration_s = 2.5")
    robot = robot_from(tmp_path, text)
    problems = gait_problems(robot, idx(robot, "00", "10", "00", "10", "00"))
    assert [p.kind for p in problems] == ["never-cools"]
    assert "actuator 'sma-left' gains" in problems[0].message


def test_an_on_time_error_the_build_lets_through_says_to_expect_a_fault_not_error_in_a_warning(tmp_path):
    """`proleg build` printed "proleg: warning: gait 0 of +x: error: ... the firmware cuts it"
    and built anyway: a warning that called itself an error."""
    from proleg.firmware.gaits import firmware_gaits, gait_warnings

    text = (ROBOTS / "paper-r1.toml").read_text().replace("min_cooldown_ms = 800", "min_cooldown_ms = 30000")
    robot = robot_from(tmp_path, text.replace("[transitions]", "[transitions]\ndefault_duration_s = 2.5"))
    lines = gait_warnings(robot, firmware_gaits(robot))  # not refused: on-time is an estimate
    faulting = [ln for ln in lines if "expect a fault: " in ln]
    assert faulting and all(("debt" in ln or "gains" in ln) for ln in faulting), lines
    assert not any(": error: " in ln for ln in lines), lines


def test_a_step_the_durations_say_outlasts_the_state_timeout_is_one_expect_a_fault_line_per_gait(tmp_path):
    """R1 whose file says each step takes 0.9 s, with state_timeout_ms = 500: it built without a
    word and the simulated firmware stopped 0.6 s after START (STATE_TIMEOUT). One problem per
    gait names its longest step; without durations, or with the timeout above them, none."""
    from proleg.firmware.gaits import firmware_gaits, gait_warnings
    from proleg.report import SimSession
    from proleg.sim.simulators import open_simulated

    text = (ROBOTS / "paper-r1.toml").read_text()
    assert "state_timeout_ms = 8000" in text and "[transitions]\n" in text
    slow = text.replace("[transitions]\n", "[transitions]\ndefault_duration_s = 0.9\n")
    robot = robot_from(tmp_path, slow.replace("state_timeout_ms = 8000", "state_timeout_ms = 500"))
    problems = [p for p in gait_problems(robot, idx(robot, "00", "10", "11", "01", "00")) if p.kind == "timeout"]
    assert len(problems) == 1 and problems[0].severity == "error"
    assert problems[0].message == (
        "gait 00 10 11 01 00: step 1 (00 -> 10) takes 0.9 s (the robot file's durations) (and 3 more of its steps), "
        "not under safety.state_timeout_ms = 500: the firmware stops it (STATE_TIMEOUT); raise state_timeout_ms "
        "or check the durations")
    lines = gait_warnings(robot, firmware_gaits(robot))  # built, as on-time is: said to expect a fault
    assert [ln.split(": gait ")[0] for ln in lines if "STATE_TIMEOUT" in ln] == \
        ["gait 0 of +x: expect a fault", "gait 0 of -x: expect a fault"], lines
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    report = session.run_gait("+x", 0, 3.0)
    assert [f.code for f in report.faults][:1] == ["STATE_TIMEOUT"], report.faults
    for ok in (slow, text.replace("state_timeout_ms = 8000", "state_timeout_ms = 500")):
        robot = robot_from(tmp_path, ok)
        assert "timeout" not in kinds(robot, "00", "10", "11", "01", "00")


def test_an_entry_step_from_rest_that_outlasts_the_state_timeout_is_a_timeout_problem_too(tmp_path):
    """The firmware's sequencer times the entry path's steps as it times the gait's (seq.c): R1
    whose 00 -> 10 takes 9 s, against state_timeout_ms = 8000, enters gait 10 11 01 by that step
    and stops there (STATE_TIMEOUT), and the check, which timed only the gait's own steps, let it
    through. Entered by a quick step (from 01), or with the gait through 00 and no slow step, none."""
    text = (ROBOTS / "paper-r1.toml").read_text()
    assert "state_timeout_ms = 8000" in text and text.count("  [ 0,  0,  0,  0],\n]\n") == 1
    slow = text.replace("  [ 0,  0,  0,  0],\n]\n", "  [ 0,  0,  0,  0],\n]\n"
                        "durations_s = [[0, 1, 9, 1], [1, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0]]\n")
    robot = robot_from(tmp_path, slow)
    assert entry_path(robot, idx(robot, "10", "11", "01")).states == tuple(idx(robot, "00", "10"))
    problems = [p for p in gait_problems(robot, idx(robot, "10", "11", "01")) if p.kind == "timeout"]
    assert [p.message for p in problems] == [
        "gait 10 11 01 10: its entry from rest's step 00 -> 10 takes 9 s (the robot file's durations), not under "
        "safety.state_timeout_ms = 8000: the firmware stops it (STATE_TIMEOUT); raise state_timeout_ms or check "
        "the durations"] and problems[0].severity == "error"
    assert "timeout" not in kinds(robot, "01", "11", "01")  # entered by 00 -> 01, 1 s
    assert "timeout" not in kinds(robot, "00", "01", "11", "10")


def test_a_gait_through_a_state_the_body_cannot_hold_is_an_unholdable_error_the_build_says_to_expect(tmp_path):
    """inchworm-3 with the middle ψ* at 10°: in 101 the raised tail and head lift the middle pad
    to ≈ 14.6° at their hold peaks, past its 11° edge. Loading warned about the state, but the gaits the firmware
    carries through it (+x gait 1: 001 101 100 ...) were built without a word, and gait 1 ended
    in STATE_TIMEOUT on the nominal plant. Now each such gait is one ``unholdable`` error, which
    the build prints as 'expect a fault' (a model's finding: not refused)."""
    from proleg.firmware.gaits import firmware_gaits, gait_warnings
    from proleg.report import SimSession
    from proleg.sim.simulators import open_simulated

    text = (ROBOTS / "inchworm-3.toml").read_text()
    i = text.index('name = "middle"')
    j = text.index("psi_star_deg = [20.0]", i)
    robot = robot_from(tmp_path, text[:j] + "psi_star_deg = [10.0]" + text[j + len("psi_star_deg = [20.0]"):])
    problems = [p for p in gait_problems(robot, idx(robot, "000", "100", "101", "001", "000")) if p.kind == "unholdable"]
    assert len(problems) == 1 and problems[0].severity == "error", problems
    assert problems[0].message.startswith(
        "gait 000 100 101 001 000: goes to state 101 (step 2), which the simulated body cannot hold: in 101 "
        "'middle' (level 0) sits at 14.6°, past its level-1 edge 11.0° (the warning when the robot file is loaded)")
    assert "unholdable" not in kinds(robot, "000", "100", "110", "111", "011", "001", "000")
    gaits = firmware_gaits(robot)
    through = [k for k, g in enumerate(gaits["+x"]) if robot.transitions.index("101") in g.states]
    assert through and through[0] != 0, through  # gait 0 is not one of them here
    lines = gait_warnings(robot, gaits)
    assert f"gait {through[0]} of +x: expect a fault: " in "\n".join(lines) and \
        sum("cannot hold" in ln for ln in lines) == sum(robot.transitions.index("101") in g.states
                                                         for gs in gaits.values() for g in gs), lines
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    report = session.run_gait("+x", through[0], 20.0)
    assert [f.code for f in report.faults][:1] == ["STATE_TIMEOUT"], report.faults


def _inchworm_middle_held_up() -> str:
    """inchworm-3 with the middle ψ* 12° and hysteresis 8°: 111 -> 101 cannot end."""
    text = (ROBOTS / "inchworm-3.toml").read_text()
    i = text.index('name = "middle"')
    j = text.index("psi_star_deg = [20.0]", i)
    k = text.index("hysteresis_deg = 2.0", i)
    return (text[:j] + "psi_star_deg = [12.0]" + text[j + len("psi_star_deg = [20.0]"):k] + "hysteresis_deg = 8.0"
            + text[k + len("hysteresis_deg = 2.0"):])


def test_a_gait_through_a_step_the_body_cannot_end_is_a_blocked_error_the_build_says_to_expect(tmp_path):
    """inchworm-3 with the middle ψ* 12° and hysteresis 8°: in 101 the tail and head, held at
    their hold edges (25°), keep the middle pad at ≈ 13°, inside its band (8..16°) and more
    than 2° above its lower edge, where the firmware's rule for a limb held up on its way down
    does not look, so 111 -> 101 never reads 101 (on the physical plant it sat at 12.7–14.2°).
    The load check warned about the transition, but the gaits through it (+x gait 4: 100 110
    111 101 100) were built without a word and ended in STATE_TIMEOUT. Now each such gait is
    one ``blocked`` error, which the build prints as 'expect a fault'."""
    from proleg.firmware.gaits import firmware_gaits, gait_warnings
    from proleg.report import SimSession
    from proleg.sim.simulators import open_simulated

    robot = robot_from(tmp_path, _inchworm_middle_held_up())
    assert list(robot.blocked) == [tuple(idx(robot, "111", "101"))]
    problems = [p for p in gait_problems(robot, idx(robot, "100", "110", "111", "101", "100")) if p.severity == "error"]
    assert [p.kind for p in problems] == ["blocked"], problems
    assert problems[0].message.startswith(
        "gait 100 110 111 101 100: makes the step 111 -> 101 (step 3), which the simulated body cannot end: in 101 "
        "the raised "
        "limbs hold 'middle' at 13.0°, above its level-0 edge 8.0°"), problems[0].message
    assert "blocked" not in kinds(robot, "000", "100", "110", "111", "011", "001", "000")
    gaits = firmware_gaits(robot)
    through = [k for k, g in enumerate(gaits["+x"]) if any(
        (int(a), int(b)) in robot.blocked for a, b in zip(g.states, [*g.states[1:], g.states[0]]))]
    assert through and through[0] != 0, through
    assert f"gait {through[0]} of +x: expect a fault: " in "\n".join(gait_warnings(robot, gaits))
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    report = session.run_gait("+x", through[0], 20.0)
    assert [f.code for f in report.faults][:1] == ["STATE_TIMEOUT"], report.faults


def test_the_entry_path_from_rest_uses_only_allowed_transitions_the_hardware_can_make(tmp_path):
    robot = robot_from(tmp_path, ONE_ACTUATOR)
    # gait 01 11 01: 00 -> 10 -> 01 is shorter to 01 but lowers 'front' while raising 'back'
    # on one coil; 00 -> 10 -> 11 enters at the gait's second state
    path = entry_path(robot, idx(robot, "01", "11", "01"))
    assert path.states == tuple(idx(robot, "00", "10", "11")) and path.gait_step == 1
    assert path.transitions == 2
    one = load_robot(ROBOTS / "paper-r1-one-actuator.toml")
    assert entry_path(one, idx(one, "10", "11", "10")).states == tuple(idx(one, "00", "10"))


def test_a_gait_unreachable_from_rest_is_an_error_naming_it(tmp_path):
    text = ONE_ACTUATOR.replace('matrix = [[0, "x", 1, "x"]', 'matrix = [[0, "x", "x", "x"]')
    robot = robot_from(tmp_path, text)
    with pytest.raises(GaitError, match=r"^gait 01 11 01: no allowed path from the rest state 00 into the gait"):
        entry_path(robot, idx(robot, "01", "11", "01"))
    assert "no-entry" in kinds(robot, "01", "11", "01")


FOUR_SHARED = Path(__file__).parent / "fixtures" / "four-shared.toml"  # p1,p2 on coil1; p3,p4 on coil2


def _shared(robot, walk: str) -> list[str]:
    return [p.message for p in gait_problems(robot, robot.transitions.sequence(walk)) if p.kind == "shared-actuator"]


def test_raising_the_far_limb_of_a_shared_coil_alone_is_a_shared_actuator_error():
    # eight-shared's gait 0 raised p4 alone: coil2 lifts p3 first, nothing moved on the sim and
    # the firmware blamed the healthy coil (SMA_ON_LIMIT, STATE_TIMEOUT, "gave up coil2")
    robot = load_robot(FOUR_SHARED)
    assert _shared(robot, "0000,0001,0000") == [
        "gait 0000 0001 0000: step 1 (0000 -> 0001) raises 'p4' but not 'p3', which share actuator 'coil2': "
        "holding 'p4' up, it lifts 'p3' too on the simulated body, so state 0001 cannot be held (the warning "
        "when the robot file is loaded; mark the transitions into it \"x\")"]
    with pytest.raises(GaitError, match="goes to state 0001 .* 'p4' needs"):  # the first error: unreachable too
        check_gait(robot, robot.transitions.sequence("0000,0001,0000"))


def test_lowering_the_near_limb_of_a_shared_coil_alone_is_a_shared_actuator_error():
    robot = load_robot(FOUR_SHARED)
    [msg] = _shared(robot, "0000,0010,0011,0001,0000")
    assert "step 3 (0011 -> 0001) lowers 'p3' but not 'p4', which share actuator 'coil2'" in msg


def test_the_near_limb_of_a_shared_coil_may_rise_and_fall_alone_as_the_body_model_holds_it():
    # consistent with the load check (coupled_states): the coil lifts its near limb p3 first,
    # so 0010 can be held and 0000 -> 0010 -> 0011 -> 0010 -> 0000 is the coil's own order
    robot = load_robot(FOUR_SHARED)
    assert 0b0010 not in robot.coil_lifts and 0b0001 in robot.coil_lifts
    assert _shared(robot, "0000,0010,0011,0010,0000") == []
    one = load_robot(ROBOTS / "paper-r1-one-actuator.toml")
    assert _shared(one, "00,10,11,10,00") == []


def test_the_entry_path_avoids_a_step_the_shared_coil_cannot_make():
    """0000 -> 0001 raises p4 alone (a shared-actuator error), and 0011 is unreachable anyway:
    coil2 at full stroke bends its far limb p4 to 17.2° (the physical plant, coil2 on for 6 s:
    ψ = 0, 8.2, 31.6, 17.2°), short of 21°. The way into 0010 is the near limb's own."""
    robot = load_robot(FOUR_SHARED)
    path = entry_path(robot, robot.transitions.sequence("0010,1010,0010"))
    assert [robot.transitions.label(s) for s in path.states] == ["0000", "0010"]
    assert robot.transitions.index("0011") in robot.unreachable
    with pytest.raises(GaitError, match="no allowed path from the rest state 0000"):
        entry_path(robot, robot.transitions.sequence("0011,0111,0011"))


CRAB = Path(__file__).parent / "fixtures" / "crab-3-entry.toml"  # 010, 011, 020, 021 cannot be held


def test_the_entry_path_keeps_out_of_states_the_body_cannot_hold_where_it_can():
    """The shortest way into 120 121 120 was 000 -> 010 -> 020 -> 120, through two states the
    load check warns the body cannot hold: the firmware follows it and stopped in STATE_TIMEOUT
    (110 -> 020, the back pad lifted) before the gait began, while `proleg gait` listed the gait
    without a word. 000 -> 100 -> 110 -> 120 is as short and holdable."""
    robot = load_robot(CRAB)
    assert {robot.transitions.index(s) for s in ("010", "020")} <= set(robot.unholdable)
    path = entry_path(robot, robot.transitions.sequence("120,121,120"))
    assert [robot.transitions.label(s) for s in path.states] == ["000", "100", "110", "120"]
    assert gait_problems(robot, robot.transitions.sequence("120,121,120")) == []


def test_an_entry_path_only_through_states_the_body_cannot_hold_is_an_unholdable_error(tmp_path):
    text = CRAB.read_text(encoding="utf-8").replace('allow = "one-level"',
                                                   'allow = "one-level"\nforbidden = ["000->100", "000->001"]')
    robot = robot_from(tmp_path, text)
    walk = robot.transitions.sequence("120,121,120")
    path = entry_path(robot, walk)  # no other way in: the shortest, as before
    assert [robot.transitions.label(s) for s in path.states] == ["000", "010", "020", "120"]
    [p] = [p for p in gait_problems(robot, walk) if p.kind == "unholdable"]
    assert p.severity == "error"
    assert p.message.startswith("gait 120 121 120: its entry from rest (000 010 020 120) goes to states 010, 020, "
                                "which the simulated body cannot hold, and there is no other way in: in 010 "
                                "'back' (level 0) sits at"), p.message


def test_an_entry_path_only_through_a_step_the_body_cannot_end_is_a_blocked_error_worded_as_the_gaits(tmp_path):
    """The gait 101 001 101 is clean, but with 000 -> 001, 100 -> 101 and 011 -> 001 forbidden
    every way in ends with 111 -> 101, which cannot end: the error names the entry as the
    unholdable one does (its count of the steps past three was "and more", without a number)."""
    text = _inchworm_middle_held_up()
    for row, fixed in (('[  0,  -3,   0, "x",   3,', '[  0, "x",   0, "x",   3,'),
                       ('[ -3, "x", "x", "x",   0,  -3,', '[ -3, "x", "x", "x",   0, "x",'),
                       ('["x",   3,   3,   0,', '["x", "x",   3,   0,')):
        text = text.replace(row, fixed)
    robot = robot_from(tmp_path, text)
    walk = robot.transitions.sequence("101,001,101")
    assert [robot.transitions.label(s) for s in entry_path(robot, walk).states] == ["000", "010", "011", "111", "101"]
    [p] = [p for p in gait_problems(robot, walk) if p.severity == "error"]
    assert p.kind == "blocked" and p.message.startswith(
        "gait 101 001 101: its entry from rest (000 010 011 111 101) makes the step 111 -> 101, which the simulated "
        "body cannot end, and there is no other way in: in 101 the raised limbs hold 'middle' at 13.0°"), p.message


def _inchworm_middle_on_the_tail_coil(tmp_path: Path):
    """inchworm-3 with its middle limb named on the tail's coil (a lab wiring two limbs to one
    coil): in the model the coil sits at the tail and bends the middle to 8.1° alone."""
    text = (ROBOTS / "inchworm-3.toml").read_text(encoding="utf-8")
    text = (text.replace('actuator = "sma-middle"', 'actuator = "sma-tail"')
                .replace('[[actuator]]\nname = "sma-middle"\nchannel = 1\n\n', '')
                .replace('name = "sma-head"\nchannel = 2', 'name = "sma-head"\nchannel = 1'))
    assert text.count("sma-middle") == 0
    return robot_from(tmp_path, text)


def test_a_state_a_raised_limb_cannot_reach_is_an_unreachable_error(tmp_path):
    """The build chose 100 110 111 101 100 as gait 0 (no shared coil moves its limbs apart in
    it) and the firmware faulted 3.6 s into the simulation (SMA_ON_LIMIT, then STATE_TIMEOUT on
    'middle'): the middle limb, on the tail's coil, gets 8.1° alone and 16.2° with every coil
    hot, short of its 21° entry edge. Every state with the middle raised is unreachable, and a
    gait stepping into one is an error that names the limb and the angles."""
    robot = _inchworm_middle_on_the_tail_coil(tmp_path)
    middle_up = {s for s in range(robot.transitions.n_states) if (s >> 1) & 1}
    assert set(robot.unreachable) == middle_up
    for s in middle_up:
        [(limb, got, need)] = robot.unreachable[s]
        assert robot.limbs[limb].name == "middle" and got < need == pytest.approx(21.0)
    [problem] = [p for p in gait_problems(robot, robot.transitions.sequence("100,110,111,101,100"))
                 if p.kind == "unreachable"]
    assert problem.severity == "error" and problem.message == (
        "gait 100 110 111 101 100: goes to states 110 (step 1), 111 (step 2), which the robot cannot reach "
        "on the simulated body (every raised limb's coil at full stroke): in 110 'middle' needs ψ ≥ 21.0° and "
        "gets at most 8.1° (the warning when the robot file is loaded)")
    assert kinds(robot, "000", "100", "101", "001") == []  # the tail and head alone: reachable


def test_the_build_does_not_make_a_gait_with_an_unreachable_state_gait_0(tmp_path):
    """Every optimal gait of the wiring above needs the middle limb up: the firmware carries none
    of them (instead of firmware that faults within seconds), and the build says why; it used to
    refuse the robot, which left a lab no way to learn its matrix or load a gait of its own."""
    from proleg.firmware.gaits import firmware_gaits, gait_warnings

    robot = _inchworm_middle_on_the_tail_coil(tmp_path)
    fw = firmware_gaits(robot)
    assert fw["+x"] == () and fw["-x"] == ()
    lines = gait_warnings(robot, fw)
    assert len(lines) == 2 and lines[0].startswith("+x: none of its optimal gaits can run on this robot")
    assert "which the robot cannot reach" in lines[0] and "'middle' needs" in lines[0]
    assert "the firmware carries no +x gait (START +x is refused: NACK NO_GAIT)" in lines[0]


def test_a_library_gait_the_hardware_cannot_make_is_still_refused(tmp_path):
    """A direction left out is refilled by a library entry the user asked for: when that one
    cannot be made either, the build refuses it as before (the user asked for it)."""
    from proleg.errors import BuildError
    from proleg.firmware.gaits import FirmwareGaits, GaitSelection, gait_warnings
    from types import SimpleNamespace

    robot = _inchworm_middle_on_the_tail_coil(tmp_path)
    states = robot.transitions.sequence("100,110,111,101,100")
    fw = FirmwareGaits({"+x": (SimpleNamespace(states=tuple(states)),), "-x": ()}, GaitSelection("total", None))
    with pytest.raises(BuildError, match=r"gait 0 of \+x, the one START runs, cannot run on this robot: .*"
                                         r"which the robot cannot reach .* 'middle' needs"):
        gait_warnings(robot, fw)


def test_no_bundled_robot_has_an_unreachable_state():
    for path in sorted(ROBOTS.glob("*.toml")):
        assert load_robot(path).unreachable == {}, path.name


def test_the_fallbacks_leave_out_the_states_the_robot_cannot_reach(tmp_path):
    """Without sma-head the fallback of the wiring above was 000 -> 100 -> 110 -> 010 -> 000,
    through 110 and 010, which the middle limb (on the tail's coil) cannot reach."""
    from proleg.limbloss import dead_table, remap, remapped_table

    robot = _inchworm_middle_on_the_tail_coil(tmp_path)
    head = [a.name for a in robot.actuators].index("sma-head")
    tables = [dead_table(robot, head)]
    if (new_map := remap(robot, head)) is not None:
        tables.append(remapped_table(robot, new_map, head))
    for t in tables:
        entered = {int(s) for s in t.src} | {int(d) for d in t.dst}
        assert entered and not entered & set(robot.unreachable), sorted(entered & set(robot.unreachable))


def test_a_limb_that_passes_its_level_on_the_way_is_not_called_unreachable(tmp_path):
    """R1 with a soft body (working_strain 0.12) and ψ* 86°: both coils at full stroke turn it
    197° in all, read as −16.7° at its ends, and 11 was 'unreachable: gets at most −16.7°',
    though both ends pass 87° on the way there. The reach is the most along the way."""
    from build_checks import robot_variant

    r1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"
    soft = robot_variant(tmp_path, r1, (r"psi_star_deg = \[20.0\]", "psi_star_deg = [86.0]"),
                         (r"psi_star_deg = \[20.0\]", "psi_star_deg = [86.0]"),
                         (r"\Z", "\n[plant]\nworking_strain = 0.12\n"))
    robot = load_robot(soft)
    assert robot.transitions.index("11") not in robot.unreachable
    stiff = robot_variant(tmp_path / "stiff", r1, (r"psi_star_deg = \[20.0\]", "psi_star_deg = [86.0]"))
    [(_, got, need)] = [u for u in load_robot(stiff).unreachable[load_robot(stiff).transitions.index("10")]]
    assert 0.0 < got < need  # a body that does not bend so far: still unreachable, with what it gets
