"""SE(2) composition of a gait's transitions, and gait libraries."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import GaitError
from proleg.gait.compose import Pose, compose_path, gait_path, net_motion
from proleg.gait.library import gait_library, library_gaits, parse_headings
from proleg.gait.planar import PlanarObjective, optimal_planar_gaits
from proleg.transitions import PlanarRewards, TransitionTable


def matrix_pose(steps) -> tuple[float, float, float]:
    """Oracle: products of homogeneous 3×3 SE(2) matrices."""
    T = np.eye(3)
    for dx, dy, dth in steps:
        c, s = math.cos(math.radians(dth)), math.sin(math.radians(dth))
        T = T @ np.array([[c, -s, dx], [s, c, dy], [0, 0, 1]])
    return T[0, 2], T[1, 2], math.degrees(math.atan2(T[1, 0], T[0, 0]))


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-90, 90)), min_size=1, max_size=8),
       st.integers(1, 4))
def test_composition_is_the_product_of_se2_matrices(steps, cycles):
    end = compose_path(np.array(steps), cycles)[-1]
    x, y, th = matrix_pose(steps * cycles)
    assert (end.x, end.y) == pytest.approx((x, y), abs=1e-9)
    assert math.remainder(end.theta_deg - th, 360.0) == pytest.approx(0.0, abs=1e-9)
    assert end.theta_deg == pytest.approx(cycles * sum(s[2] for s in steps), abs=1e-9)


def square_table():
    # 0 → 1 → 2 → 3 → 0: each step 1 forward, then a 90° left turn: one pass is a closed square
    src, dst = np.array([0, 1, 2, 3, 1]), np.array([1, 2, 3, 0, 0])
    dx = np.array([1.0, 1.0, 1.0, 1.0, 0.5])
    planar = PlanarRewards(dy=np.zeros(5), dtheta_deg=np.array([90.0, 90.0, 90.0, 90.0, -10.0]))
    return TransitionTable.from_edges((4,), src, dst, dx, None, planar)


def test_a_gait_that_turns_90_degrees_a_step_walks_a_square_and_comes_back():
    t = square_table()
    end = net_motion(t, (0, 1, 2, 3, 0))
    assert (end.x, end.y) == pytest.approx((0.0, 0.0), abs=1e-12) and end.theta_deg == pytest.approx(360.0)
    path = gait_path(t, (0, 1, 2, 3), 2)
    assert len(path) == 9 and path[0] == Pose(0.0, 0.0, 0.0)
    assert (path[1].x, path[1].y, path[2].x, path[2].y) == pytest.approx((1.0, 0.0, 1.0, 1.0))
    with pytest.raises(GaitError, match="not an allowed transition"):
        net_motion(t, (0, 2))


def test_headings_parse_and_refuse_nonsense():
    hs = parse_headings("0, 45,90,180,270,rot-cw,rot-ccw")
    assert [h.name for h in hs] == ["0", "45", "90", "180", "270", "rot-cw", "rot-ccw"]
    assert hs[1].heading_deg == 45.0 and hs[5].rotate == "cw"
    for bad, msg in (("north", "neither a heading"), ("0,0", "given twice"), ("", "at least one"), ("nan", "within ±3600"),
                     ("1e308", "within ±3600"),
                     ("0,,90", "entry 2 of '0,,90' is empty"), ("0,90,", "entry 3 of '0,90,' is empty"),
                     ("0,360", r"heading 360 is given twice \(the same heading as 0\)"),
                     ("90,-270", r"heading -270 is given twice \(the same heading as 90\)")):
        with pytest.raises(GaitError, match=msg):
            parse_headings(bad)


def test_the_library_holds_each_headings_best_gait_in_order():
    rng = np.random.default_rng(5)
    n = 5
    allowed = ~np.eye(n, dtype=bool)
    src, dst = np.nonzero(allowed)
    m = len(src)
    planar = PlanarRewards(dy=rng.normal(size=m), dtheta_deg=rng.normal(0, 20, size=m))
    t = TransitionTable.from_edges((n,), src, dst, rng.normal(size=m), None, planar)
    entries = gait_library(t, "0,90,180,rot-cw,rot-ccw", "rate", 4, rotation_cap_deg=30.0, translation_cap=1.0)
    assert [e.heading.name for e in entries] == ["0", "90", "180", "rot-cw", "rot-ccw"]
    for e in entries:
        if e.heading.rotate is None:
            want = optimal_planar_gaits(t, PlanarObjective(e.heading.heading_deg), "rate", 4, 30.0)
        else:
            want = optimal_planar_gaits(t, PlanarObjective(), "rate", 4, rotate=e.heading.rotate, translation_cap=1.0)
        assert e.result.value == pytest.approx(want.value) and e.gait == want.gaits[0]
    lib = library_gaits(entries)
    assert [h.name for h, _ in lib] == [e.heading.name for e in entries if e.gait is not None]
    cw = dict((h.name, g) for h, g in lib)["rot-cw"]
    assert net_motion(t, cw.states).theta_deg < 0
