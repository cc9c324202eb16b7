"""A per-limb or per-actuator ``[plant]`` key given something that is neither a number nor a
list says that a list is taken too: a string or a table there was "expected a number", as if
the key took one value only."""

from __future__ import annotations

import pytest
from build_checks import R1_MATRIX, TWO_LIMBS

from proleg.errors import RobotFileError
from proleg.robot import load_robot

R1 = TWO_LIMBS + f"[transitions]\n{R1_MATRIX}\n\n[plant]\n"


@pytest.mark.parametrize("line, says", [
    ('imu_offset_deg = "1"', r"plant\.imu_offset_deg: expected a number in \[-20, 20\] °, or a list of 2 "
                             r"\(one per limb\), got '1'$"),
    ("power_scale = {left = 0.8}", r"plant\.power_scale: expected a number in \[0\.2, 2\] ×, or a list of 2 "
                                   r"\(one per actuator\), got \{left = 0\.8\}$"),
    ("psi_rest_deg = true", r"plant\.psi_rest_deg: expected a number in \(-90, 90\) °, or a list of 2 "
                            r"\(one per limb\), got true$"),
])
def test_a_per_limb_or_actuator_key_that_is_no_number_says_a_list_is_taken(tmp_path, line, says):
    path = tmp_path / "t.toml"
    path.write_text(R1 + line + "\n")
    with pytest.raises(RobotFileError, match=says):
        load_robot(path)


def test_a_number_out_of_range_is_still_said_as_one(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(R1 + "power_scale = 5\n")
    with pytest.raises(RobotFileError, match=r"plant\.power_scale: expected a number in \[0\.2, 2\] ×, got 5$"):
        load_robot(path)
