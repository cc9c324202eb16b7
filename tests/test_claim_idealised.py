"""The claim bench's idealised drive reports its own speed under every condition
(``claim.idealised_walk``), so that the bench can tell a condition that slows the gait itself
(whatever drives it) from one the controller handles badly."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from proleg.paths import robots_dir
from proleg.report import claim
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
    s = claim.summarise(results, nominal)
    walked = [r for r in results if r.possible and r.idealised_mm_s is not None]
    slowed = [r.point.name for r in walked if r.idealised_mm_s < 0.75 * nom_ideal]
    assert s["slowed_by_the_condition_itself"] == slowed
    assert s["idealised_kept_75pct_where_possible"] == len(walked) - len(slowed)
    assert s["idealised_walked_where_possible"] == len(walked)
    assert s["feedback_kept_75pct_of_idealised_where_possible"] == sum(
        r.feedback.completed and r.feedback.speed_mm_s >= 0.75 * r.idealised_mm_s for r in walked)
    assert math.isclose(s["idealised_nominal_mm_s"], round(nom_ideal, 4))
