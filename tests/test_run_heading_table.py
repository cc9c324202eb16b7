"""``proleg run --heading`` on a firmware without the heading in a library: a computed gait the
firmware carries anyway (a robot without a library asked for 0° or 180°, its ±x gait 0) is
started by its index, with its way in from rest. Loaded as the user gait it had none, and a
gait that does not visit rest (110 ↔ 111) was refused from rest: "the robot stands in 000,
which the gait does not visit … move the robot into one of its states first"."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

from build_checks import cli

from proleg.firmware.gaits import choose_heading, firmware_gaits
from proleg.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"


def test_a_heading_whose_gait_the_firmware_carries_is_that_gait_by_its_index():
    for name in ("paper-r1.toml", "inchworm-3.toml", "paper-r1-one-actuator.toml"):
        robot = load_robot(ROBOTS / name)
        fw = firmware_gaits(robot)
        choice = choose_heading(robot, fw, 0.0)
        assert (choice.direction, choice.index) == ("+x", 0), (name, choice.message)
        assert choice.states == tuple(int(s) for s in fw["+x"][0].states[:-1])
        assert "the firmware's +x gait 0" in choice.message


def _away_from_rest(tmp_path: Path) -> Path:
    """Three limbs, one level a step; only 110 ↔ 111 moves the robot (+x), entered over 010."""
    labels = ["".join(p) for p in itertools.product("01", repeat=3)]
    rows = ["from,to,reward"]
    for a in labels:
        for b in labels:
            if sum(x != y for x, y in zip(a, b)) == 1:
                rows.append(f"{a},{b},{1.0 if (a, b) == ('110', '111') else 0.5 if (a, b) == ('111', '110') else 0}")
    (tmp_path / "t.csv").write_text("\n".join(rows) + "\n")
    text = '[robot]\nname = "away"\n'
    for i in range(3):
        text += f'[[limb]]\nname = "l{i}"\npsi_star_deg = [20.0]\nactuator = "a{i}"\n'
    text += "".join(f'[[actuator]]\nname = "a{i}"\n' for i in range(3))
    text += '[transitions]\nfile = "t.csv"\nunits = "mm"\n[control]\ntick_hz = 800\n'
    path = tmp_path / "away.toml"
    path.write_text(text)
    return path


def test_run_heading_0_walks_a_gait_that_does_not_visit_rest(tmp_path, capsys):
    path = _away_from_rest(tmp_path)
    robot = load_robot(path)
    assert [robot.transitions.label(s) for s in firmware_gaits(robot)["+x"][0].states] == ["110", "111", "110"]
    code, out, err = cli(capsys, "run", path, "--port", f"sim://{path}?plant=table", "--heading", "0",
                         "--duration", "8", "--format", "jsonl")
    assert code == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["ok"] and result["gait"] == 0 and result["direction"] == "+x"
    assert result["heading"]["loaded"] is False and result["cycles"] >= 1


PL2 = """
[robot]
name = "pl2"
[[limb]]
name = "L"
psi_star_deg = [20.0]
actuator = "x"
[[limb]]
name = "R"
psi_star_deg = [20.0]
actuator = "y"
[[actuator]]
name = "x"
[[actuator]]
name = "y"
[transitions]
units = "mm"
matrix = [[0, -1, 1, "x"], [1, 0, "x", -1], [-1, "x", 0, 1], ["x", 0.5, -0.5, 0]]
dy = [[0, 0.5, 0.2, "x"], [0.1, 0, "x", 0.3], [-0.2, "x", 0, 0.1], ["x", 0.1, 0.1, 0]]
dtheta_deg = [[0, 2, -1, "x"], [1, 0, "x", 3], [-1, "x", 0, 1], ["x", 1, 1, 0]]
[gaits]
library = [0, 90, 270]
"""


def test_a_library_heading_nothing_walks_is_said_as_a_warning_when_run(tmp_path, capsys):
    """The build says "(nothing scores above zero: the best)" of such an entry; run walked it
    (270°: a gait drifting +y) with the library's plain line."""
    path = tmp_path / "pl2.toml"
    path.write_text(PL2)
    robot = load_robot(path)
    fw = firmware_gaits(robot)
    assert {lg.heading.name: lg.below_zero for lg in fw.library} == {"0": False, "90": False, "270": True}
    down = choose_heading(robot, fw, 270.0)
    assert down.still and down.warned and not down.nearest
    assert down.message.endswith("(nothing scores above zero for it: the library's best, which does not move that way)")
    up = choose_heading(robot, fw, 90.0)
    assert not up.still and not up.warned and "nothing scores" not in up.message
