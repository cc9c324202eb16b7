"""The example robots beyond the paper on the default (physical) plant, with the controller's
default hold (issue 14): several limbs are held at once while others fall, and no robot file
needs ``hold_duty = 0`` for that any more. And the robot-file check that a limb's top level is
within its own coil's reach on the simulated body (``proleg.body``)."""

from __future__ import annotations

import logging
import math
from pathlib import Path
from types import SimpleNamespace

import pytest

from proleg.body import body_geometry, default_length_mm, own_reach_deg
from proleg.errors import RobotFileError
from proleg.paths import robots_dir
from proleg.report import SimSession
from proleg.robot import load_robot
from proleg.robot_body import worn_holds_of
from proleg.sim.physical import PhysicalPlant
from proleg.sim.simulators import open_simulated

ROOT = Path(__file__).resolve().parents[1]

def _walk(name: str, direction: str, seconds: float = 40.0):
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    assert robot.control.hold_duty > 0.0  # the default hold: no workaround in the file
    sim = open_simulated(robot)  # the default plant: physical
    assert sim.plant_kind == "physical"
    session = SimSession(sim)
    session.advance(0.2)
    return session.run_gait(direction, 0, seconds)


@pytest.mark.parametrize("direction", ["+x", "-x"])
def test_inchworm_walks_both_ways_on_the_physical_plant_without_faults(direction):
    """What is asserted of each cycle is the steady cycles' direction, not the first one's: the
    first starts from rest with every coil at ambient, and in +x it earns much less (measured:
    +0.13 mm against +0.37..+0.84 for the next nine; 000→100 +0.14 mm against +0.26 and
    110→111 −0.20 against −0.02..−0.08; with an earlier controller it was −0.05..−0.14): a
    cold coil takes longer to reach As while the held limbs sag, and no earlier cycle's
    settling motion falls into its window (a cycle runs from one report of step 0 to the
    next). In −x the first cycle is not smaller (−0.56 against −0.52, −0.38). The whole run
    is asserted to move the robot its way. docs/robot-file.md, 'Example robots'."""
    report = _walk("inchworm-3", direction)
    sign = 1 if direction == "+x" else -1
    assert report.faults == [] and report.errors == []
    assert report.cycles >= 3, report.cycles
    assert sign * report.displacement_mm > 0, report.displacement_mm
    first, *steady = report.cycle_displacements_mm
    assert all(sign * d > 0 for d in steady), report.cycle_displacements_mm


@pytest.mark.parametrize("direction", ["+x", "-x"])
def test_caterpillar_walks_both_ways_on_the_physical_plant_without_faults(direction):
    """Its gait 0 is twelve steps (~15 s a cycle in +x): 60 s give at least three cycles."""
    report = _walk("caterpillar-4", direction, 60.0)
    sign = 1 if direction == "+x" else -1
    assert report.faults == [] and report.errors == []
    assert report.cycles >= 3, report.cycles
    assert all(sign * d > 0 for d in report.cycle_displacements_mm), report.cycle_displacements_mm


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "robots").glob("*.toml")))
def test_every_example_robot_reaches_its_top_levels_with_its_own_coils_without_a_warning(name, caplog):
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(ROOT / "robots" / f"{name}.toml")
    assert [r.getMessage() for r in caplog.records] == []
    plant = PhysicalPlant(robot)
    names = [a.name for a in robot.actuators]
    for i, limb in enumerate(robot.limbs):
        c = [0.0] * len(names)
        c[names.index(limb.actuator)] = 1.0
        plant.pose(c)
        assert plant.psi_deg[i] >= limb.psi_star_deg[-1] + limb.hysteresis_deg / 2, (limb.name, plant.psi_deg[i])


def test_the_reach_the_check_computes_is_what_the_plant_bends():
    robot = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    acts = [a.name for a in robot.actuators]
    limb_acts = [acts.index(lb.actuator) for lb in robot.limbs]
    reach = own_reach_deg(body_geometry(limb_acts, len(acts), robot.plant.length_mm, [8.0] * len(acts)), limb_acts)
    plant = PhysicalPlant(robot)
    assert plant.geometry.length_mm == robot.plant.length_mm == 120.0  # 40 mm between four contacts
    for i, j in enumerate(limb_acts):
        c = [0.0] * len(acts)
        c[j] = 1.0
        plant.pose(c)
        assert plant.psi_deg[i] == pytest.approx(reach[i], abs=1e-6)


def _caterpillar_text(**replace: str) -> str:
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    return text


def test_a_top_level_out_of_its_own_coils_reach_is_one_warning_line_per_limb(tmp_path, caplog):
    """The old caterpillar-4 (prolegs at ψ* 15°/35°) on an 80 mm body: each proleg's coil
    bends it to ≈ 22°, short of 36°."""
    path = tmp_path / "cat.toml"
    path.write_text(_caterpillar_text(**{"[12.0, 24.0]": "[15.0, 35.0]",
                                         "cross_gain_deg = 12.0": "cross_gain_deg = 12.0\nlength_mm = 80"}))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    lines = [r.getMessage() for r in caplog.records]
    assert robot.plant.length_mm == 80.0
    assert len(lines) == 2 and all("\n" not in line for line in lines), lines  # not also their hold tops
    for line, limb in zip(lines, ("rear", "front")):
        assert f"limb {limb!r}" in line and "needs ψ ≥ 36.0°" in line and "80 mm body" in line, line
        reach = float(line.split("bends it to ")[1].split("°")[0])
        assert 20.0 < reach < 25.0, line
    # a longer body reaches them: no warning
    path.write_text(_caterpillar_text(**{"[12.0, 24.0]": "[15.0, 35.0]",
                                         "cross_gain_deg = 12.0": "cross_gain_deg = 12.0\nlength_mm = 150"}))
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    assert caplog.records == []


def test_body_length_defaults_from_the_number_of_contacts_and_is_checked(tmp_path):
    assert default_length_mm(2) == 80.0 and default_length_mm(3) == 80.0
    assert default_length_mm(4) == 120.0 and default_length_mm(8) == 280.0
    path = tmp_path / "cat.toml"
    path.write_text(_caterpillar_text(**{"cross_gain_deg = 12.0": "cross_gain_deg = 12.0\nlength_mm = 5"}))
    with pytest.raises(RobotFileError, match=r"plant\.length_mm: expected a number in \[20, 2000\] mm, got 5"):
        load_robot(path)


def test_a_proleg_between_raised_limbs_is_lifted_a_state_the_file_allows_is_one_warning_naming_them(tmp_path, caplog):
    """caterpillar-4's 1020 (rear proleg at level 0 between the raised tail and the front
    proleg at level 2) cannot be held on the simulated body: the neighbours' coils, held
    where the controller holds them, bend the rear proleg past its first edge. The example
    file marks such states "x"; a file that allows 1000 -> 1020 gets one warning line naming
    the state, the lifted limb and the raised limbs, and the plant, driven there, reads
    the rear proleg at level 1."""
    from proleg.robot_body import coupled_states
    from proleg.sim.physical.measure import IdealDrive, _run_to

    robot = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    t = robot.transitions
    check = dict(limbs=list(robot.limbs), actuators=[a.name for a in robot.actuators], section=robot.plant,
                 hold_margin_deg=robot.control.hold_margin_deg)
    assert coupled_states(table=t, **check) == {}  # the example forbids them all
    # the plant agrees: held at 1010 and the front proleg raised to level 2, the rear one reads level 1
    plant = PhysicalPlant(robot)
    drive = IdealDrive(robot, plant, robot.control.hold_margin_deg)
    assert _run_to(plant, drive, t.index("1010"), robot.control.drive_duty, 0.002, 12.0, 1.0) is not None
    assert _run_to(plant, drive, t.index("1020"), robot.control.drive_duty, 0.002, 12.0, 1.0) is None
    assert t.label(plant.true_state)[1] == "1", t.label(plant.true_state)
    # a file that allows 1000 <-> 1020 (made-up entries) is warned about in one line
    text = (ROOT / "robots" / "caterpillar-4.toml").read_text()
    lines = text.splitlines()
    labels = [t.label(i) for i in range(t.n_states)]
    a, b = labels.index("1000"), labels.index("1020")
    for row, col in ((a, b), (b, a)):
        k = next(i for i, ln in enumerate(lines) if ln.rstrip().endswith(f"# from {labels[row]}"))
        body, comment = lines[k].split("],")
        cells = body.strip().lstrip("[").split(",")
        cells[col] = " 1"
        lines[k] = "  [" + ",".join(cells) + "]," + comment
    path = tmp_path / "cat.toml"
    path.write_text("\n".join(lines) + "\n")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        allowed = load_robot(path)
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 1 and "\n" not in warned[0], warned
    assert "state 1020" in warned[0] and "limb 'rear' (level 0)" in warned[0], warned[0]
    assert "'tail', 'front'" in warned[0] and '"x"' in warned[0], warned[0]
    hits = coupled_states(table=allowed.transitions, **check)
    assert list(hits) == [b] and [(i, raising) for i, raising, _ in hits[b]] == [(1, [0, 2])]


def test_a_two_limb_robot_is_checked_for_states_its_body_cannot_hold_too(tmp_path, caplog):
    """A four-level rear pad (ψ* 8°, 16°, 24°) beside a binary front pad: raising the front
    end lifts the rear one past 8.75°, so 01 cannot be held; the paper's robots (ψ* 20°)
    are not lifted past theirs and load without a word."""
    lines = ['[robot]', 'name = "ml4-2"', '[[limb]]', 'name = "rear"', 'levels = 4',
             'psi_star_deg = [8.0, 16.0, 24.0]', 'hysteresis_deg = 1.5', 'actuator = "a"',
             '[[limb]]', 'name = "front"', 'psi_star_deg = [18.0]', 'actuator = "b"',
             '[[actuator]]', 'name = "a"', 'channel = 0', '[[actuator]]', 'name = "b"', 'channel = 1',
             '[transitions]', 'states = ["00", "01", "10", "11", "20", "21", "30", "31"]', 'matrix = [']
    allowed = {(0, 1), (1, 0), (0, 2), (2, 0), (2, 3), (3, 2), (1, 3), (3, 1)}
    lines += ["  [" + ", ".join("0" if a == b else "1" if (a, b) in allowed else '"x"' for b in range(8)) + "],"
              for a in range(8)]
    path = tmp_path / "ml4-2.toml"
    path.write_text("\n".join([*lines, "]"]) + "\n")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 1 and "state 01: limb 'rear' (level 0) is lifted" in warned[0], warned
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        for name in ("paper-r1", "paper-r2", "paper-r3", "paper-r1-stroke", "paper-r1-one-actuator"):
            load_robot(ROOT / "robots" / f"{name}.toml")
    assert not caplog.records, [r.getMessage() for r in caplog.records]


def test_a_two_limb_robot_whose_raised_end_holds_the_other_inside_its_band_is_warned_it_never_settles(tmp_path, caplog):
    """R1 with hysteresis 16°: the load check posed the raised end at ψ* + margin (24°), which
    lifts the other end to 10°, under its band (12..28°), and the file loaded without a word.
    The firmware holds the raised end at its hold edge (ψ* + h/2 + margin = 32°) and above:
    the other end sat at 13–15°, read level 0 but never settled (no two-limb rule settles a
    limb held up), and 00 -> 10 ended in STATE_TIMEOUT "one would not settle". Posed at the
    hold edge it is at 13.2°: 10 and 01 are one line each, and gait 0 is an ``unholdable``
    error; hysteresis 14° (it walks) loads without a word."""
    from proleg.firmware.gaits import firmware_gaits
    from proleg.gait.feasibility import gait_problems

    text = (ROOT / "robots" / "paper-r1.toml").read_text()
    assert text.count("hysteresis_deg = 2.0") == 2
    path = tmp_path / "hy.toml"
    path.write_text(text.replace("hysteresis_deg = 2.0", "hysteresis_deg = 14.0"))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    assert not caplog.records, [r.getMessage() for r in caplog.records]
    path.write_text(text.replace("hysteresis_deg = 2.0", "hysteresis_deg = 16.0"))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 2, warned
    assert "state 10: limb 'right' (level 0) is held up to 13.2° by the raised limbs 'left'" in warned[1], warned
    assert "(12.0..28.0°): it reads level 0 but never settles" in warned[1], warned
    gait0 = [int(s) for s in firmware_gaits(robot)["+x"][0].states]
    problems = [p for p in gait_problems(robot, gait0) if p.severity == "error"]
    assert [p.kind for p in problems] == ["unholdable"] and "it never settles" in problems[0].message, problems
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    report = session.run_gait("+x", 0, 15.0)
    assert [f.code for f in report.faults][:1] == ["STATE_TIMEOUT"], report.faults


def test_a_state_a_raised_limbs_overshoot_lifts_a_limb_past_its_edge_in_is_warned(tmp_path, caplog):
    """Three 3-level limbs (ψ* 8°, 16°) on a 120 mm body: in 202 the two end limbs are held at
    level 2. Posed at ψ* + margin (20°) they lifted the middle one to 9.00°, its 9° edge to a
    thousandth (nano-3x6, three such limbs of 6 levels: read 212 instead of 202 in gait 0 and
    ended in STATE_TIMEOUT, the middle limb at 9.7°). The firmware heats them to their hold
    edge (21°: 9.4°), switches the coil off at the hold top (22°), and the rise carries on to
    ≈ 24° (``HOLD_OVERSHOOT_DEG``): posed at that peak the middle limb is at 10.8°, clear of the
    edge, and the state is warned about."""
    from proleg.robot_body import _held_psi, coupled_states

    rows = []
    labels = [f"{a}{b}{c}" for a in range(3) for b in range(3) for c in range(3)]
    allowed = {("000", "001"), ("001", "002"), ("002", "102"), ("102", "202"), ("202", "102"), ("102", "002"),
               ("002", "001"), ("001", "000")}
    for a in labels:
        rows.append("  [" + ", ".join("0" if a == b else "1" if (a, b) in allowed else '"x"' for b in labels) + "],")
    lines = ['[robot]', 'name = "three-3"']
    for k in range(3):
        lines += ['[[limb]]', f'name = "l{k}"', 'levels = 3', 'psi_star_deg = [8.0, 16.0]', f'actuator = "a{k}"']
    lines += [f'[[actuator]]\nname = "a{k}"' for k in range(3)]
    lines += ['[transitions]', 'matrix = [', *rows, ']', '[plant]', 'length_mm = 120']
    path = tmp_path / "three-3.toml"
    path.write_text("\n".join(lines) + "\n")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 1 and "state 202: limb 'l1' (level 0) is lifted to 10.8°" in warned[0], warned
    t, names = robot.transitions, [a.name for a in robot.actuators]
    s = t.index("202")
    assert robot.unholdable == {s: ((1, pytest.approx(10.79, abs=0.01)),)}
    margin = robot.control.hold_margin_deg
    old = _held_psi(list(robot.limbs), names, robot.plant, [s], margin - 1.0)  # ψ* + margin: h/2 = 1° lower
    edge = _held_psi(list(robot.limbs), names, robot.plant, [s], margin)
    assert old[(s, 1)] == pytest.approx(9.0, abs=0.01) and edge[(s, 1)] == pytest.approx(9.45, abs=0.01)
    assert s in coupled_states(list(robot.limbs), names, robot.plant, t, robot.control.hold_margin_deg)


_THREE_LEVEL_REAR = (Path(__file__).parent / "fixtures" / "l3-l2.toml").read_text()


def test_a_limb_the_raised_limbs_hold_inside_its_band_cannot_come_down_and_the_transition_is_warned(tmp_path, caplog):
    """A three-level rear pad (ψ* 10°, 22°) beside a binary front pad: posed at ψ* + margin,
    the raised front end held the rear one at ≈ 10°, short of its level-1 entry edge (11°) but
    above its level-0 edge (9°), so the load check warned only that lowering it from 11 never
    reads level 0. The firmware holds the front higher (its hold edge 25°, and its rise
    overshoots the hold top 26° to 28.8°): driven 00 -> 01 on the physical plant the rear is
    lifted to 12.2° and reads 11, so 01 cannot be held however it is entered. Posed where the
    firmware holds it (``robot_body.hold_peak_deg``), the rear is at 11.6°: one line about the
    state (the transition's own line would say less), and gait 0 (00 10 20 21 11 01 00), which
    ran into STATE_TIMEOUT at 11 -> 01, is an ``unholdable`` error; a file that marks the
    transitions into 01 "x" loads without a word."""
    from proleg.firmware.gaits import firmware_gaits
    from proleg.gait.feasibility import gait_problems
    from proleg.protocol.definition import FaultCode
    from proleg.sim.simulators import open_simulated

    path = tmp_path / "l3-l2.toml"
    path.write_text(_THREE_LEVEL_REAR)
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 1 and "\n" not in warned[0], warned
    assert "state 01: limb 'rear' (level 0) is lifted to 11.6° by the raised limbs 'front'" in warned[0], warned[0]
    assert "past its level-1 edge 11.0° (ψ* + hysteresis/2)" in warned[0], warned[0]
    gait0 = firmware_gaits(robot)["+x"][0].states
    assert [robot.transitions.label(int(s)) for s in gait0] == ["00", "10", "20", "21", "11", "01", "00"]
    assert [p.kind for p in gait_problems(robot, [int(s) for s in gait0]) if p.severity == "error"] == ["unholdable"]
    # the simulated firmware on the physical plant: the step 11 -> 01 never ends
    session = SimSession(open_simulated(robot))
    session.advance(0.2)
    report = session.run_gait("+x", 0, 20.0)
    assert [f.code for f in report.faults][:1] == [FaultCode.STATE_TIMEOUT.name], report.faults
    t = robot.transitions
    suspect = report.limb_loss[0]["detail"]
    assert (t.label(suspect // t.n_states), t.label(suspect % t.n_states)) == ("11", "01")
    # marked "x", the file loads without a word
    caplog.clear()
    path.write_text(_THREE_LEVEL_REAR.replace('["x", 0, 1, 0, "x", 0],  # 11', '["x", "x", 1, 0, "x", 0],  # 11')
                    .replace('[0, -1, 1, "x", "x", "x"],  # 00', '[0, "x", 1, "x", "x", "x"],  # 00'))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    assert not caplog.records, [r.getMessage() for r in caplog.records]


def test_a_limb_whose_lowest_band_holds_the_rest_angle_is_warned_as_resting_not_as_held_by_no_limbs(tmp_path, caplog):
    """R1 with the left ψ* at 0.5°: its level-0 edge is -0.5°, and the body rests at 0°, so
    lowering it (10 -> 00) never reads level 0. No limb is raised in 00, and the warning read
    "the raised limbs  hold it at 0.0°" (an empty list). It says the limb rests there, and to
    check its psi_star_deg."""
    text = (robots_dir() / "paper-r1.toml").read_text()
    assert text.count("psi_star_deg = [20.0]") == 2
    path = tmp_path / "low.toml"
    path.write_text(text.replace("psi_star_deg = [20.0]", "psi_star_deg = [0.5]", 1))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    down = [r.getMessage() for r in caplog.records if "transition 10→00" in r.getMessage()]
    assert len(down) == 1, [r.getMessage() for r in caplog.records]
    assert "limb 'left' cannot come down to level 0: it rests at 0.0° on the simulated 80 mm body" in down[0], down
    assert "check its psi_star_deg, or mark the transition" in down[0], down
    assert "raised limbs" not in down[0] and "  " not in down[0], down


def test_one_coil_on_both_limbs_lifts_its_own_end_first_so_the_far_end_alone_is_warned(tmp_path, caplog):
    """R1 with both limbs on sma-left and no forbidden list: state 01 (the far limb up, the
    coil's own down) cannot be held, since the coil lifts its own end first. It loaded
    without a word and gait 0 ran through 01 into SMA_ON_LIMIT and STATE_TIMEOUT. The
    one-actuator R1, which forbids every way into 01, loads without a word."""
    text = (ROOT / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith('actuator = "sma-right"'))
    lines[k] = 'actuator = "sma-left"'
    a = lines.index('name = "sma-right"')
    assert lines[a - 1] == "[[actuator]]" and lines[a + 1].startswith("channel")
    del lines[a - 1:a + 2]
    path = tmp_path / "shared.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    warned = [r.getMessage() for r in caplog.records if "cannot be held" in r.getMessage()]
    assert len(warned) == 1 and "state 01: limb 'left' (level 0) is lifted" in warned[0], warned
    assert "by its own coil 'sma-left', which also holds 'right' up" in warned[0]


def test_a_limb_that_rests_past_its_first_edge_is_said_so_not_lifted_by_nobody(tmp_path, caplog):
    """ψ* −30° and 10°: the limb rests at 0°, at level 1, and its level 0 cannot be held. The
    warning used to say it was "lifted ... by the raised limbs " (an empty list)."""
    text = (ROOT / "robots" / "paper-r1.toml").read_text(encoding="utf-8")
    path = tmp_path / "low.toml"
    body = text.replace("psi_star_deg = [20.0]", "psi_star_deg = [-30.0]", 1)
    assert body != text
    path.write_text(body, encoding="utf-8")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    warned = [r.getMessage() for r in caplog.records if "cannot be held" in r.getMessage()]
    assert warned and all("raised limbs  " not in w for w in warned), warned
    assert any("state 00: limb 'left' rests at" in w and "its level 0 lies below where it rests" in w
               for w in warned), warned


@pytest.mark.parametrize("name", ["inchworm-3", "caterpillar-4"])
def test_no_firmware_gait_of_an_example_robot_passes_through_a_state_its_body_cannot_hold(name):
    from proleg.firmware.build import firmware_gaits
    from proleg.robot_body import coupled_states

    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    n = robot.transitions.n_states
    every = SimpleNamespace(n_states=n, src=[0] * n, dst=list(range(n)))  # every state entered
    bad = set(coupled_states(list(robot.limbs), [a.name for a in robot.actuators], robot.plant, every,
                             robot.control.hold_margin_deg))
    assert bad == ({robot.transitions.index(s) for s in ("0201", "1020", "1021", "1201")}
                   if name == "caterpillar-4" else set())
    for gaits in firmware_gaits(robot).values():
        for g in gaits:
            assert not bad.intersection(int(s) for s in g.states)


def test_caterpillar_keeps_pace_with_the_idealised_drive_of_its_gait():
    """On a long body every step tilts the held limbs by a few degrees through the body; a falling
    limb that waited warm for each such sag (as for a neighbour about to drop a level) made the
    falling steps of caterpillar-4's gait 0 last 1.5-3 s (measured here: 1.30 s a step against
    the idealised drive's 1.03). Now it waits only for a neighbour within 2° of its band (ctl.h),
    and the firmware reaches its states at least 90 % as fast as the idealised drive of the same
    gait (true ψ, no stall rules: claim.idealised_walk; measured 1.07 s a step).
    docs/control.md, 'Long bodies'."""
    from proleg.report import claim

    robot = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    ideal = claim.idealised_walk(robot, claim.NOMINAL)
    steps = len(claim.gait_states(robot, "+x", 0)) - 1
    report = _walk("caterpillar-4", "+x", 60.0)
    assert report.faults == [] and report.errors == [] and report.unexpected_transitions == 0
    assert report.displacement_mm > 0, report.displacement_mm
    s_per_step = report.duration_s / len(report.states_reached)
    assert s_per_step <= ideal.s_per_cycle / steps / 0.9, (s_per_step, ideal.s_per_cycle / steps)


@pytest.mark.parametrize("body", ["", "\n[plant]\nworking_strain = 0.061\n"])
def test_a_hold_top_out_of_reach_is_one_warning_line_with_the_margin_that_fits(tmp_path, caplog, body):
    """The one-actuator R1 with the default 4° hold margin: its far end bends to ≈ 23.5° with
    its one coil at full stroke, short of its hold top 26°, and the warning says which margin
    fits (its hold top 0.5° below the reach); with that margin, no warning. On a body a little
    less stiff (working_strain 0.061) the margin that fits was rounded up (1.4) and warned of
    again: it is the tenth below."""
    text = (robots_dir() / "paper-r1-one-actuator.toml").read_text() + body
    assert "hold_margin_deg = 1.0" in text and text.count("[plant]") == (1 if body else 0)
    path = tmp_path / "one.toml"
    path.write_text(text.replace("hold_margin_deg = 1.0", "hold_margin_deg = 4.0"))
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "limb 'right': held raised" in lines[0] and "ψ ≥ 26.0°" in lines[0], lines
    # the warning says the hold watch holds it short: the firmware for this file has it
    assert worn_holds_of(robot) == [1]
    reach = float(lines[0].split("bends it to ")[1].split("°")[0])
    assert 22.0 < reach < 25.0, lines
    fits = float(lines[0].split("hold_margin_deg to at most ")[1])
    assert fits == pytest.approx(reach - 0.5 - 1.0 - 21.0, abs=0.16)  # reach to the nearest tenth, fits below
    path.write_text(text.replace("hold_margin_deg = 1.0", f"hold_margin_deg = {fits}"))
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        load_robot(path)
    assert caplog.records == []


def test_the_body_working_strain_is_a_robot_file_key_the_physical_plant_bends_by(tmp_path, caplog):
    """``[plant] working_strain`` (a lab's measurement of its body, not an operating condition):
    a fully heated coil bends its end about in proportion, on the plant and in the load-time
    reach checks alike; out of range it is refused naming the key."""
    src = (ROOT / "robots" / "paper-r1.toml").read_text()
    assert "[plant]" not in src  # R1 leaves every plant key at its default

    def r1(extra: str):
        path = tmp_path / "r1.toml"
        path.write_text(src + f"\n[plant]\n{extra}\n")
        return load_robot(path)

    def bent(robot) -> float:  # the left end with its coil heated through its transformation, the right coil off
        plant = PhysicalPlant(robot)
        for _ in range(1500):
            plant.step(0.002, [0.8, 0.0])
        return float(plant.psi_deg[0])

    stiff = r1("working_strain = 0.03")
    assert stiff.plant.working_strain == 0.03 and PhysicalPlant(stiff).geometry.working_strain == 0.03
    nominal = load_robot(ROOT / "robots" / "paper-r1.toml")
    full, half = bent(nominal), bent(stiff)
    assert full > 50.0 and 0.4 < half / full < 0.6, (full, half)
    from proleg.robot_body import body_of
    reach = [own_reach_deg(body_of([0, 1], 2, r.plant), [0, 1])[0] for r in (nominal, stiff)]
    assert 0.45 < reach[1] / reach[0] < 0.55, reach
    for bad in ("0", "0.3", '"stiff"'):
        with pytest.raises(RobotFileError, match=r"plant\.working_strain: expected a number in \(0, 0\.2\]"):
            r1(f"working_strain = {bad}")
    # so stiff that no coil bends its end past its level: the load-time reach check says so
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="proleg"):
        r1("working_strain = 0.005")
    assert any("psi_star_deg" in rec.getMessage() for rec in caplog.records), [r.getMessage() for r in caplog.records]
    # and names the key the lab set, not only length_mm (it said "or give [plant] length_mm")
    assert all("[plant] (length_mm, working_strain)" in rec.getMessage() for rec in caplog.records
               if "its top level needs" in rec.getMessage()), [r.getMessage() for r in caplog.records]


def test_a_body_too_soft_for_the_model_is_filed_under_working_strain_not_length_mm(tmp_path, caplog):
    """R1 with working_strain 0.2 and its default 80 mm body: a coil bends its span by 275°, past
    what the model describes. The load warning and the physical plant's refusal both named
    plant.length_mm, a key the file does not give; they name the key it gave, and say which way
    each key goes. A body given too long is still length_mm's."""
    from proleg.errors import SimError

    src = (ROOT / "robots" / "paper-r1.toml").read_text()
    path = tmp_path / "r1.toml"
    path.write_text(src + "\n[plant]\nworking_strain = 0.2\n")
    with caplog.at_level(logging.WARNING, logger="proleg"):
        robot = load_robot(path)
    warned = [r.getMessage() for r in caplog.records if "curl over itself" in r.getMessage()]
    assert len(warned) == 1 and f"{path}: plant.working_strain: coil 'sma-left' spans 48 mm" in warned[0], warned
    assert "a shorter body ([plant] length_mm) or a stiffer one (a smaller working_strain than 0.2)" in warned[0]
    with pytest.raises(SimError, match=r"r1\.toml: plant\.working_strain: coil 'sma-left' spans 48 mm .* curl over itself"):
        PhysicalPlant(robot)
    path.write_text(src + "\n[plant]\nlength_mm = 1000\nworking_strain = 0.05\n")
    with pytest.raises(SimError, match=r"r1\.toml: plant\.length_mm: coil 'sma-left' spans"):
        PhysicalPlant(load_robot(path))


def test_a_limb_may_give_its_pads_own_friction_coefficients(tmp_path):
    """``[[limb]] friction`` takes a pad's measured coefficients in place of a material name
    (the paper's D1/D2 or the materials' coefficients): the soft and hard pads' own numbers
    walk exactly as "D1" does (and reversed as "D2"), other numbers walk otherwise, and a
    coefficient out of range or a kinetic one above the static is refused naming the level."""
    from proleg.physics.materials import HARD, SOFT

    src = (ROOT / "robots" / "paper-r1.toml").read_text()
    assert src.count('actuator = "sma-') == 2 and "\nfriction" not in src

    def r1(friction: str):
        path = tmp_path / "r1.toml"
        path.write_text(src.replace('actuator = "sma-left"', f'actuator = "sma-left"\nfriction = {friction}')
                           .replace('actuator = "sma-right"', f'actuator = "sma-right"\nfriction = {friction}'))
        return load_robot(path)

    def travel(robot) -> float:  # the left coil heated and let cool, then the right, three times
        plant = PhysicalPlant(robot)
        for _ in range(3):
            for duties in ([0.8, 0.0], [0.0, 0.0], [0.0, 0.8], [0.0, 0.0]):
                for _ in range(750 if 0.8 in duties else 1500):
                    plant.step(0.002, duties)
        return plant.displacement_mm

    pad = lambda m: f"{{ mu_static = {m.mu_static}, mu_kinetic = {m.mu_kinetic} }}"  # noqa: E731
    d1 = travel(r1('"D1"'))
    assert abs(d1) > 0.3
    assert travel(r1(f"[{pad(SOFT)}, {pad(HARD)}]")) == pytest.approx(d1, abs=1e-9)
    assert travel(r1(f"[{pad(HARD)}, {pad(SOFT)}]")) == pytest.approx(travel(r1('"D2"')), abs=1e-9)
    stickier = travel(r1(f"[{{ mu_static = 2.0, mu_kinetic = 1.6 }}, {pad(HARD)}]"))
    assert abs(stickier - d1) > 0.05, (stickier, d1)  # the numbers are used, not a name's
    assert r1('["soft", { mu_static = 2, mu_kinetic = 1.5 }]').limbs[0].friction == ("soft", (2.0, 1.5))
    # counted from 1 as every list of the robot file is ("friction[1]" named the second, level 1), with the level
    for bad, said in (("[\"soft\", { mu_static = 0.3, mu_kinetic = 0.4 }]",
                       r"limb 'left': friction\[2\]\.mu_kinetic \(level 1\): expected at most mu_static \(0\.3\), got 0\.4$"),
                      ("[\"soft\", { mu_static = 0, mu_kinetic = 0 }]",
                       r"friction\[2\]\.mu_static \(level 1\): expected a number in \(0, 5\]"),
                      ("[{ mu = 1 }, \"hard\"]", r"friction\[1\] \(level 0\): expected the keys mu_static and mu_kinetic"),
                      ("[\"soft\", \"glue\"]", r"friction\[2\] \(level 1\): expected a material \(soft, hard\)")):
        with pytest.raises(RobotFileError, match=said):
            r1(bad)


def test_a_coil_narrower_than_twice_its_wire_is_refused_it_has_no_helix(tmp_path):
    """Between a straight wire (as wide as its wire) and a helix (at least twice as wide: its
    inner diameter not negative) there is no coil, and the wire-length formula (turns × π × mean
    diameter) gave a 0.1 mm wire in a 0.12 mm coil 9 mm of wire for 30 mm of coil: 1 Ω, and
    `proleg sim` heated it to 415 °C without a word. A thick wire in the default 0.4 mm coil
    says the coil diameter is the default."""
    src = (ROOT / "robots" / "paper-r1.toml").read_text()

    def r1(plant: str):
        path = tmp_path / "r1.toml"
        path.write_text(src + f"\n[plant]\n{plant}\n")
        return load_robot(path)

    for od in ("0.12", "0.1001", "0.199"):
        with pytest.raises(RobotFileError, match=r"r1\.toml: plant\.coil_diameter_mm: expected, for actuator "
                                                 rf"'sma-left' and its 0\.1 mm wire, .*got {od}$"):
            r1(f"wire_diameter_mm = 0.1\ncoil_diameter_mm = {od}")
    with pytest.raises(RobotFileError, match=r"actuator 'sma-right' and its 0\.3 mm wire, 0\.3 \(a straight wire\) "
                                             r"or at least 0\.6 .*got 0\.4 \(the default: give coil_diameter_mm\)$"):
        r1("wire_diameter_mm = [0.1, 0.3]")
    assert list(PhysicalPlant(r1("wire_diameter_mm = 0.1\ncoil_diameter_mm = 0.2")).resistance_ohm) == \
        pytest.approx([0.80e-6 * (30 / 0.1) * math.pi * 0.1e-3 / (math.pi * (0.1e-3) ** 2 / 4)] * 2)  # 9.6 Ω


def test_the_robot_files_coils_set_the_physical_plants_wire_and_transformation(tmp_path):
    """``[plant]`` wire_diameter_mm, coil_diameter_mm, coil_length_mm (per actuator) make each
    coil's resistance from its wire (ρ·L/A, NiTi 0.80 µΩ·m), a straight wire when the coil is as
    wide as its wire; as_c..mf_c move its transformation on the physical plant too. They
    describe the robot, so they are not run conditions."""
    from proleg.errors import SimError
    from proleg.sim.closed_loop import make_plant

    src = (ROOT / "robots" / "paper-r1.toml").read_text()

    def r1(plant: str):
        path = tmp_path / "r1.toml"
        path.write_text(src + f"\n[plant]\n{plant}\n")
        return load_robot(path)

    def wire_ohm(d_mm, od_mm, length_mm):
        wire_m = length_mm * 1e-3 if od_mm == d_mm else (length_mm / d_mm) * math.pi * (od_mm - d_mm) * 1e-3
        return 0.80e-6 * wire_m / (math.pi * (d_mm * 1e-3) ** 2 / 4)

    assert list(PhysicalPlant(load_robot(ROOT / "robots" / "paper-r1.toml")).resistance_ohm) == \
        pytest.approx([wire_ohm(0.1, 0.4, 30)] * 2)  # the default coil: 28.8 Ω
    thick = PhysicalPlant(r1("wire_diameter_mm = [0.1, 0.15]\ncoil_diameter_mm = [0.4, 0.6]"))
    assert list(thick.resistance_ohm) == pytest.approx([wire_ohm(0.1, 0.4, 30), wire_ohm(0.15, 0.6, 30)])
    straight = PhysicalPlant(r1("wire_diameter_mm = 0.1\ncoil_diameter_mm = 0.1\ncoil_length_mm = 100"))
    assert list(straight.resistance_ohm) == pytest.approx([wire_ohm(0.1, 0.1, 100)] * 2)  # 10.2 Ω

    # a 90 °C alloy: at duty 0.3 (≈ 85 °C on this supply) the default coil bends its end, this one does not
    def bent_at(robot, duty=0.3) -> float:
        plant = PhysicalPlant(robot)
        for _ in range(4000):
            plant.step(0.002, [duty, 0.0])
        return float(plant.psi_deg[0])
    hot = r1("as_c = 95.0\naf_c = 110.0\nms_c = 85.0\nmf_c = 70.0")
    assert PhysicalPlant(hot).transformation_c() == [(95.0, 110.0)] * 2
    assert bent_at(load_robot(ROOT / "robots" / "paper-r1.toml")) > 20.0 and bent_at(hot) < 2.0

    with pytest.raises(RobotFileError, match=r"plant\.coil_diameter_mm: expected, for actuator 'sma-left' and its "
                                             r"0\.1 mm wire, 0\.1 \(a straight wire\) or at least 0\.2 .*got 0\.05$"):
        r1("coil_diameter_mm = 0.05")
    with pytest.raises(RobotFileError, match=r"plant\.wire_diameter_mm\[2\]: expected a number in \(0, 2\] mm"):
        r1("wire_diameter_mm = [0.1, 0]")
    with pytest.raises(SimError, match="wire_diameter_mm"):
        make_plant(load_robot(ROOT / "robots" / "paper-r1.toml"), "physical", ["wire_diameter_mm=0.2"])
