"""A ground steeper than the contacts' static friction holds the body on is warned of.

The physical plant is quasi-static: it moves the body only while its shape changes. R1 on 12°
at ``friction=0.2`` (soft pads' μ_s 0.2 < tan 12°) stopped with STATE_TIMEOUT and then stood on
the slope for the rest of the run with every coil cold, where a robot slides downhill, and
nothing said so (friction.py's docstring promised a ``downhill_mm`` that did not exist).
"""

from __future__ import annotations

import logging

import pytest

from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.closed_loop import make_plant

STEEP = "steeper than the contacts' static friction holds the body on"


def _warnings(caplog, robot: str, conditions: list[str]) -> list[str]:
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        make_plant(load_robot(robots_dir() / f"{robot}.toml"), "physical", conditions)
    return [r.getMessage() for r in caplog.records if STEEP in r.getMessage()]


@pytest.mark.parametrize("robot, conditions, where", [
    ("paper-r1", ["incline_deg=12", "friction=0.2"], "at rest (11.3"),
    ("paper-r1", ["incline_deg=-8", "friction=0.2"], "with every contact on its least grippy pad (4°"),
    ("paper-r2", ["incline_deg=6", "friction=0.2"], "at rest (4°"),  # R2 rests on its hard pads
])
def test_a_slope_the_contacts_cannot_hold_is_warned_of(caplog, robot, conditions, where):
    lines = _warnings(caplog, robot, conditions)
    assert len(lines) == 1 and where in lines[0] and "slides downhill" in lines[0]


@pytest.mark.parametrize("robot, conditions", [
    ("paper-r1", ["incline_deg=12"]), ("paper-r2", ["incline_deg=-12"]), ("caterpillar-4", ["incline_deg=12"]),
    ("paper-r1", ["incline_deg=3", "friction=0.2"]), ("paper-r1", ["friction=0.2"]),
])
def test_a_slope_the_contacts_hold_is_not(caplog, robot, conditions):
    assert _warnings(caplog, robot, conditions) == []
