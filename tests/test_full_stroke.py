"""Full strokes (robot file ``[[limb]] stroke_deg``): how far the controller raises a limb on its
top level. The robot file, the rendered firmware, the idealised drive, and the firmware walking
R1's body held at full strokes on the physical plant, learn-then-walk: the matrix the simulator
measures for a pair of strokes says which way the robot goes, and the firmware goes that way
(docs/control.md, "Full strokes")."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from proleg.errors import RobotFileError
from proleg.firmware.render import render_config
from proleg.report import SimSession
from proleg.robot import load_robot, stroke_leads
from proleg.sim.physical import PhysicalPlant
from proleg.sim.physical.measure import IdealDrive, measure_matrix
from proleg.sim.simulators import open_simulated

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
R1 = ROBOTS / "paper-r1.toml"
STROKE = ROBOTS / "paper-r1-stroke.toml"
SIM_BOARD = {"name": "host-sim", "family": "sim", "pwm_channels": ["SIM0", "SIM1"],
             "i2c": {"hz": 400000, "imu_addresses": [0x68, 0x69]}, "uart_baud": 115200, "clock_hz": 0}


def with_strokes(tmp_path: Path, left: object, right: object, matrix: str | None = None) -> Path:
    """paper-r1-stroke.toml with other strokes (None: the key left out) and, if given, another
    [transitions] matrix."""
    text = STROKE.read_text(encoding="utf-8")
    lines = []
    strokes = iter([left, right])
    for line in text.splitlines():
        if line.startswith("stroke_deg"):
            value = next(strokes)
            if value is None:
                continue
            line = f"stroke_deg = {value}"
        lines.append(line)
    text = "\n".join(lines) + "\n"
    if matrix is not None:
        text = re.sub(r"matrix = \[\n(.*\n)*?\]\n", f"matrix = {matrix}\n", text)
    path = tmp_path / "r1-strokes.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_stroke_deg_is_read_per_limb_and_absent_means_none(tmp_path):
    robot = load_robot(STROKE)
    assert [lb.stroke_deg for lb in robot.limbs] == [76.0, 72.0]
    assert [lb.stroke_deg for lb in load_robot(R1).limbs] == [None, None]
    assert [lb.stroke_deg for lb in load_robot(with_strokes(tmp_path, 70, None)).limbs] == [70.0, None]


RANGE = ("expected an angle from 26 (1° above where it is held without one: psi* + hysteresis/2 + "
         "control.hold_margin_deg) to 85 degrees")


@pytest.mark.parametrize("value, expected", [
    ("25.9", f"{RANGE}, got 25.9"),    # not above the hold edge's band (ψ* + h/2 + 4° = 25°)
    ("-12", f"{RANGE}, got -12"),
    ("85.5", f"{RANGE}, got 85.5"),    # the hold band above it would pass 89°
    ('"full"', "expected a number, got 'full'"),
    ("true", "expected a number, got true"),  # as written in the file, not Python's True
    ("nan", "expected a finite number, got nan"),  # "a number, got nan" read as nonsense
])
def test_a_stroke_outside_its_range_is_a_one_line_error_naming_the_limb(tmp_path, value, expected):
    path = with_strokes(tmp_path, value, 72)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: limb 'left': stroke_deg: {expected}"


@pytest.mark.parametrize("extra, expected", [
    ('stroke_fall_lead = "middle"', ("control.stroke_fall_lead: expected the name of a limb with a stroke_deg "
                                     "(left, right), got 'middle'")),
    ('stroke_rise_lead = 3', "control.stroke_rise_lead: expected a string, got 3"),
])
def test_a_stroke_lead_that_is_not_a_limb_with_a_stroke_is_a_one_line_error(tmp_path, extra, expected):
    path = with_strokes(tmp_path, 76, 72)
    path.write_text(path.read_text(encoding="utf-8").replace("hold_ms = 100\n", f"hold_ms = 100\n{extra}\n"))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: {expected}"
    r1 = tmp_path / "r1.toml"
    r1.write_text(R1.read_text(encoding="utf-8").replace("hold_ms = 100\n", 'hold_ms = 100\nstroke_rise_lead = "left"\n'))
    with pytest.raises(RobotFileError, match="no \\[\\[limb\\]\\] has a stroke_deg to lead with"):
        load_robot(r1)


def test_the_leads_default_to_the_largest_stroke_up_and_none_down(tmp_path):
    assert stroke_leads(load_robot(STROKE).limbs, load_robot(STROKE).control) == (0, None)
    robot = load_robot(with_strokes(tmp_path, 70, 74))
    assert stroke_leads(robot.limbs, robot.control) == (1, None)
    robot = load_robot(with_strokes(tmp_path, 74, 74))
    assert stroke_leads(robot.limbs, robot.control) == (0, None)   # a tie: the first limb
    assert stroke_leads(load_robot(R1).limbs, load_robot(R1).control) is None


def test_the_firmware_carries_a_stroke_table_only_when_a_limb_has_a_stroke(tmp_path):
    gaits = {"+x": [], "-x": []}
    plain = render_config(load_robot(R1), gaits, SIM_BOARD)["robot_config.h"]
    assert "CFG_LIMB_STROKE_CDEG" not in plain  # the paper's R1 builds exactly as before
    both = render_config(load_robot(STROKE), gaits, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_LIMB_STROKE_CDEG { 7600, 7200 }" in both
    assert "#define CFG_STROKE_RISE_LEAD 0u" in both and "CFG_STROKE_FALL_LEAD" not in both
    one = render_config(load_robot(with_strokes(tmp_path, 70.25, None)), gaits, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_LIMB_STROKE_CDEG { 7025, PSI_NO_STROKE }" in one


def test_the_ideal_drive_follows_the_firmwares_stroke_rules():
    """The rise lead (the left: the larger stroke) crosses ψ* first, then they climb in step
    (shares of the climb from the band's upper edge 21°: left (ψ − 21) / 55, right / 51)."""
    robot = load_robot(STROKE)
    plant = PhysicalPlant(robot)
    drive = IdealDrive(robot, plant, 4.0)
    eleven = robot.transitions.labels().index("11")
    assert drive.command([5.0, 15.0], eleven) == [1, 0]     # the right waits for the rise lead to cross
    assert drive.command([21.5, 15.0], eleven) == [1, 1]    # crossed (1 %): both climb
    assert drive.command([25.0, 15.0], eleven) == [0, 1]    # 7 % ahead of a limb at 0: waits for it
    assert drive.command([60.0, 60.0], eleven) == [1, 0]    # 71 % against 76 %: the right waits
    assert drive.command([75.5, 40.0], eleven) == [0, 1]    # 99 % against 37 %
    assert drive.command([76.5, 72.5], eleven) == [0, 0]    # at both strokes: held
    assert drive.command([30.0, 30.0], 0) == [-1, -1]


def test_the_ideal_drive_holds_the_others_until_the_fall_lead_is_halfway_down(tmp_path):
    path = with_strokes(tmp_path, 76, 72)
    path.write_text(path.read_text(encoding="utf-8").replace("hold_ms = 100\n", 'hold_ms = 100\nstroke_fall_lead = "right"\n'))
    robot = load_robot(path)
    drive = IdealDrive(robot, PhysicalPlant(robot), 4.0)
    assert drive.command([75.0, 72.5], 0, 0.002) == [1, -1]    # the left held at its stroke (76°)
    assert drive.command([76.5, 50.0], 0, 0.002) == [0, -1]    # the lead 57 % up its climb: still held
    assert drive.command([75.0, 40.0], 0, 0.002) == [-1, -1]   # 37 %: past halfway down, both fall
    assert drive.command([75.0, 72.5], 3, 0.002) == [1, 0]     # another step ...
    for _ in range(1100):                                       # ... and a lead that never comes down
        cmd = drive.command([75.0, 72.5], 0, 0.002)
    assert cmd == [-1, -1]                                      # held for at most 2 s


@pytest.mark.parametrize("left, right", [(76, 72), (72, 76), (66, 76)])
def test_learn_then_walk_on_full_strokes_goes_the_way_the_measured_matrix_says(tmp_path, left, right):
    """Only 00 and 11 can be held at full strokes (either end at its stroke lifts the other past
    ψ* through the body); the measured 00 → 11 → 00 decides the direction. The firmware walks
    each steady cycle that way, within the hil band of the measured sum (0.45..1.75 ×)."""
    robot = load_robot(with_strokes(tmp_path, left, right))
    m = measure_matrix(robot)
    labels = robot.transitions.labels()
    zero, eleven = labels.index("00"), labels.index("11")
    reached = {(a, b) for a in range(4) for b in range(4) if m.samples[a, b] > 0}
    assert reached == {(zero, eleven), (eleven, zero)}, m.samples
    per_cycle = float(m.matrix_mm[zero, eleven] + m.matrix_mm[eleven, zero])
    assert abs(per_cycle) > 5.0, per_cycle
    direction = "+x" if per_cycle > 0 else "-x"
    sign = 1 if per_cycle > 0 else -1
    cells = [["x"] * 4 for _ in range(4)]
    for a in range(4):
        cells[a][a] = "0"
    cells[zero][eleven] = f"{m.matrix_mm[zero, eleven]:.2f}"
    cells[eleven][zero] = f"{m.matrix_mm[eleven, zero]:.2f}"
    matrix = "[" + ", ".join("[" + ", ".join(c if c[0] != "x" else '"x"' for c in row) + "]" for row in cells) + "]"
    learned = load_robot(with_strokes(tmp_path, left, right, matrix))
    session = SimSession(open_simulated(learned))
    session.advance(0.2)
    run = session.run_gait(direction, 0, 25.0)
    assert run.faults == [] and run.errors == []
    steady = run.cycle_displacements_mm[1:]   # the first cycle starts from a cold robot
    assert len(steady) >= 3, run.cycle_displacements_mm
    for d in steady:
        assert 0.45 * abs(per_cycle) <= sign * d <= 1.75 * abs(per_cycle), (run.cycle_displacements_mm, per_cycle)


def _walk_tracking_psi(robot, direction: str = "+x", seconds: float = 25.0):
    """The firmware walking gait 0; also the highest true ψ of each limb over the run."""
    sim = open_simulated(robot)
    highest = [-90.0] * len(robot.limbs)
    step = sim.step

    def stepping() -> None:
        step()
        for i, p in enumerate(sim.plant.psi_deg):
            highest[i] = max(highest[i], float(p))

    sim.step = stepping
    session = SimSession(sim)
    session.advance(0.2)
    return session.run_gait(direction, 0, seconds), highest


def test_a_limb_is_raised_to_its_stroke_and_one_out_of_reach_as_far_as_it_goes(tmp_path):
    """76°/72°: each limb gets to its stroke. 84° is past what R1's left coil bends its end to
    (about 80°): the firmware keeps heating while the limb still climbs (it is not 'hovering'
    then), settles where it stops (150 ms without a 0.5° gain: within 3° of the end, where the
    climb has slowed), and the robot walks on."""
    run, highest = _walk_tracking_psi(load_robot(STROKE))
    assert run.faults == [] and highest[0] >= 76.0 and highest[1] >= 72.0, highest
    run, highest = _walk_tracking_psi(load_robot(with_strokes(tmp_path, 84, 72)))
    assert run.faults == [] and run.errors == []
    assert 77.0 <= highest[0] < 84.0, highest
    steady = run.cycle_displacements_mm[1:]
    assert len(steady) >= 3 and all(d > 5.0 for d in steady), run.cycle_displacements_mm


def test_a_fall_lead_makes_r2s_pads_ratchet(tmp_path):
    """R2's pads (D2: hard below ψ*, soft above) need the same end to lead on the way up and on
    the way down: with strokes 72°/76° the right end crosses ψ* first (the larger stroke); only
    with control.stroke_fall_lead = "right" does it also go down first, and the robot walks."""
    text = (R1.parent / "paper-r2.toml").read_text(encoding="utf-8")
    text = text.replace('actuator = "sma-left"\n', 'actuator = "sma-left"\nfriction = "D2"\nstroke_deg = 72\n', 1)
    text = text.replace('actuator = "sma-right"\n', 'actuator = "sma-right"\nfriction = "D2"\nstroke_deg = 76\n', 1)
    text = text.replace("drive_duty = 0.6", "drive_duty = 0.8")
    text = re.sub(r"matrix = \[\n(.*\n)*?\]\n", 'matrix = [[0, "x", "x", 1], ["x", 0, "x", "x"], ["x", "x", 0, "x"], '
                  '[1, "x", "x", 0]]\n', text)
    cycles = {}
    for name, extra in (("unordered", ""), ("fall lead", 'stroke_fall_lead = "right"\n')):
        path = tmp_path / f"{name.replace(' ', '-')}.toml"
        path.write_text(text.replace("hold_ms = 100\n", f"hold_ms = 100\n{extra}"), encoding="utf-8")
        run, _ = _walk_tracking_psi(load_robot(path), seconds=30.0)
        assert run.faults == [] and run.errors == []
        cycles[name] = run.cycle_displacements_mm[1:]
    assert all(abs(d) < 1.0 for d in cycles["unordered"]), cycles
    assert len(cycles["fall lead"]) >= 3 and all(d > 4.0 for d in cycles["fall lead"]), cycles


def test_the_example_robots_matrix_is_what_the_simulator_measures():
    """robots/paper-r1-stroke.toml's matrix is the learned one (rounded to 0.1 mm)."""
    robot = load_robot(STROKE)
    m = measure_matrix(robot)
    table, allowed = robot.transitions.dense()
    measured = np.where(np.isfinite(m.matrix_mm), m.matrix_mm, 0.0)
    assert np.array_equal(np.asarray(allowed, dtype=bool), np.isfinite(m.matrix_mm))
    assert np.allclose(np.where(allowed, table, 0.0), measured, atol=0.1)


def test_states_a_stroke_makes_unholdable_are_warned_about_at_load(tmp_path, caplog):
    """The coupling check held raised limbs at ψ* + the hold margin, not at their strokes: R1's
    body at full strokes with the paper's matrix (10 and 01 allowed) loaded without a word, and
    its gait 0 (00 10 11 01 00) stopped at once with STATE_TIMEOUT on the nominal robot."""
    import logging

    paper = "[[0, -1, 1, \"x\"], [1, 0, \"x\", -1], [-1, \"x\", 0, 1], [\"x\", 1, -1, 0]]"
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(with_strokes(tmp_path, 76.0, 72.0, paper))
    held = [r.getMessage() for r in caplog.records if "cannot be held" in r.getMessage()]
    assert len(held) == 2 and "state 01: limb 'left'" in held[0] and "state 10: limb 'right'" in held[1]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(with_strokes(tmp_path, None, None, paper))  # held just past psi*: both states hold
        load_robot(STROKE)  # its own matrix enters only 00 and 11
    assert not [r for r in caplog.records if "cannot be held" in r.getMessage()]


def test_the_ideal_drives_copies_of_the_firmwares_stroke_constants_agree_with_it():
    """drive.py follows core/ctl.h's stroke rules with its own copies of their constants (and
    psi.h's progress edges, for the lag watch): a change on one side only would make the
    idealised drive, and the claim bench's "physically possible", judge another controller."""
    from proleg.sim.physical import drive

    core = ROBOTS.parent / "firmware_templates" / "core"
    text = (core / "ctl.h").read_text() + (core / "psi.h").read_text()

    def define(name: str) -> str:
        return re.search(rf"#define {name} (.+)", text)[1].strip()

    def number(name: str) -> int:
        return int(define(name).rstrip("u"))

    assert drive.CLIMB_MAX_S == number("CTL_CLIMB_MAX_MS") / 1000
    assert drive.CLIMB_STOP_S == number("CTL_CLIMB_STOP_MS") / 1000
    assert drive.HOVER_S == number("CTL_HOVER_MS") / 1000
    assert drive.CLIMB_GAIN_DEG == number("CTL_CLIMB_GAIN_CDEG") / 100
    assert drive.FALL_WAIT_S == number("CTL_FALL_WAIT_MS") / 1000
    assert drive.LAG_S == number("CTL_LAG_MS") / 1000
    assert drive.SHARE_SYNC == number("CTL_SHARE_SYNC") / number("CTL_SHARE_FULL")
    assert drive.FALL_SHARE == number("CTL_FALL_SHARE") / number("CTL_SHARE_FULL")
    edges = [int(x) for x in define("PSI_PROGRESS_CDEG").strip("{}").split(",")]
    assert [e * 100 for e in drive.PROGRESS_DEG] == edges


def test_the_table_plant_takes_a_staggered_stroke_step_as_the_matrix_transition_it_is(tmp_path):
    """The rise lead crosses first on purpose (00 -> 10 -> 11, 00 -> 10 forbidden): the table
    plant counted two unexpected transitions and 0 mm, so `sim --plant table` walked R1 at full
    strokes 12.0 mm a cycle against the matrix's 25.1, and `learn --sim` learned 00 -> 11 as 0."""
    from proleg.firmware.gaits import firmware_gaits
    from proleg.sim.closed_loop import SimulatedRobot

    robot = load_robot(STROKE)
    session = SimSession(SimulatedRobot(robot, plant="table"))
    session.advance(0.2)
    run = session.run_gait("+x", 0, 20.0)
    assert run.faults == [] and len(run.cycle_displacements_mm) >= 3, run
    states = firmware_gaits(robot)["+x"][0].states
    promised = sum(robot.transitions.dense()[0][a, b] for a, b in zip(states, states[1:]))
    assert promised > 20.0
    assert run.cycle_displacements_mm == pytest.approx([promised] * len(run.cycle_displacements_mm))
    assert run.unexpected_transitions == 0


@pytest.mark.parametrize("body", ["", "working_strain = 0.058\n"])
def test_a_stroke_out_of_reach_in_a_state_the_matrix_enters_is_one_warning_line(tmp_path, caplog, body):
    """inchworm-3's middle limb raised alone bends to ≈ 31° on its 80 mm body: a stroke_deg of 40
    loaded without a word (only hold tops were checked against the reach), and the firmware heated
    that coil toward 40° at every raise until the limb stopped short (fric-3-like robot: 106 °C
    against 78 °C with a stroke in reach). One line names the limb, the state and the stroke that
    fits; with that stroke, none. A stiffer body (working_strain 0.058) reaches 30.1°: the stroke
    that fits, 29.56°, was advised rounded up to 29.6, and that stroke was warned of again."""
    import logging

    text = (ROBOTS / "inchworm-3.toml").read_text(encoding="utf-8")
    assert text.count('actuator = "sma-middle"\n') == 1 and text.rstrip().splitlines()[-1].startswith("cross_gain")
    path = tmp_path / "worm.toml"

    def warnings(stroke: float) -> list[str]:
        path.write_text(text.replace('actuator = "sma-middle"\n', f'actuator = "sma-middle"\nstroke_deg = {stroke}\n')
                        + body, encoding="utf-8")
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="proleg"):
            load_robot(path)
        return [r.getMessage() for r in caplog.records if "stroke_deg" in r.getMessage()]

    lines = warnings(40.0)
    assert len(lines) == 1, lines
    assert f"{path}: limb 'middle': stroke_deg 40° is out of reach in state 010" in lines[0], lines
    reach = float(lines[0].split("bends it to ")[1].split("°")[0])
    assert 28.0 < reach < 34.0, lines
    fits = float(lines[0].split("set stroke_deg to at most ")[1].split(",")[0])
    assert fits == pytest.approx(reach - 0.5, abs=0.16)  # reach to the nearest tenth, the fit to the one below
    assert warnings(fits) == []
