"""``proleg sim --measure-climb``: the steepest grade each gait climbs on the physical plant
(a bisection over a 0.25° grid, checked against a brute-force scan), the ``[control]
max_climb_deg`` it suggests from them, and that every example robot file carries exactly
that suggestion. The guard that enforces the limit on the board is in test_climb_guard.py."""

from __future__ import annotations

import json

import pytest
from build_checks import cli as _cli
from hypothesis import given, settings
from hypothesis import strategies as st
from proleg.paths import robots_dir
from proleg.robot import load_robot


@settings(max_examples=60, deadline=None)
@given(threshold=st.floats(-1.0, 13.0))
def test_the_bisection_finds_the_steepest_grade_a_brute_force_scan_finds(threshold):
    """A gait that climbs every grade up to `threshold` and none steeper: the bisection's answer
    is the scan's over the same 0.25° grid."""
    from unittest import mock

    from proleg.sim.physical import climb

    calls = []

    def mm(robot, states, direction, grade, conditions=()):
        calls.append(grade)
        return 1.0 if grade <= threshold else -0.5

    with mock.patch.object(climb, "climb_mm", mm):
        got = climb.steepest_climb(None, (0, 3), "+x")
    grid = [k * climb.RESOLUTION_DEG for k in range(round(climb.TOP_DEG / climb.RESOLUTION_DEG) + 1)]
    climbed = [g for g in grid if g <= threshold]
    assert got == (max(climbed) if climbed else None)
    assert len(calls) <= 2 + 6  # 48 steps: bisection, not a scan


@settings(max_examples=60, deadline=None)
@given(rates=st.lists(st.floats(-1.0, 1.0), min_size=49, max_size=49).map(lambda r: sorted(r, reverse=True)))
def test_a_grade_climbed_at_under_5_percent_of_the_flat_speed_is_not_climbed(rates):
    """Speeds that fall with the grade (one per 0.25° grid step, the flat's first): the steepest
    grade climbed is the steepest on which the robot still makes 5 % of its flat speed up the
    slope, as a scan finds; a robot that does not move up on the flat climbs nothing (None)."""
    from unittest import mock

    from proleg.sim.physical import climb

    def mm(robot, states, direction, grade, conditions=()):
        return rates[round(grade / climb.RESOLUTION_DEG)]

    with mock.patch.object(climb, "climb_mm", mm):
        got = climb.steepest_climb(None, (0, 3), "+x")
    if rates[0] <= 0:
        assert got is None
    else:
        climbed = [k for k, r in enumerate(rates) if r > 0.05 * rates[0]]
        assert got == max(climbed) * climb.RESOLUTION_DEG


def test_each_direction_is_suggested_its_own_limit_and_one_that_does_not_move_takes_the_others():
    from proleg.robot_climb import ClimbLimit
    from proleg.sim.physical.climb import suggested_limits

    assert suggested_limits({"+x": [1.5], "-x": [3.0]}) == ClimbLimit(1.5, 3.0)
    assert suggested_limits({"+x": [1.5, 1.25], "-x": [3.0]}) == ClimbLimit.of([1.5, 1.0], 3.0)  # each gait its own
    assert suggested_limits({"+x": [1.25, 1.75, 1.0], "-x": [3.0, 3.2]}) == ClimbLimit.of([1.0, 1.5], 3.0)
    assert suggested_limits({"+x": [2.0, None], "-x": [2.0]}) == ClimbLimit.of([2.0, 0.5], 2.0)  # one goes back
    assert suggested_limits({"+x": [None], "-x": [2.75]}) == ClimbLimit(2.5, 2.5)
    assert suggested_limits({"+x": [2.0]}) == ClimbLimit(2.0, 2.0)
    assert suggested_limits({"+x": [None], "-x": [None]}) is None
    assert str(ClimbLimit(1.5, 3.0)) == '{ "+x" = 1.5, "-x" = 3 }' and str(ClimbLimit(2.5, 2.5)) == "2.5"


def test_the_suggested_limit_is_the_smaller_climb_on_the_half_degree_and_at_least_half_a_degree():
    from proleg.sim.physical.climb import suggested_limit

    assert suggested_limit([2.75, 3.0]) == 2.5
    assert suggested_limit([None, 2.75]) == 2.5
    assert suggested_limit([0.0]) == 0.5
    assert suggested_limit([12.0, 12.0]) == 12.0
    assert suggested_limit([None, None]) is None


def _climbing_robots():
    """Every example robot file with a max_climb_deg; one with four or more limbs is ``long``
    (its bisections take two minutes on host-sim: `make bench` runs it)."""
    for path in sorted(robots_dir().glob("*.toml")):
        if "max_climb_deg = " in path.read_text(encoding="utf-8"):
            long = len(load_robot(path).limbs) >= 4
            yield pytest.param(path.stem, marks=[pytest.mark.long] if long else [])


@pytest.mark.parametrize("name", list(_climbing_robots()))
def test_every_example_robots_limit_is_what_measure_climb_suggests(capsys, name):
    """The robot files' max_climb_deg are measured, not chosen: --measure-climb gives them back
    (over as many gaits of each way as the file lists limits for)."""
    path = robots_dir() / f"{name}.toml"
    limit = load_robot(path).control.max_climb_deg
    listed = max(1, *(len(limit.gaits_toward(d)) for d in ("+x", "-x")))
    rc, out, _ = _cli(capsys, "sim", str(path), "--measure-climb", "--json", "--climb-gaits", str(listed))
    report = json.loads(out)
    assert rc == 0
    assert report["suggested_max_climb_deg"] == report["max_climb_deg"], report


@pytest.mark.parametrize("argv, text", [
    (("planar-4", "--measure-climb"), "cannot carry [control] max_climb_deg"),
    (("paper-r2", "--measure-climb", "--condition", "incline_deg=2"), "leave incline_deg out"),
    (("paper-r2", "--measure-climb", "--plant", "table"), "physical plant"),
    (("paper-r2", "--measure-climb", "--board", "avr-emu"), "not with --board"),
    (("paper-r2", "--measure-climb", "--calibrated"), "not with --calibrated"),
])
def test_measure_climb_says_what_it_cannot_do(capsys, argv, text):
    rc, _, err = _cli(capsys, "sim", str(robots_dir() / f"{argv[0]}.toml"), *argv[1:])
    assert rc == 2 and text in err and "Traceback" not in err


def test_a_warning_every_plant_gives_is_said_once(capsys):
    """Each grade and way is a plant of its own, and each plant's warnings were printed again,
    word for word: R1 at 20 V said each coil's overheat advice once per plant."""
    code, _out, err = _cli(capsys, "sim", robots_dir() / "paper-r1.toml", "--measure-climb", "--condition", "supply_v=20")
    lines = [ln for ln in err.splitlines() if ln.startswith("proleg: warning:")]
    assert code == 0 and len(lines) == 2 and len(set(lines)) == 2, err  # sma-left's and sma-right's
    code, _out, err = _cli(capsys, "sim", robots_dir() / "paper-r1.toml", "--measure-climb", "--condition", "supply_v=20")
    assert len([ln for ln in err.splitlines() if ln.startswith("proleg: warning:")]) == 2  # said again by a new command
