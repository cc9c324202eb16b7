"""The gait library in the firmware (robot file [gaits], proleg build --library) and the host
selecting by heading (proleg run --heading / --rotate), in closed loop on the planar table
plant: running a heading moves the robot's pose along that heading."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import pytest

from proleg.cli import main
from proleg.errors import BuildError, RobotFileError
from proleg.firmware.boards import load_board
from proleg.firmware.fit import check_fit
from proleg.firmware.gaits import choose_heading, firmware_gaits
from proleg.firmware.render import render_config
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
PLANAR = ROOT / "robots" / "planar-4.toml"


@pytest.fixture(scope="module")
def robot():
    return load_robot(PLANAR)


@pytest.fixture(scope="module")
def fw(robot):
    return firmware_gaits(robot)


def labels(robot, states):
    return [robot.transitions.label(s) for s in states]


def test_the_library_is_in_the_gait_table_where_the_host_will_look(robot, fw):
    names = [lg.heading.name for lg in fw.library]
    assert names == ["0", "90", "180", "270", "rot-cw", "rot-ccw"]
    for lg in fw.library:
        in_table = fw[lg.direction][lg.index]
        assert in_table.states == lg.gait.states  # START direction index runs exactly this gait
    # the ±x optimal ties keep their places: a library gait already there is not copied
    assert {(lg.direction, lg.index) for lg in fw.library if not lg.appended} == {("+x", 0), ("-x", 0)}
    appended = [lg for lg in fw.library if lg.appended]
    n_ties = len(fw["+x"]) - len(appended)
    assert sorted(lg.index for lg in appended) == list(range(n_ties, len(fw["+x"])))
    # each heading gait goes along its heading; the rotations turn their way
    for lg in fw.library:
        if lg.heading.heading_deg is not None:
            h = math.radians(lg.heading.heading_deg)
            along = lg.net.x * math.cos(h) + lg.net.y * math.sin(h)
            across = -lg.net.x * math.sin(h) + lg.net.y * math.cos(h)
            assert along > 2.5 and abs(across) < 0.3 and abs(lg.net.theta_deg) <= 5.0
    turns = {lg.heading.rotate: lg.net.theta_deg for lg in fw.library if lg.heading.rotate}
    assert turns["cw"] < -5 and turns["ccw"] > 5


def test_the_generated_header_and_table_name_every_library_gait(robot, fw):
    files = render_config(robot, fw, load_board("host-sim"))
    header, table = files["robot_config.h"], files["gait_table.c"]
    assert "#define CFG_N_LIBRARY_GAITS 6u" in header
    for text in (header, table):
        assert "gait library (headings 0,90,180,270,rot-cw,rot-ccw, objective rate" in text
        for lg in fw.library:
            assert lg.describe(robot.transitions.label) in text
    assert f"#define CFG_N_GAITS_PX {len(fw['+x'])}u" in header
    # without a library: no library lines, and the table is what it was
    plain = dataclasses.replace(robot, library=None)
    files = render_config(plain, firmware_gaits(plain), load_board("host-sim"))
    assert "library" not in files["robot_config.h"] and "CFG_N_LIBRARY_GAITS" not in files["robot_config.h"]


def test_build_writes_the_library_into_the_manifest(robot, tmp_path, capsys):
    out = tmp_path / "build"
    assert main(["build", str(PLANAR), "--board", "host-sim", "-o", str(out), "--library", "0,45,rot-cw"]) == 0
    printed = capsys.readouterr().out
    assert "library heading 45 deg: +x gait" in printed
    manifest = json.loads((out / "proleg-build.json").read_text())
    assert manifest["gait_library_selection"]["headings"] == ["0", "45", "rot-cw"]
    assert manifest["gait_library_selection"]["rotation_cap_deg"] == 5.0  # the robot file's question, other headings
    lib = {e["heading"]: e for e in manifest["gait_library"]}
    assert set(lib) == {"0", "45", "rot-cw"}
    for e in lib.values():
        assert manifest["gaits"][e["direction"]][e["gait"]] == [robot.transitions.index(s) for s in e["states"]]
        assert set(e["net_motion"]) == {"dx", "dy", "dtheta_deg"}
    assert lib["rot-cw"]["rotate"] == "cw" and lib["45"]["heading_deg"] == 45.0


def test_a_library_that_does_not_fit_the_flash_is_refused_naming_it(robot, fw):
    nano = load_board("arduino-nano")
    need = check_fit(robot, nano, fw).flash_estimate
    small = dataclasses.replace(nano, flash_bytes=need - 1)
    with pytest.raises(BuildError, match=r"does not fit board arduino-nano .*its gait library \(6 headings, 4 gaits "
                                         r"of their own\) takes about \d+ bytes of that: fewer headings"):
        check_fit(robot, small, fw)


@pytest.mark.parametrize("gaits, message", [
    ('library = [0, "north"]', r"gaits\.library: 'north' is neither a heading in degrees nor rot-cw/rot-ccw"),
    ('library = [0]\nobjective = "speed"', r'gaits\.objective: expected "total" or "rate", got \'speed\''),
    ('library = [0]\ncolour = 1', r"gaits: unknown key 'colour'"),
    ("rotation_cap_deg = 5", r"gaits: the keys rotation_cap_deg describe a library; give gaits.library"),
    ('library = [0, 0]', r"gaits\.library: heading 0 is given twice"),
    ('library = [0, 360]', r"gaits\.library: heading 360 is given twice \(the same heading as 0\)"),
    ('library = [0]\nmax_transitions = 1000000000', r"gaits\.max_transitions: expected a whole number in 2\.\.256, "
                                                    r"got 1000000000"),
    ('library = [0]\nvariance_weight = -1', r"gaits\.variance_weight: expected a number in \[0, 1e\+09\] or \[λx, λy, λθ\], "
                                            r"got -1$"),
    ('library = [0]\nvariance_weight = [0, 1e308, 0]', r"gaits\.variance_weight: expected a number in \[0, 1e\+09\] or "
                                                       r"\[λx, λy, λθ\], got \[0, 1e\+308, 0\]$"),
    ('library = [0]\ntransition_cost = 1e308', r"gaits\.transition_cost: expected a number in \[0, 1e\+09\] \(a cost "
                                               r"per transition, as --transition-cost\), got 1e\+308$"),
])
def test_a_bad_gaits_table_is_one_line_naming_the_key(tmp_path, gaits, message):
    text = PLANAR.read_text()
    start = text.index("\n[gaits]\n")
    end = text.index("\n[transitions]\n")
    bad = tmp_path / "bad.toml"
    bad.write_text(text[:start] + "[gaits]\n" + gaits + "\n\n" + text[end:])
    with pytest.raises(RobotFileError, match=message) as e:
        load_robot(bad)
    assert str(e.value).startswith(str(bad)) and "\n" not in str(e.value)


@pytest.mark.parametrize("gaits, needs", [
    ("library = [0, 90]", "dy"),
    ('library = [0, "rot-cw"]', "dtheta_deg"),
    ("library = [0]\nrotation_cap_deg = 5", "dtheta_deg"),
    ("library = [0]\nvariance_weight = 1", "var_dx"),
])
def test_a_library_asking_for_statistics_the_file_lacks_is_refused_when_read(tmp_path, gaits, needs):
    """paper-r1 has Δx only: a heading off the x axis, a rotation or a variance weight needs a
    planar statistic it does not give. Refused when the file is read (gait and build agree),
    naming the file, gaits.library and the statistic."""
    r1 = re.sub(r"^max_climb_deg.*\n(\s+#.*\n)*", "", (PLANAR.parent / "paper-r1.toml").read_text(), flags=re.M)
    bad = tmp_path / "r1-library.toml"  # (the climb guard is not for library robots)
    bad.write_text(r1 + "\n[gaits]\n" + gaits + "\n")
    with pytest.raises(RobotFileError, match=rf"gaits\.library: .*needs \[transitions\]\.{needs} in the robot file") as e:
        load_robot(bad)
    assert str(e.value).startswith(str(bad)) and "\n" not in str(e.value)
    (tmp_path / "ok.toml").write_text(r1 + "\n[gaits]\nlibrary = [0, 180]\n")
    assert load_robot(tmp_path / "ok.toml").library is not None


def test_choosing_a_heading(robot, fw):
    exact = choose_heading(robot, fw, 90.0)
    assert (exact.direction, exact.index) == next((lg.direction, lg.index) for lg in fw.library if lg.heading.name == "90")
    assert "nearest" not in exact.message
    near = choose_heading(robot, fw, 200.0)
    assert near.heading.name == "180" and "the library's nearest heading, 180°, 20° off" in near.message
    assert choose_heading(robot, fw, -80.0).heading.name == "270"  # on the circle
    assert choose_heading(robot, fw, rotate="ccw").heading.name == "rot-ccw"
    computed = choose_heading(robot, fw, 30.0, exact=True)
    assert "not in the firmware's library" in computed.message
    # the exact heading's gait is one the firmware carries (+x gait 0): started by its index, with its
    # way in from rest, not loaded as the user gait (tests/test_run_heading_table.py)
    assert (computed.direction, computed.index) == ("+x", 0) and "the firmware's +x gait 0" in computed.message
    assert computed.states[0] != computed.states[-1] and len(computed.states) >= 2  # open


# ------------------------------------------------------------------ closed loop (sim://, table plant)
def run_heading(capsys, robot_file: Path, *steer: str, duration: str = "8") -> dict:
    url = f"sim://{robot_file}?plant=table"
    code = main(["run", str(robot_file), "--port", url, *steer, "--duration", duration, "--format", "jsonl", "-q"])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads(out.splitlines()[-1])
    assert result["msg"] == "RESULT" and result["ok"] and result["cycles"] >= 2
    return result


def direction_deg(pose: dict) -> float:
    return math.degrees(math.atan2(pose["y_mm"], pose["x_mm"]))


@pytest.mark.parametrize("heading", [90.0, 180.0])
def test_running_a_heading_moves_the_robot_along_it(capsys, heading):
    result = run_heading(capsys, PLANAR, "--heading", f"{heading:g}")
    pose = result["pose"]
    assert math.hypot(pose["x_mm"], pose["y_mm"]) > 15.0
    off = abs((direction_deg(pose) - heading + 180) % 360 - 180)
    assert off < 20.0, pose
    assert result["heading"]["ran"] == f"{heading:g}" and not result["heading"]["loaded"]


def test_a_rotation_gait_turns_the_robot_on_the_spot(capsys):
    result = run_heading(capsys, PLANAR, "--rotate", "cw")
    pose = result["pose"]
    assert pose["theta_deg"] < -15.0 and math.hypot(pose["x_mm"], pose["y_mm"]) < 10.0, pose


def test_without_a_library_the_gait_for_the_heading_is_computed_and_loaded(capsys, tmp_path):
    text = PLANAR.read_text()
    bare = tmp_path / "planar-4.toml"  # the same robot, no [gaits]: the firmware carries no library
    bare.write_text(text[: text.index("\n[gaits]\n")] + text[text.index("\n[transitions]\n"):])
    result = run_heading(capsys, bare, "--heading", "90")
    assert result["heading"]["loaded"] and result["gait"] == 255
    off = abs((direction_deg(result["pose"]) - 90 + 180) % 360 - 180)
    assert off < 25.0 and math.hypot(result["pose"]["x_mm"], result["pose"]["y_mm"]) > 10.0, result["pose"]


def test_a_board_built_with_another_library_is_refused_not_steered_by_index(capsys):
    """The library gait is started by its index: with a library other than the one the board
    was built with (its gait hash in INFO), that index may be another gait. proleg run says so."""
    url = f"sim://{PLANAR}?plant=table"  # built with the robot file's [gaits] library
    code = main(["run", str(PLANAR), "--port", url, "--heading", "0", "--library", "0,180", "--duration", "2"])
    _, err = capsys.readouterr()
    assert code == 1
    assert "is not the one" in err and "--exact-heading" in err and "Traceback" not in err
    assert "build and flash with the same [gaits] library" in err
    # --sim builds its board from the robot file: flashing is not the way out there
    code = main(["run", str(PLANAR), "--sim", "--heading", "0", "--library", "0,180", "--duration", "2"])
    _, err = capsys.readouterr()
    assert code == 1 and "the simulated board is built from the robot file's [gaits] library" in err, err
