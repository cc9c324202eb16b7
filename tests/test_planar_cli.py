"""``proleg gait`` with planar options: text, JSON, plot, library, one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from build_checks import cli as run

from proleg.cli import main

ROBOTS = Path(__file__).resolve().parents[1] / "robots"

# 2 limbs; 00 → 10 → 11 → 00 moves +x most but turns 20°; 00 → 01 → 00 moves less, straight
PLANAR = """
[robot]
name = "planar-two"
[[limb]]
name = "left"
psi_star_deg = [20.0]
actuator = "a"
[[limb]]
name = "right"
psi_star_deg = [20.0]
actuator = "b"
[[actuator]]
name = "a"
[[actuator]]
name = "b"
[transitions]
units = "mm"
matrix     = [[0, 1, 2, "x"], [0.5, 0, "x", 0], ["x", "x", 0, 2], [0, "x", 0, 0]]
dy         = [[0, 0, 0, "x"], [0, 0, "x", 0], ["x", "x", 0, 1], [0, "x", 0, 0]]
dtheta_deg = [[0, 2, 10, "x"], [-2, 0, "x", 0], ["x", "x", 0, 10], [0, "x", 0, 0]]
var_dx     = [[0, 0.1, 1, "x"], [0.1, 0, "x", 0], ["x", "x", 0, 1], [0, "x", 0, 0]]
"""


@pytest.fixture()
def robot(tmp_path) -> str:
    p = tmp_path / "planar.toml"
    p.write_text(PLANAR)
    return str(p)


def test_the_rotation_cap_picks_the_straight_gait_and_shows_its_motion(capsys, robot):
    code, out, _ = run(capsys, "gait", robot, "--heading", "0", "--max-transitions", "4", "--json")
    assert code == 0
    r = json.loads(out)["results"][0]
    assert r["gaits"][0]["states"] == ["00", "10", "11", "00"] and r["below_zero"] is False
    assert r["gaits"][0]["net_motion"]["dtheta_deg"] == pytest.approx(20.0)
    code, out, _ = run(capsys, "gait", robot, "--heading", "0", "--rotation-cap-deg", "5", "--max-transitions", "4",
                       "--json", "--cycles", "3")
    r = json.loads(out)["results"][0]
    g = r["gaits"][0]
    assert g["states"] == ["00", "01", "00"] and g["repeats"] == 2 and r["value"] == pytest.approx(3.0)
    # 1 mm straight on, turn 2°, then 0.5 mm in the turned frame, turn back: composed in SE(2)
    dx, dy = 1 + 0.5 * math.cos(math.radians(2)), 0.5 * math.sin(math.radians(2))
    assert g["net_motion"] == pytest.approx({"dx": dx, "dy": dy, "dtheta_deg": 0.0}, abs=1e-12)
    assert len(g["path"]) == 3 * 2 + 1 and g["path"][-1] == pytest.approx([3 * dx, 3 * dy, 0.0], abs=1e-12)
    assert g["entry_path"] == {"states": ["00"], "gait_step": 0}


def test_text_marks_repeats_and_a_best_below_zero(capsys, robot):
    code, out, _ = run(capsys, "gait", robot, "--heading", "0", "--rotation-cap-deg", "5", "--max-transitions", "4")
    assert code == 0 and "00 → 01 → 00    J=+1.5  ×2  N=2" in out
    assert "per pass Δx=+1.4997 Δy=+0.0174497 mm  Δθ=+0°; after 10 passes (+15, +0.1745) mm, +0°" in out
    code, out, _ = run(capsys, "gait", robot, "--heading", "0", "--transition-cost", "5", "--max-transitions", "4")
    assert "no gait scores above zero: the best one is shown" in out


def test_library_and_plot(capsys, robot, tmp_path):
    png = tmp_path / "paths.png"
    code, out, err = run(capsys, "gait", robot, "--library", "0,90,rot-ccw", "--max-transitions", "4", "--json", "--translation-cap", "5",
                         "--plot", str(png))
    assert code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {png}" in err  # stdout is the JSON alone
    doc = json.loads(out)
    assert [r["direction"] for r in doc["results"]] == ["0", "90", "rot-ccw"]
    assert all(r["gaits"] for r in doc["results"])
    assert doc["results"][2]["gaits"][0]["states"] == ["00", "10", "11", "00"]  # turns +20° a pass


@pytest.mark.parametrize("argv, message", [
    (["--heading", "0", "--rotate", "cw"], "give one of --heading, --rotate and --library"),
    (["--library", "0,north"], "'north' is neither a heading"),
    (["--heading", "0", "--plot", "out.txt"], "must end in .png"),
    (["--translation-cap", "1"], "--translation-cap only applies with --rotate"),
    # a cap that applies to none of the questions asked was taken and ignored: refused
    (["--rotate", "cw", "--rotation-cap-deg", "5"], "--rotation-cap-deg caps how far a heading's gait turns"),
    (["--library", "rot-ccw", "--rotation-cap-deg", "0"], "does not apply to rot-ccw"),
    (["--heading", "0", "--translation-cap", "1"], "--translation-cap bounds a turn's drift"),
    (["--library", "0,90", "--translation-cap", "1"], "not to headings"),
])
def test_planar_mistakes_are_one_line(capsys, robot, argv, message):
    code, _, err = run(capsys, "gait", robot, "--max-transitions", "4", *argv)
    assert code == 2 and message in err and "Traceback" not in err and err.count("\n") == 1


def test_a_rotation_cap_on_a_robot_without_dtheta_is_one_line(capsys):
    code, _, err = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--rotation-cap-deg", "5")
    assert code == 2 and "needs [transitions].dtheta_deg" in err


def test_a_heading_on_a_robot_without_dy_names_the_file_and_the_heading(capsys):
    code, _, err = run(capsys, "gait", str(ROBOTS / "paper-r1.toml"), "--heading", "90")
    assert code == 2 and "paper-r1.toml: heading 90° (off the x axis) needs [transitions].dy" in err


def test_build_with_a_library_the_robot_file_cannot_answer_names_the_file_as_gait_does(capsys, tmp_path):
    for library, needs in (("0,90", "heading 90° (off the x axis) needs [transitions].dy"),
                           ("rot-cw", "a rotation gait needs [transitions].dtheta_deg")):
        code, out, err = run(capsys, "build", str(ROBOTS / "paper-r1.toml"), "--board", "host-sim",
                             "--library", library, "-o", str(tmp_path / "fw"))
        assert code == 2 and out == "" and f"paper-r1.toml: {needs} in the robot file" in err, err


def test_evaluate_with_library_names_library_not_an_option_from_the_gaits_table(capsys):
    """planar-4's [gaits] table fills --library's other options; --evaluate named the first of
    them (--variance-weight), an option the user had not given."""
    code, _, err = run(capsys, "gait", str(ROBOTS / "planar-4.toml"), "--evaluate", "0000,0010,0000",
                       "--library", "0")
    assert code == 2 and "--library: not with --evaluate" in err


def test_a_negative_transition_cost_in_the_gaits_table_is_refused_as_on_the_command_line(tmp_path, capsys):
    text = (ROBOTS / "planar-4.toml").read_text()
    assert "transition_cost = 0.05" in text
    bad = tmp_path / "neg.toml"
    bad.write_text(text.replace("transition_cost = 0.05", "transition_cost = -1", 1))
    code, _, err = run(capsys, "gait", str(bad), "--library", "0")
    assert code == 2 and "transition_cost: expected a number in [0, 1e+09]" in err and "Traceback" not in err


@pytest.mark.parametrize("option, value", [("--transition-cost", "1e308"), ("--variance-weight", "1e308"),
                                           ("--variance-weight", "0,0,1e10")])
def test_a_penalty_past_a_matrix_entrys_bound_is_refused_not_overflowed(capsys, option, value):
    """κ or λ of 1e308 overflowed the gait search's sums to −inf: RuntimeWarnings and "no gait",
    where 1e300 listed the best gait below zero."""
    with pytest.raises(SystemExit) as e:
        main(["gait", str(ROBOTS / "planar-4.toml"), option, value, "--heading", "0"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and f"argument {option}: expected a number in [0, 1e+09], got '" in err
    assert "RuntimeWarning" not in err


def test_gait_library_answers_what_the_firmware_carries(capsys):
    """planar-4's [gaits] asks rate, variance weight, transition cost, rotation cap and simple
    cycles: `gait --library` answered with objective total and none of them, so it did not show
    the library the build puts in the firmware."""
    from proleg.firmware.gaits import firmware_gaits
    from proleg.robot import load_robot

    path = ROBOTS / "planar-4.toml"
    code, out, err = run(capsys, "gait", str(path), "--library", "0,90,180,270,rot-cw,rot-ccw", "--json")
    assert code == 0, err
    results = json.loads(out)["results"]
    assert {r["objective"] for r in results} == {"rate"}
    carried = {g.heading.name: tuple(g.gait.states) for g in firmware_gaits(load_robot(path)).library}
    shown = {r["direction"]: tuple(load_robot(path).transitions.index(s) for s in r["gaits"][0]["states"])
             for r in results if r["gaits"]}
    assert shown == carried


def test_a_library_on_a_robot_of_many_states_takes_the_builds_bound(capsys, tmp_path):
    """Five binary limbs (32 states): `gait` bounds the total objective by itself (2 · 5 = 10),
    but `gait --library` and `build --library` refused: 'needs an explicit max_transitions'."""
    lines = ["[robot]", 'name = "five"']
    for i in range(5):
        lines += ["[[limb]]", f'name = "l{i}"', "psi_star_deg = [20.0]", f'actuator = "a{i}"']
    for i in range(5):
        lines += ["[[actuator]]", f'name = "a{i}"', f"channel = {i}"]
    n = 32
    def cell(a: int, b: int) -> str:  # one limb at a time, each limb its own rewards (few ties)
        k = (a ^ b).bit_length()
        return "0" if a == b else (f"{1 + k / 10}" if a < b else f"{-0.5 - k / 100}") if bin(a ^ b).count("1") == 1 \
            else '"x"'

    rows = ["[" + ", ".join(cell(a, b) for b in range(n)) + "]" for a in range(n)]
    dy = ["[" + ", ".join("0" if cell(a, b) != '"x"' else '"x"' for b in range(n)) + "]" for a in range(n)]
    lines += ["[transitions]", "matrix = [" + ", ".join(rows) + "]", "dy = [" + ", ".join(dy) + "]"]
    path = tmp_path / "five.toml"
    path.write_text("\n".join(lines) + "\n")
    code, out, err = run(capsys, "gait", str(path), "--library", "0", "--json")
    assert code == 0, err
    assert {r["max_transitions"] for r in json.loads(out)["results"]} == {10}


def test_the_physical_plant_says_it_does_not_model_a_robot_that_moves_in_the_plane(caplog):
    """planar-4 on the physical plant is four contacts in a row moving along x: the plant says
    so (naming the row it lays out) for a file with planar statistics, and not for R1."""
    from proleg.robot import load_robot
    from proleg.sim.closed_loop import make_plant

    with caplog.at_level("WARNING", logger="proleg.sim.closed_loop"):
        make_plant(load_robot(ROBOTS / "paper-r1.toml"), "physical")
        assert not [r for r in caplog.records if "planar statistics" in r.getMessage()]
        make_plant(load_robot(ROBOTS / "planar-4.toml"), "physical")
    lines = [r.getMessage() for r in caplog.records if "planar statistics" in r.getMessage()]
    assert len(lines) == 1 and "in a row in file order (front, left, back, right)" in lines[0]
    assert "--plant table" in lines[0]


def test_check_of_a_planar_robot_gives_the_plant_as_the_reason_not_a_matrix_to_measure(capsys):
    code, _, err = run(capsys, "check", str(ROBOTS / "planar-4.toml"), "--rows", "1")
    assert code == 1
    assert "planar statistics describe a body that moves in the plane" in err
    assert "--measure-matrix" not in err.splitlines()[-1]


def test_only_a_planar_motion_makes_a_table_move_in_the_plane(tmp_path):
    """dy or dθ (planar-4) is a motion in the plane; variances alone (a learned file's var_dx)
    are not: the physical plant's warning, learn's pose and check's advice all ask this."""
    from proleg.robot import load_robot

    learned = tmp_path / "learned.toml"
    learned.write_text(PLANAR.replace("dy         =", "#dy =").replace("dtheta_deg =", "#dtheta_deg ="))
    assert load_robot(ROBOTS / "planar-4.toml").transitions.moves_in_plane
    assert load_robot(learned).transitions.planar is not None  # var_dx is there
    assert not load_robot(learned).transitions.moves_in_plane
    assert not load_robot(ROBOTS / "paper-r1.toml").transitions.moves_in_plane
