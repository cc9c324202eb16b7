"""Two [[actuator]]s on one PWM channel are refused naming the other actuator, and a channel
taken by default (an actuator's place, counted from 0) is said to be one: "got 1" for an
actuator with no channel key named nothing the file holds."""

from __future__ import annotations

import pytest

from proleg.errors import RobotFileError
from proleg.robot import load_robot

HEAD = """
[robot]
name = "t"

[[limb]]
name = "left"
psi_star_deg = [20.0]
actuator = "x"

[[limb]]
name = "right"
psi_star_deg = [20.0]
actuator = "y"
"""

TAIL = """
[transitions]
matrix = [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]
"""


def _load(tmp_path, x: str, y: str):
    path = tmp_path / "t.toml"
    path.write_text(HEAD + f'\n[[actuator]]\nname = "x"\n{x}\n[[actuator]]\nname = "y"\n{y}\n' + TAIL)
    return load_robot(path)


@pytest.mark.parametrize("x, y, says", [
    ("channel = 1", "", r"t\.toml: actuator 'y': channel: expected a channel no other actuator uses: without one it "
                        r"takes its place among the \[\[actuator\]\]s counted from 0, 1, which actuator 'x' has "
                        r"\(channel = 1\): give it a channel of its own$"),
    ("", "channel = 0", r"t\.toml: actuator 'y': channel: expected a channel no other actuator uses \(actuator 'x' "
                        r"has channel 0, by default\), got 0$"),
    ("channel = 3", "channel = 3", r"t\.toml: actuator 'y': channel: expected a channel no other actuator uses "
                                   r"\(actuator 'x' has channel = 3\), got 3$"),
], ids=["default-meets-written", "written-meets-default", "both-written"])
def test_a_shared_channel_names_the_actuator_that_has_it(tmp_path, x, y, says):
    with pytest.raises(RobotFileError, match=says):
        _load(tmp_path, x, y)


def test_distinct_channels_written_or_by_default_load(tmp_path):
    robot = _load(tmp_path, "channel = 1", "channel = 0")
    assert [(a.name, a.channel, a.channel_given) for a in robot.actuators] == [("x", 1, True), ("y", 0, True)]
    robot = _load(tmp_path, "", "")
    assert [(a.channel, a.channel_given) for a in robot.actuators] == [(0, False), (1, False)]
