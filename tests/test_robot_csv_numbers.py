"""A transition CSV's numbers are read as a person types them (proleg.typed): a digit
separator in a reward or a duration is a typo naming the CSV line, not a number ten times
as large."""

from __future__ import annotations

from pathlib import Path

import pytest
from build_checks import TWO_LIMBS

from proleg.errors import RobotFileError
from proleg.robot import load_robot

HEAD = TWO_LIMBS + '[transitions]\nfile = "t.csv"\n'


def csv_robot(tmp_path: Path, rows: str) -> Path:
    (tmp_path / "t.csv").write_text(rows)
    path = tmp_path / "t.toml"
    path.write_text(HEAD)
    return path


def test_a_digit_separator_in_a_csv_reward_is_refused_naming_the_line(tmp_path):
    with pytest.raises(RobotFileError, match=r"t\.csv:3: reward: expected a number, got '1_0'"):
        load_robot(csv_robot(tmp_path, "from,to,reward\n00,10,1\n10,00,1_0\n"))


def test_a_digit_separator_in_a_csv_duration_is_refused_naming_the_line(tmp_path):
    with pytest.raises(RobotFileError, match=r"t\.csv:2: duration_s: expected a number in .* seconds, got '1_5'"):
        load_robot(csv_robot(tmp_path, "from,to,reward,duration_s\n00,10,1,1_5\n10,00,1,2\n"))


def test_csv_numbers_without_separators_still_load(tmp_path):
    robot = load_robot(csv_robot(tmp_path, "from,to,reward,duration_s\n00,10,1e1,1.5\n10,00,-2.5,2\n"))
    t = robot.transitions
    assert sorted(zip(t.src.tolist(), t.dst.tolist(), t.reward.tolist(), t.duration.tolist())) == [
        (0b00, 0b10, 10.0, 1.5), (0b10, 0b00, -2.5, 2.0)]
