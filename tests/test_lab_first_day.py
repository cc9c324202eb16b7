"""A lab's first day with a robot of its own and no matrix yet: the mistakes it makes in
``[transitions] matrix = "unmeasured"`` / ``allow`` and in the learn flow, and what the
tools say about the files it writes (tests/test_unmeasured.py has the flow that works)."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.errors import RobotFileError
from proleg.robot import load_robot

_LIMBS = "".join(f'[[limb]]\nname = "l{i}"\npsi_star_deg = [20.0]\nactuator = "a{i}"\nfriction = "D1"\n\n'
                 f'[[actuator]]\nname = "a{i}"\n\n' for i in range(2))


def _robot(tmp_path: Path, transitions: str, name: str = "lab.toml") -> Path:
    path = tmp_path / name
    path.write_text(f'[robot]\nname = "lab"\n\n{_LIMBS}[transitions]\n{transitions}\n', encoding="utf-8")
    return path


@pytest.mark.parametrize("word", ["unmesured", "Unmeasured"])
def test_a_misspelt_unmeasured_beside_allow_is_named_as_the_matrix_not_the_allow(tmp_path, word):
    """It used to say 'transitions.allow: expected matrix = "unmeasured" beside it', which
    sends the lab to the key it wrote right."""
    with pytest.raises(RobotFileError) as e:
        load_robot(_robot(tmp_path, f'matrix = "{word}"\nallow = "one-level"'))
    assert "transitions.matrix: expected 4 rows of 4 entries, or \"unmeasured\"" in str(e.value)
    assert f"got '{word}'" in str(e.value) or f'got "{word}"' in str(e.value)


def test_allow_beside_a_written_matrix_is_still_refused_on_allow(tmp_path):
    with pytest.raises(RobotFileError, match='transitions.allow: expected matrix = "unmeasured" beside it'):
        load_robot(_robot(tmp_path, 'matrix = [[0, 1, 1, "x"], [1, 0, "x", 1], [1, "x", 0, 1], ["x", 1, 1, 0]]\n'
                                    'allow = "any"'))


_LEARNED = ('units = "mm"\nmatrix = [[0, 0.2, -0.1, "x"], [0.1, 0, "x", 0.3], [0.2, "x", 0, -0.1], ["x", 0.1, 0.2, 0]]\n'
            'n_trials = [[0, 2, 2, "x"], [2, 0, "x", 2], [2, "x", 0, 2], ["x", 2, 2, 0]]\n'
            'var_dx = [[0, 0.01, 0.02, "x"], [0.01, 0, "x", 0.01], [0.01, "x", 0, 0.03], ["x", 0.01, 0.01, 0]]\n')


def test_a_learned_file_with_variances_alone_is_not_warned_about_as_a_planar_robot(tmp_path):
    """learn --out writes var_dx and n_trials beside the matrix; every physical-plant run of
    such a file (sim, run --sim, check) said '[transitions] has planar statistics (dy,
    dtheta_deg): a robot that moves in the plane', of a worm that has none."""
    from proleg.sim.plant_warnings import planar_warnings

    assert planar_warnings(load_robot(_robot(tmp_path, _LEARNED))) == []
    dy = 'dy = [[0, 0.1, 0.1, "x"], [0.1, 0, "x", 0.1], [0.1, "x", 0, 0.1], ["x", 0.1, 0.1, 0]]\n'
    lines = planar_warnings(load_robot(_robot(tmp_path, _LEARNED + dy, "planar.toml")))
    assert len(lines) == 1 and "has planar statistics (dy, dtheta_deg)" in lines[0]



def _relearn(tmp_path, capsys, *extra):
    from build_checks import cli

    learned = _robot(tmp_path, _LEARNED + "\n[control]\ntick_hz = 500\n")
    log = tmp_path / f"again{len(extra)}.jsonl"
    code, _, err = cli(capsys, "learn", learned, "--sim", *extra, "--repeats", "1", "--max-pieces", "1", "--log", log)
    assert code == 0, err
    return err, log


def test_relearning_a_learned_file_learns_the_body_not_the_files_own_means(tmp_path, capsys):
    """A learned file learned again with --sim: the table plant (--sim's default then) moved by
    the file's own learned matrix, so the trials handed its means back, and nothing said so.
    --sim learns on the physical plant now unless --truth gives a matrix to hide; the table
    plant asked for by name still says what it does."""
    err, _ = _relearn(tmp_path, capsys)
    assert "(physical plant)" in err and "was learned" not in err
    err, _ = _relearn(tmp_path, capsys, "--plant", "table")
    assert "was learned (it has n_trials), and the table plant moves by its matrix" in err


def test_a_truth_with_variances_alone_logs_no_planar_motion(tmp_path, capsys):
    """The learned file's var_dx made the table plant move a planar pose, and every trial's Δy
    and Δθ were logged as 0, then written as dy, dtheta_deg: a worm turned into a planar robot."""
    import json

    _, log = _relearn(tmp_path, capsys, "--plant", "table")
    trials = [json.loads(line) for line in log.read_text().splitlines()[1:]]
    assert trials and all(t["dy"] is None and t["dtheta_deg"] is None for t in trials)


def test_the_learn_commands_the_build_suggests_for_an_unmeasured_robot_parse(tmp_path, capsys):
    """The build (and sim, run, check) of an unmeasured robot said to run `proleg learn ROBOT
    --sim --out LEARNED.toml`; typed as given it stopped at 'the following arguments are
    required: --log'."""
    import re
    import shlex

    from proleg.cli.main import build_parser
    from proleg.firmware.gaits import firmware_gaits

    robot = load_robot(_robot(tmp_path, 'matrix = "unmeasured"\nallow = "one-level"'))
    line = firmware_gaits(robot).left_out_line("+x")
    commands = re.findall(r"\((proleg learn [^)]*?)(?:,|\))", line)
    assert len(commands) == 2, line
    for command in commands:
        argv = shlex.split(command.replace("ROBOT", "lab.toml").replace("PORT", "/dev/ttyUSB0"))[1:]
        args = build_parser().parse_args(argv)
        assert args.log is not None and args.out is not None


def test_forbidden_marks_that_cut_a_part_off_from_rest_leave_it_out_instead_of_stopping_learning(tmp_path, capsys):
    """Marks that leave no way from rest (00) into 01 and 11: their own tour 01 <-> 11 was
    planned all the same (28 of a worm's 37 transitions, when every way out of rest was
    marked), and learning stopped at once: 'no piece within the thermal limits ([safety]
    max_on_ms, ...) reaches ...' of a robot whose limits had nothing to do with it."""
    from build_checks import cli

    path = _robot(tmp_path, 'matrix = "unmeasured"\nallow = "one-level"\nforbidden = ["00->01", "10->11"]\n'
                            "\n[control]\ntick_hz = 500\n")
    code, _, err = cli(capsys, "learn", path, "--sim", "--repeats", "1", "--log", tmp_path / "t.jsonl")
    assert code == 0, err
    assert "4 of them unreachable from rest (01->00, 01->11, 11->01, 11->10): 2 × 1 = 2 trials" in err
    assert "thermal limits" not in err

    cut = _robot(tmp_path, 'matrix = "unmeasured"\nallow = "one-level"\nforbidden = ["00->01", "00->10"]', "cut.toml")
    code, _, err = cli(capsys, "learn", cut, "--sim", "--repeats", "1", "--log", tmp_path / "cut.jsonl")
    assert code == 2 and "none of its 6 allowed transitions is on a closed tour from rest" in err
    assert "6 unreachable from rest" in err and 'with matrix = "unmeasured": its allow and forbidden' in err
    assert not (tmp_path / "cut.jsonl").exists()
