"""``proleg learn --sim`` of a one-limb robot: the physical plant needs two contacts, and the
refusal says how learn runs it (the table plant, ``--truth``), before the trial log is made;
it named `proleg sim --plant table`, a command that does not learn."""

from __future__ import annotations

from build_checks import cli

ONE = """
[robot]
name = "one"

[[limb]]
name = "solo"
psi_star_deg = [20.0]
actuator = "c"

[[actuator]]
name = "c"

[transitions]
units = "mm"
matrix = [[0, 1.5], [-0.5, 0]]
"""


def test_learning_a_one_limb_robot_on_the_physical_plant_points_to_truth(tmp_path, capsys):
    path = tmp_path / "one.toml"
    path.write_text(ONE)
    log = tmp_path / "one.jsonl"
    code, out, err = cli(capsys, "learn", path, "--sim", "--log", log)
    assert code == 2 and out == ""
    assert "the physical plant needs two limbs at least" in err and "--truth TRUTH.toml" in err
    assert "proleg sim --plant table" not in err
    assert not log.exists()
    code, out, err = cli(capsys, "learn", path, "--sim", "--log", log, "--truth", path, "--repeats", "1")
    assert code == 0, err
    assert log.exists()
