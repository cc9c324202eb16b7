"""The climb guard: ``[control] max_climb_deg``. The firmware refuses START (NACK TOO_STEEP,
detail = the climb in 0.01°) when the ground it levelled on at rest rises more than that in
the gait's direction, before any coil heats (docs/calibration.md, "Too steep to climb").

The oracle is the physical plant's true incline: after a flat calibration and 2.5 s at rest
on the slope, START of a built-in gait is refused exactly when the slope rises more than the
limit in the gait's direction (outside a band of 0.3° around the limit, where the firmware's
estimate of the slope, σ ≈ 0.1°, may fall either side)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from build_checks import cli as _cli
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    precondition,
    rule,
    run_state_machine_as_test,
)
from proleg.errors import RobotFileError
from proleg.firmware.boards import load_board
from proleg.firmware.build import firmware_gaits, render_project
from proleg.link.replies import CommandRefused
from proleg.paths import robots_dir
from proleg.protocol.definition import DIR_UNSTATED, GAIT_USER, ErrorCode
from proleg.report.claim import GridPoint, feedback_run
from proleg.robot import load_robot

R1 = robots_dir() / "paper-r1.toml"
BAND_DEG = 0.3


def _r1_with(tmp: Path, value: str | None) -> Path:
    """R1's file with `max_climb_deg = value` (None: without the key)."""
    lines = R1.read_text(encoding="utf-8").splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if line.startswith("max_climb_deg"))
    lines[at] = "" if value is None else f"max_climb_deg = {value}\n"
    text = "".join(lines)
    out = tmp / f"r1-climb-{value}.toml"
    out.write_text(text, encoding="utf-8")
    return out


_ROBOTS: dict[float, object] = {}


def _r1_limited(limit: float | tuple[float, float], tmp_path_factory) -> object:
    """R1 with max_climb_deg = limit, or (+x, -x) = limit."""
    if limit not in _ROBOTS:
        value = f"{limit:g}" if isinstance(limit, float) else f'{{ "+x" = {limit[0]:g}, "-x" = {limit[1]:g} }}'
        _ROBOTS[limit] = load_robot(_r1_with(tmp_path_factory.mktemp("climb"), value))
    return _ROBOTS[limit]


def _start_on(robot, incline_deg: float, direction: str = "+x", **kw):
    """Flat calibration, then `incline_deg`, 2.5 s at rest there, START, 3 s of gait."""
    point = GridPoint("slope", ("incline",), "mild", (f"incline_deg={incline_deg:g}",))
    return feedback_run(robot, point, direction=direction, duration_s=3.0, **kw)


def _refused(outcome) -> bool:
    return "TOO_STEEP" in outcome.fault


@pytest.mark.parametrize("value, expected", [
    ("0.2", "[0.5, 19.5]"), ("20", "[0.5, 19.5]"), ('"steep"', "a number"), ("true", "a number"),
    ('{ "+x" = 2, "-x" = 25 }', "max_climb_deg.-x: expected a number in [0.5, 19.5]"),
    ('{ "+x" = 2 }', "max_climb_deg.-x: expected a number (required)"),
    ('{ "+x" = 2, "-x" = 3, "+y" = 1 }', "unknown key '+y'"),
    # per-gait lists: the entry is named
    ('{ "+x" = [], "-x" = 2 }', "max_climb_deg.+x: expected a number, or a list"),
    ('{ "+x" = 2, "-x" = [3, 0.2] }', "max_climb_deg.-x[1]: expected a number in [0.5, 19.5]"),
    ('{ "+x" = [2, "x"], "-x" = 2 }', "max_climb_deg.+x[1]: expected a number"),
    ("[2, 3]", 'a number, or a table { "+x" = …, "-x" = … }'),
])
def test_a_limit_out_of_range_is_one_line_naming_the_key(tmp_path, value, expected):
    with pytest.raises(RobotFileError) as e:
        load_robot(_r1_with(tmp_path, value))
    message = str(e.value)
    assert "max_climb_deg" in message and expected in message and "\n" not in message


@settings(max_examples=200, deadline=None)
@given(plus=st.one_of(st.sampled_from([0.5, 2.0, 3.5]), st.lists(st.sampled_from([0.5, 1.0, 2.5, 4.0]), min_size=1,
                                                                  max_size=5)),
       minus=st.lists(st.sampled_from([1.0, 1.5, 6.0]), min_size=1, max_size=4))
def test_each_gait_takes_its_listed_limit_and_the_rest_the_smallest_of_the_list(plus, minus):
    """Oracle: the list as written. The limit keeps it short (trailing repeats of the smallest go)
    and says it back as a robot file would; every gait, listed or past the list, and the loaded
    gait (None) get the same limit from both."""
    from proleg.robot_climb import ClimbLimit

    def written(v, gait):
        if isinstance(v, float):
            return v
        return v[gait] if gait is not None and gait < len(v) else min(v)

    limit = ClimbLimit.of(plus, minus)
    for d, v in (("+x", plus), ("-x", minus)):
        for gait in (None, *range(7)):
            assert limit.toward(d, gait) == written(v, gait)
    # said back in the file's form, it reads as the same limit
    assert ClimbLimit.of(*(_read_back(limit.to_json(), d) for d in ("+x", "-x"))) == limit


def _read_back(j, d):
    way = j if not isinstance(j, dict) else j[d]
    return way if isinstance(way, float) else tuple(way)


def test_a_per_gait_list_is_built_into_the_firmware_and_may_not_name_more_gaits_than_it_carries(tmp_path):
    from proleg.errors import BuildError

    board = load_board("arduino-nano")
    r3 = robots_dir() / "paper-r3.toml"  # gaits: +x one, -x three
    path = tmp_path / "r3.toml"
    path.write_text(r3.read_text(encoding="utf-8").replace(
        "max_climb_deg = 2.5", 'max_climb_deg = { "+x" = 2.5, "-x" = [6, 1.5] }'), encoding="utf-8")
    robot = load_robot(path)
    config = render_project(robot, board, firmware_gaits(robot))["gen/robot_config.h"]
    assert "#define CFG_MAX_CLIMB_GAITS_MX 600, 150 " in config and "CFG_MAX_CLIMB_GAITS_PX" not in config
    assert "#define CFG_MAX_CLIMB_MX_CDEG 150 " in config  # the loaded gait, and -x gait 2: the smallest
    path.write_text(r3.read_text(encoding="utf-8").replace(
        "max_climb_deg = 2.5", 'max_climb_deg = { "+x" = [2.5, 1], "-x" = 3 }'), encoding="utf-8")
    robot = load_robot(path)
    with pytest.raises(BuildError, match=r"max_climb_deg\.\+x: 2 limits, but the firmware carries 1 gait walking \+x"):
        render_project(robot, board, firmware_gaits(robot))


def test_each_built_in_gait_is_refused_by_its_own_limit_and_the_rest_by_the_smallest(tmp_path_factory):
    """R3 walking -x up 4°: gait 0 (limit 6°) starts; gait 1 (1.5°) and gait 2, past the list
    (the smallest, 1.5°), are refused, and so is the loaded gait stated -x."""
    r3 = robots_dir() / "paper-r3.toml"
    path = tmp_path_factory.mktemp("pergait") / "r3.toml"
    path.write_text(r3.read_text(encoding="utf-8").replace(
        "max_climb_deg = 2.5", 'max_climb_deg = { "+x" = 2.5, "-x" = [6, 1.5] }'), encoding="utf-8")
    robot = load_robot(path)
    assert not _refused(_start_on(robot, -4.0, "-x", gait=0))
    for gait in (1, 2, [0, 1, 3, 0]):
        out = _start_on(robot, -4.0, "-x", gait=gait)
        assert _refused(out) and _detail_deg(out) == pytest.approx(4.0, abs=BAND_DEG), (gait, out)


def test_the_guard_is_built_only_when_the_robot_file_sets_it(tmp_path):
    board = load_board("arduino-nano")
    for value, lines in ((None, ()), ("2.5", ("#define CFG_MAX_CLIMB_CDEG 250 ",)),
                         ('{ "+x" = 2.5, "-x" = 2.5 }', ("#define CFG_MAX_CLIMB_CDEG 250 ",)),
                         ('{ "+x" = 1.5, "-x" = 3 }', ("#define CFG_MAX_CLIMB_CDEG 150 ",
                                                       "#define CFG_MAX_CLIMB_MX_CDEG 300 "))):
        robot = load_robot(_r1_with(tmp_path, value))
        config = render_project(robot, board, firmware_gaits(robot))["gen/robot_config.h"]
        assert [line for line in config.splitlines() if "CFG_MAX_CLIMB" in line and "#define" in line] == [
            next(line for line in config.splitlines() if line.startswith(want)) for want in lines]


@settings(max_examples=16, deadline=None)
@given(limit=st.sampled_from([1.5, 4.0, (1.5, 4.0), (5.0, 2.0)]),
       incline=st.floats(-9.0, 9.0).map(lambda v: round(v, 2)),
       direction=st.sampled_from(["+x", "-x"]))
def test_start_is_refused_exactly_when_the_gait_would_climb_more_than_the_limit(
        tmp_path_factory, limit, incline, direction):
    """One limit both ways, or each its own (+x, -x)."""
    climb = incline if direction == "+x" else -incline
    robot = _r1_limited(limit, tmp_path_factory)
    limit = robot.control.max_climb_deg.toward(direction)
    if abs(climb - limit) < BAND_DEG:
        return  # the firmware's slope estimate may fall either side of the limit
    outcome = _start_on(robot, incline, direction)
    if climb > limit:
        assert _refused(outcome), outcome
        assert _detail_deg(outcome) == pytest.approx(climb, abs=BAND_DEG)  # the detail is the measured climb
        assert outcome.displacement_mm == 0.0 and outcome.coil_peak_c < 26.0  # no coil ever heated
    else:
        assert not _refused(outcome), outcome
        assert outcome.coil_peak_c > 40.0  # it walked: the coils heated


def _detail_deg(outcome) -> float:
    return float(outcome.fault.split("rises ")[1].split("°")[0])


def test_the_refusal_reports_the_climb_it_measured(tmp_path_factory):
    outcome = _start_on(_r1_limited(1.5, tmp_path_factory), 6.0, "+x")
    assert _detail_deg(outcome) == pytest.approx(6.0, abs=0.3)


def _calibrated_then_put_on(robot, conditions: list[str]):
    """A simulated board calibrated at rest on the flat, then put down under `conditions` and
    left 2.5 s at rest there: (the simulated robot, its session)."""
    from proleg.link.level import calibrate_level
    from proleg.report.gait_run import SimSession
    from proleg.sim.closed_loop import SimulatedRobot, make_plant

    sim = SimulatedRobot(robot, seed=1, plant=make_plant(robot, "physical"))
    session = SimSession(sim)
    session.advance(0.3)
    assert calibrate_level(session.client).ok
    sim.plant = make_plant(robot, "physical", conditions)
    session.advance(2.5)
    return sim, session


def _start_after_a_knock(robot, knock: list[str], direction: str):
    """Flat calibration; down a 12° slope (-x, levelled there at START); stopped, then the robot
    put down again under `knock` (an IMU knocked since, another slope), 2.5 s at rest, START in
    `direction`: the run's errors and the coils' hottest temperature from there."""
    from proleg.sim.closed_loop import make_plant

    sim, session = _calibrated_then_put_on(robot, ["incline_deg=12"])
    assert not session.run_gait("-x", 0, 2.0).errors  # downhill: levelled on ±12°, walks
    sim.plant = make_plant(robot, "physical", knock)  # cold, at rest
    session.advance(2.5)
    run = session.run_gait(direction, 0, 2.0)
    return " ".join(run.errors), float(max(sim.plant.temperature_c))


def test_ground_beyond_what_the_board_levels_on_is_refused_either_way(tmp_path_factory):
    """An end tilted more than 20° from the flat record at rest (levelled on 12° before, then
    an IMU knocked 10°: it reads 10° against the ground in use, at rest, 22° in all): the board
    levels on no such ground, so it cannot measure the climb; the guard refuses it uphill and
    down (detail 0xFFFF)."""
    robot = _r1_limited(4.0, tmp_path_factory)
    for direction in ("+x", "-x"):
        errors, hottest = _start_after_a_knock(robot, ["incline_deg=12", "imu_offset_deg=0:10"], direction)
        assert "TOO_STEEP" in errors and "more than 20°" in errors, errors
        assert hottest < 26.0
    errors, _ = _start_after_a_knock(robot, ["incline_deg=12", "imu_offset_deg=0:4"], "-x")
    assert "TOO_STEEP" not in errors, errors  # 16°: levelled on, and downhill


def test_a_robot_with_a_gait_library_cannot_carry_the_guard(tmp_path):
    """planar-4's [gaits] library walks headings and turns: no +x / -x for the guard to climb."""
    planar = robots_dir() / "planar-4.toml"
    path = tmp_path / "planar-climb.toml"
    path.write_text(planar.read_text(encoding="utf-8").replace("[control]\n", "[control]\nmax_climb_deg = 2\n", 1),
                    encoding="utf-8")
    with pytest.raises(RobotFileError) as e:
        load_robot(path)
    assert "not with a [gaits] library" in str(e.value) and "max_climb_deg" in str(e.value)


def test_without_a_flat_calibration_the_slope_is_not_known_and_start_is_not_refused(tmp_path_factory):
    """The IMUs' mounting tilt cannot be told from the slope without a flat record."""
    outcome = _start_on(_r1_limited(1.5, tmp_path_factory), 6.0, "+x", calibrate=False)
    assert not _refused(outcome), outcome


def test_a_loaded_gait_is_guarded_in_the_way_its_start_states(tmp_path_factory):
    """LOAD_GAIT carries states; START of the loaded sequence says which way it walks (the
    learn-then-walk gait 00→10→01→00 here), and the guard checks that way."""
    robot = _r1_limited(1.5, tmp_path_factory)
    up = _start_on(robot, 6.0, "+x", gait=[0, 2, 1, 0])
    assert _refused(up) and _detail_deg(up) == pytest.approx(6.0, abs=BAND_DEG), up
    assert not _refused(_start_on(robot, -6.0, "+x", gait=[0, 2, 1, 0]))  # downhill


def test_a_loaded_gait_whose_way_start_leaves_unstated_is_not_guarded(tmp_path_factory):
    """A learning probe or a planar heading walks neither +x nor -x: START says so
    (DIR_UNSTATED) and the firmware does not refuse it on any ground."""
    from proleg.link.direction import UNSTATED

    sim, session = _calibrated_then_put_on(_r1_limited(1.5, tmp_path_factory), ["incline_deg=6"])
    session.client.load_gait([0, 2, 1])
    run = session.run_gait(UNSTATED, GAIT_USER, 3.0)
    assert not run.errors, run.errors
    assert max(sim.plant.temperature_c) > 40.0  # it ran: a coil heated


def test_only_the_loaded_gait_may_leave_its_way_unstated():
    from proleg.errors import LinkError
    from proleg.link.direction import UNSTATED, direction_code

    assert direction_code(UNSTATED, GAIT_USER) == DIR_UNSTATED
    assert direction_code("-x", GAIT_USER) == 1
    with pytest.raises(LinkError, match="only the loaded sequence"):
        direction_code(UNSTATED, 0)


def test_four_limbs_read_the_slope_from_the_first_and_last_ends(tmp_path):
    path = robots_dir() / "caterpillar-4.toml"
    robot = load_robot(path)  # { "+x" = 1, "-x" = 3 }
    assert _refused(_start_on(robot, 4.0, "+x"))
    assert _refused(_start_on(robot, -4.0, "-x"))
    assert not _refused(_start_on(robot, -4.0, "+x"))  # downhill
    assert _refused(_start_on(robot, 2.2, "+x"))  # 2.2° up: more than +x climbs
    assert not _refused(_start_on(robot, -2.2, "-x"))  # 2.2° up: -x climbs it
    listed = tmp_path / "c4.toml"  # each of the first two +x gaits its own limit
    listed.write_text(path.read_text(encoding="utf-8").replace(
        'max_climb_deg = { "+x" = 1, "-x" = 3 }', 'max_climb_deg = { "+x" = [1.5, 1], "-x" = 3 }'), encoding="utf-8")
    robot = load_robot(listed)
    assert not _refused(_start_on(robot, 1.25, "+x"))  # limits 1.5° for gait 0, 1° for gait 1
    assert _refused(_start_on(robot, 1.25, "+x", gait=1))


def test_the_host_says_what_too_steep_means():
    e = CommandRefused("START", int(ErrorCode.TOO_STEEP), 512, "robot on /dev/ttyUSB0")
    assert e.error == ErrorCode.TOO_STEEP
    assert "rises 5.12° in the gait's direction" in str(e) and "max_climb_deg" in str(e)


def test_levelling_on_the_ground_without_a_flat_record_does_not_arm_the_guard(tmp_path_factory):
    """`proleg calibrate --ground` without a flat record measures each IMU's mounting tilt
    with the ground: here IMUs mounted +4° and −4° on flat ground, which the guard would take
    for a 4° slope."""
    from proleg.link.level import calibrate_level
    from proleg.report.gait_run import SimSession
    from proleg.sim.closed_loop import SimulatedRobot, make_plant

    robot = _r1_limited(1.5, tmp_path_factory)
    sim = SimulatedRobot(robot, seed=1, plant=make_plant(robot, "physical", ["imu_offset_deg=0:4", "imu_offset_deg=1:-4"]))
    session = SimSession(sim)
    session.advance(0.3)
    assert calibrate_level(session.client, ground=True).ok
    run = session.run_gait("+x", 0, 3.0)
    assert not any("TOO_STEEP" in e for e in run.errors), run.errors
    assert run.displacement_mm != 0.0



@pytest.mark.parametrize("board, cause", [("host-sim", "external"), ("host-sim", "brown-out"), ("avr-emu", "external"), ("arm-emu", "external")])
def test_a_reconnect_does_not_blind_the_guard_to_the_slope_it_refused(tmp_path_factory, board, cause):
    """A Nano resets whenever a host opens its port, and every reset forgot the ground levelled
    on (the levelling at rest needs 2 s at rest to come back): `proleg run` STARTs as soon as
    the state is known, and R1 on the Nano (the exact image, avr-emu) started up the 6° slope
    its 2.5° guard had refused just before the reconnect. A reset that is not a power-on now
    keeps the ground, as it keeps the coils' budget. (host-sim kept it even across a power-on,
    unlike the chips, whose RAM the C runtime clears: there it is 0, as documented.)"""
    from proleg.link.level import calibrate_level, get_level
    from proleg.link.sim_link import SimLink
    from proleg.link.client import RobotClient
    from proleg.sim.closed_loop import SimulatedRobot, make_plant
    from proleg.sim.simulated_boards import simulated_board, simulated_robot

    if board != "host-sim" and simulated_board(board).missing():
        pytest.skip(simulated_board(board).missing())
    robot = _r1_limited(2.5, tmp_path_factory)
    sim = (SimulatedRobot(robot, plant="physical") if board == "host-sim"
           else simulated_robot(board, robot, plant="physical"))

    def connect() -> RobotClient:
        client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
        client.connect()
        assert client.wait_known_state()
        return client

    def wait(client, seconds):
        end = client.link.clock() + seconds
        while client.link.clock() < end:
            client.recv(0.05)

    def start(client):
        with pytest.raises(CommandRefused) as e:
            client.request("START", gait=0, direction=0)
        return e.value.error, e.value.detail

    client = connect()
    assert calibrate_level(client).ok
    sim.plant = make_plant(robot, "physical", ["incline_deg=6"])  # put down on a 6° slope
    sim._push_truth()
    wait(client, 2.5)
    error, climb = start(client)
    assert error == ErrorCode.TOO_STEEP and abs(climb - 600) < 30
    client.close()
    sim.board.restart(cause)
    client = connect()  # START as soon as the state is known, as `proleg run` does
    assert start(client) == (ErrorCode.TOO_STEEP, climb)
    client.close()
    if board == "host-sim":
        sim.board.reset(2)  # a power-on: no ground levelled on until 2 s at rest
    else:
        sim.board.reset()
    client = connect()
    assert get_level(client).ground_cdeg == (0, 0)
    wait(client, 2.5)
    assert start(client)[0] == ErrorCode.TOO_STEEP
    client.close()


class ClimbGuardMachine(RuleBasedStateMachine):
    """An operator who moves the robot between slopes, rests it or not, starts gait 0 or a
    loaded gait (its way stated or not) both ways, stops, calibrates and clears, in any
    order. Whatever the order: a START the board accepts
    after a flat calibration and 2.5 s at rest on this ground never climbs more than the
    limit; a START it refuses as TOO_STEEP heats no coil; and on a ground measured at rest the
    refusal is right (outside the 0.3° band)."""

    LIMIT = 1.5

    def __init__(self):
        super().__init__()
        from proleg.report.gait_run import SimSession
        from proleg.sim.closed_loop import SimulatedRobot, make_plant

        self.make_plant = make_plant
        self.robot = _MACHINE_ROBOT[0]
        self.sim = SimulatedRobot(self.robot, seed=3, plant=make_plant(self.robot, "physical"))
        self.session = SimSession(self.sim)
        self.session.advance(0.3)
        from proleg.link.level import calibrate_level

        assert calibrate_level(self.session.client).ok  # what a user does first
        self.incline = 0.0
        self.rested_s = 0.5      # at rest on this ground, no gait since
        self.flat_record = True
        self.running = False
        self.ran = False         # a gait has run since the board last saw 2 s at rest

    def _climb(self, direction: str) -> float:
        return self.incline if direction == "+x" else -self.incline

    @precondition(lambda self: not self.running)
    @rule(incline=st.sampled_from([-6.0, -2.0, 0.0, 0.8, 2.0, 3.5, 6.0]))
    def put_down_on(self, incline):
        self.sim.plant = self.make_plant(self.robot, "physical", [f"incline_deg={incline:g}"])
        # a fresh plant is cold, but the board remembers the gait until it has been at rest 2 s
        # (CALIBRATE_LEVEL refuses before: docs/calibration.md), and being put down moved it
        self.incline, self.rested_s = incline, 0.0

    @precondition(lambda self: not self.running)
    @rule(seconds=st.sampled_from([0.5, 2.5]))
    def rest(self, seconds):
        self.session.advance(seconds)
        self.rested_s += seconds
        if self.rested_s >= 2.5:
            self.ran = False  # the board has seen its 2 s at rest since the gait

    @precondition(lambda self: not self.running and self.incline == 0.0 and (self.rested_s >= 2.5 or not self.ran))
    @rule()
    def calibrate_on_the_flat(self):
        """On the flat, at rest: cold, or 2.5 s after a gait (docs/calibration.md)."""
        from proleg.link.level import calibrate_level

        assert calibrate_level(self.session.client).ok
        self.flat_record = True
        self.rested_s += 0.2

    @precondition(lambda self: not self.running)
    @rule()
    def clear_the_record(self):
        self.session.request("CLEAR_LEVEL")
        self.session.advance(0.05)
        self.flat_record = False

    @precondition(lambda self: not self.running)
    @rule(direction=st.sampled_from(["+x", "-x", "unstated"]), loaded=st.booleans())
    def start(self, direction, loaded):
        """Gait 0, or the loaded learn-then-walk sequence (00→10→01→00, +x) with its way
        stated (either way: a wrong one is the operator's) or unstated."""
        from proleg.link.direction import direction_code

        loaded = loaded or direction == "unstated"
        if loaded:
            self.session.client.load_gait([0, 2, 1])
        before = float(max(self.sim.plant.temperature_c))
        try:
            gait = GAIT_USER if loaded else 0
            self.session.request("START", gait=gait, direction=direction_code(direction, gait))
        except CommandRefused as e:
            assert e.error == ErrorCode.TOO_STEEP, e
            assert direction != "unstated", "refused a gait whose way START left unstated"
            assert self.flat_record, "refused without a flat record"
            self.session.advance(1.0)
            assert float(max(self.sim.plant.temperature_c)) <= before + 0.01  # no coil heated
            if self.rested_s >= 2.5:
                assert self._climb(direction) > self.LIMIT - BAND_DEG, (self.incline, direction, e)
            self.rested_s += 1.0
            return
        measured_here = self.flat_record and self.rested_s >= 2.5 and direction != "unstated"
        assert not (measured_here and self._climb(direction) > self.LIMIT + BAND_DEG), (self.incline, direction)
        self.running = self.ran = True
        self.session.advance(1.5)

    @precondition(lambda self: self.running)
    @rule()
    def stop(self):
        self.session.request("STOP")
        self.session.advance(0.2)
        # its limbs come down and cool for up to 1.7 s (docs/calibration.md) before the rest
        # the firmware levels on begins: a known rest only 2.5 s after that
        self.running, self.rested_s = False, -2.5


_MACHINE_ROBOT: list = []


@pytest.fixture(scope="module")
def machine_robot(tmp_path_factory):
    if not _MACHINE_ROBOT:
        _MACHINE_ROBOT.append(_r1_limited(ClimbGuardMachine.LIMIT, tmp_path_factory))
    return _MACHINE_ROBOT[0]


def test_no_sequence_of_operator_steps_gets_a_gait_started_up_too_steep_a_slope(machine_robot):
    run_state_machine_as_test(ClimbGuardMachine, settings=settings(max_examples=40, stateful_step_count=15,
                                                                    deadline=None))


# --------------------------------------------------------------------------- proleg sim --calibrated


R2 = robots_dir() / "paper-r2.toml"  # max_climb_deg = 2.5


def test_sim_calibrated_refuses_too_steep_a_climb_and_exits_1(capsys):
    rc, out, err = _cli(capsys, "sim", str(R2), "--calibrated", "--condition", "incline_deg=4",
                        "--duration", "5", "--json")
    assert rc == 1
    assert "TOO_STEEP" in err and "rises 4.0" in err
    assert json.loads(out)["displacement_mm"] == 0.0


def test_sim_calibrated_walks_downhill_and_up_a_gentle_slope(capsys):
    for incline in ("-4", "1"):
        rc, out, err = _cli(capsys, "sim", str(R2), "--calibrated", "--condition", f"incline_deg={incline}",
                            "--duration", "15", "--json")
        report = json.loads(out)
        assert rc == 0 and report["faults"] == [] and report["displacement_mm"] > 0.0, (incline, err)


def test_sim_calibrated_calibrates_away_a_crooked_imu(capsys):
    """IMUs mounted 8° crooked (docs/calibration.md): uncalibrated the board cannot see R1's
    states (STATE_TIMEOUT); calibrated on the flat first, as --calibrated does, it walks."""
    crooked = ("--condition", "imu_offset_deg=0:8", "--condition", "imu_offset_deg=1:-8", "--duration", "15", "--json")
    rc, out, _ = _cli(capsys, "sim", str(R1), *crooked)
    assert rc == 1 and json.loads(out)["cycles"] == 0
    rc, out, _ = _cli(capsys, "sim", str(R1), "--calibrated", *crooked)
    assert rc == 0 and json.loads(out)["cycles"] >= 2


def test_sim_without_calibrated_never_refuses(capsys):
    """The board of a plain `proleg sim` was never calibrated: a gauge, not the guard."""
    rc, out, err = _cli(capsys, "sim", str(R2), "--condition", "incline_deg=4", "--duration", "5", "--json")
    assert "TOO_STEEP" not in err


def test_sim_calibrated_says_in_words_which_limb_the_flat_calibration_refused(capsys):
    """An IMU biased 20° (in range) leaves R2's left limb past the 20° a calibration takes: the
    error printed the LevelOutcome's repr (``LevelOutcome(result=<LevelResult.TOO_TILTED: 1>, …``)."""
    rc, _, err = _cli(capsys, "sim", str(R2), "--calibrated", "--condition", "imu_bias_deg=-20", "--duration", "5")
    assert rc != 0 and "Traceback" not in err
    assert "flat calibration was refused: limb 'left': tilted more than 20° at rest" in err
    assert "LevelOutcome" not in err and "<" not in err
