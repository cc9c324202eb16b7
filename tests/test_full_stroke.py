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
from proleg.robot import load_robot
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


RANGE = "expected an angle above the top band's upper edge psi* + hysteresis/2 = 21 and at most 85 degrees"


@pytest.mark.parametrize("value, expected", [
    ("21.0", f"{RANGE}, got 21.0"),    # at the band's upper edge: nothing to climb
    ("12", f"{RANGE}, got 12.0"),
    ("85.5", f"{RANGE}, got 85.5"),    # the hold band above it would pass 89°
    ('"full"', "expected a number, got 'full'"),
    ("true", "expected a number, got True"),
])
def test_a_stroke_outside_its_range_is_a_one_line_error_naming_the_limb(tmp_path, value, expected):
    path = with_strokes(tmp_path, value, 72)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: limb 'left': stroke_deg: {expected}"


def test_the_firmware_carries_a_stroke_table_only_when_a_limb_has_a_stroke(tmp_path):
    gaits = {"+x": [], "-x": []}
    plain = render_config(load_robot(R1), gaits, SIM_BOARD)["robot_config.h"]
    assert "CFG_LIMB_STROKE_CDEG" not in plain  # the paper's R1 builds exactly as before
    both = render_config(load_robot(STROKE), gaits, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_LIMB_STROKE_CDEG { 7600, 7200 }" in both
    one = render_config(load_robot(with_strokes(tmp_path, 70.25, None)), gaits, SIM_BOARD)["robot_config.h"]
    assert "#define CFG_LIMB_STROKE_CDEG { 7025, 0 }" in one


def test_the_ideal_drive_raises_to_the_strokes_the_larger_stroke_crossing_first():
    robot = load_robot(STROKE)
    plant = PhysicalPlant(robot)
    drive = IdealDrive(robot, plant, 4.0)
    eleven = robot.transitions.labels().index("11")
    assert drive.command([5.0, 15.0], eleven) == [1, 0]     # the right waits for the left to cross
    assert drive.command([25.0, 15.0], eleven) == [1, 1]    # crossed: both climb
    assert drive.command([75.0, 40.0], eleven) == [1, 1]    # short of its stroke (76°): heats on
    assert drive.command([76.5, 72.5], eleven) == [0, 0]    # at both strokes: held
    assert drive.command([30.0, 30.0], 0) == [-1, -1]


@pytest.mark.parametrize("left, right", [(76, 72), (66, 76)])
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
    first, *steady = run.cycle_displacements_mm
    assert len(steady) >= 3, run.cycle_displacements_mm
    for d in steady:
        assert 0.45 * abs(per_cycle) <= sign * d <= 1.75 * abs(per_cycle), (run.cycle_displacements_mm, per_cycle)


def test_a_stroke_beyond_the_coils_reach_is_held_where_the_limb_stops_climbing(tmp_path):
    """84° is past what R1's left coil bends its end to (about 80°): the firmware does not wait
    for it for ever, it settles where the limb stops climbing, and the robot walks on."""
    robot = load_robot(with_strokes(tmp_path, 84, 72))
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    run = session.run_gait("+x", 0, 25.0)
    assert run.faults == [] and run.errors == []
    assert max(session.sim.plant.psi_deg) < 84.0
    first, *steady = run.cycle_displacements_mm
    assert len(steady) >= 3 and all(d > 5.0 for d in steady), run.cycle_displacements_mm


def test_the_example_robots_matrix_is_what_the_simulator_measures():
    """robots/paper-r1-stroke.toml's matrix is the learned one (rounded to 0.1 mm)."""
    robot = load_robot(STROKE)
    m = measure_matrix(robot)
    table, allowed = robot.transitions.dense()
    measured = np.where(np.isfinite(m.matrix_mm), m.matrix_mm, 0.0)
    assert np.array_equal(np.asarray(allowed, dtype=bool), np.isfinite(m.matrix_mm))
    assert np.allclose(np.where(allowed, table, 0.0), measured, atol=0.1)
