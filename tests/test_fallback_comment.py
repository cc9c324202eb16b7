"""The generated gait table's comment on each fallback says what its mode means for that
loss: after the limb→actuator map, a bare "(dead)" read as if the map's last limb were the
one left dead, whichever coil was lost."""

from __future__ import annotations

import re
from pathlib import Path

from proleg.firmware.boards import load_board
from proleg.firmware.gaits import firmware_gaits
from proleg.firmware.render import render_config
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def _notes(name: str) -> list[str]:
    robot = load_robot(ROBOTS / name)
    table = render_config(robot, firmware_gaits(robot), load_board("host-sim"))["gait_table.c"]
    return [line for line in table.splitlines() if re.match(r" \*   [+-]x: without ", line)]


def test_a_dead_fallback_names_the_lost_coil_whose_limbs_stay_down():
    notes = _notes("inchworm-3.toml")
    dead = [n for n in notes if "; dead: " in n]
    assert dead, notes
    for line in dead:
        lost = re.match(r" \*   [+-]x: without (\S+):", line).group(1)
        assert line.endswith(f"; dead: the limbs on {lost} stay down"), line
    assert not any(n.endswith("(dead)") for n in notes)
