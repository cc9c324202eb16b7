"""The CLI's number parsers (``proleg.cli.number_args``): what each accepts, and the one line a
user gets for a bad value of every option that uses one (exit 2, nothing run)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from proleg.cli import main
from proleg.cli.number_args import (
    finite_float,
    gait_index,
    heading_deg,
    int_auto,
    non_negative_float,
    positive_float,
    positive_int,
    reply_timeout,
)

R1 = str(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")


@pytest.mark.parametrize(
    "parse, text, value",
    [
        (positive_int, "3", 3),
        (int_auto, "0x10", 16),
        (int_auto, "-2", -2),
        (finite_float, "-1.5", -1.5),
        (non_negative_float, "0", 0.0),
        (positive_float, "0.25", 0.25),
        (heading_deg, "-450", -450.0),
        (gait_index, "0", 0),
        (gait_index, " User ", 0xFF),
        (reply_timeout, "0.01", 0.01),
        (reply_timeout, "60", 60.0),
    ],
)
def test_each_parser_returns_the_number_it_reads(parse, text, value):
    assert parse(text) == value


@pytest.mark.parametrize(
    "parse, text",
    [
        (positive_int, "0"),
        (positive_int, "1.5"),
        (int_auto, "ten"),
        (finite_float, "inf"),
        (non_negative_float, "-0.1"),
        (positive_float, "nan"),
        (positive_float, "-1"),
        (positive_float, "inf"),
        (positive_float, "1e400"),
        (heading_deg, "nan"),
        (gait_index, "-1"),
        (gait_index, "first"),
        (reply_timeout, "0"),
        (reply_timeout, "0.001"),
        (reply_timeout, "60.5"),  # a board that stopped answering kept the command waiting (1e9: 31 years)
    ],
)
def test_each_parser_refuses_what_it_does_not_take(parse, text):
    with pytest.raises(argparse.ArgumentTypeError):
        parse(text)


@pytest.mark.parametrize(
    "argv, line",
    [
        (["sim", R1, "--duration", "0"], "argument --duration: expected a finite number above 0, got 0"),
        (["sim", R1, "--duration", "inf"], "argument --duration: expected a finite number above 0, got inf"),
        (["console", "--sim", "paper-r1", "--plain", "--duration", "0"],
         "argument --duration: expected a finite number above 0, got 0"),
        (["gait", ""], "argument ROBOT: expected a robot file or a bundled robot's name, got ''"),
        (["build", R1, "--board", "host-sim", "--max-transitions", "x"],
         "argument --max-transitions: expected a whole number, got 'x'"),
        (["gait", R1, "--cycles", "0"], "argument --cycles: expected at least 1, got 0"),
        (["gait", R1, "--cycles", "1000000000"], "argument --cycles: expected at most 10,000 passes, got 1000000000"),
        (["gait", R1, "--max-transitions", "99999"],
         "argument --max-transitions: expected a whole number of transitions in 2..256 (a gait has at least 2), got 99999"),
        (["sim", R1, "--max-transitions", "1"],
         "argument --max-transitions: expected a whole number of transitions in 2..256 (a gait has at least 2), got 1"),
        (["build", R1, "--board", "host-sim", "--max-transitions", "257"],
         "argument --max-transitions: expected a whole number of transitions in 2..256 (a gait has at least 2), got 257"),
        (["sim", R1, "--gait", "-1"], "argument --gait: expected a gait index ≥ 0, got -1"),
        (["gait", R1, "--heading", "inf"], "argument --heading: expected a heading in degrees within ±3600, got inf"),
        (["gait", R1, "--heading", "1e308"], "argument --heading: expected a heading in degrees within ±3600, got 1e308"),
        (["gait", R1, "--rotation-cap-deg", "-1"], "argument --rotation-cap-deg: expected a number >= 0, got '-1'"),
        (["run", R1, "--heading", "north"], "argument --heading: expected a heading in degrees, got 'north'"),
        (["run", R1, "--gait", "-1"], "argument --gait: expected a gait index ≥ 0, got -1"),
        (["run", R1, "--gait", "x"], "argument --gait: expected a gait index or 'user', got 'x'"),
        (["run", R1, "--duration", "soon"], "argument --duration: expected a number, got 'soon'"),
        (["run", R1, "--duration", "1_0"], "argument --duration: expected a number, got '1_0'"),  # float(): 10
        (["run", R1, "--gait", "1_0"], "argument --gait: expected a gait index or 'user', got '1_0'"),  # int(): 10
        (["check", R1, "--rows", "1_0"], "argument --rows: expected a whole number, got '1_0'"),
        (["console", "--node", "0x_f"], "argument --node: expected an integer (0x.. for hex), got '0x_f'"),
        (["set-param", "--port", "/dev/null", "drive_duty", "5_000"],
         "argument VALUE: expected a whole number, got '5_000'"),
        (["set-param", "--port", "/dev/null", "drive_duty", "lots"], "argument VALUE: expected a whole number, got 'lots'"),
        # refused by the codec after the port was opened (a Nano resets then), in its own words
        (["set-param", "--port", "/dev/null", "hold_ms", "99999999999"],
         "argument VALUE: expected a whole number in -2,147,483,648..2,147,483,647 (SET_PARAM's 32-bit value; each "
         "parameter's range: docs/control.md), got 99999999999"),
        (["run", R1, "--sim", "--progress", "0.00001"],
         "argument --progress: expected at least 0.1 s between progress lines, got 0.00001"),
        (["console", "--node", "zz"], "argument --node: expected an integer (0x.. for hex), got 'zz'"),
        (["learn", R1, "--node", "one"], "argument --node: expected an integer (0x.. for hex), got 'one'"),
        (["learn", R1, "--repeats", "-3"], "argument --repeats: expected at least 1, got -3"),
        # a simulated second in 32 years: run --sim --duration 1 never ended
        (["run", R1, "--sim", "--speed", "1e-9"],
         "argument --speed: expected at least 0.001 times real time (a simulated second in 17 minutes), got 1e-9"),
        (["sim", R1, "--pty", "--speed", "0.0001"],
         "argument --speed: expected at least 0.001 times real time (a simulated second in 17 minutes), got 0.0001"),
        # a run that would never end: its header said 11999999988 trials, and planning them took 10 GB
        (["learn", R1, "--repeats", "999999999"],
         "argument --repeats: expected at most 100,000 trials per transition, got 999999999"),
        (["run", R1, "--sim", "--timeout", "0.001"],
         "argument --timeout: expected at least 0.01 s (a reply takes a few ms), got 0.001"),
        (["run", R1, "--port", "/dev/ttyS0", "--baudrate", "-5"],
         "argument --baudrate: expected a baud rate in 1..12,000,000, got -5"),
        (["console", "--port", "/dev/ttyS0", "--baudrate", "99999999999999"],
         "argument --baudrate: expected a baud rate in 1..12,000,000, got 99999999999999"),
        (["learn", R1, "--port", "x", "--baudrate", "fast"],
         "argument --baudrate: expected a baud rate (a whole number), got 'fast'"),
        (["calibrate", R1, "--can", "x", "--bitrate", "0"],
         "argument --bitrate: expected a CAN bit rate in bit/s in 1..1,000,000, got 0"),
        (["calibrate", R1, "--can", "x", "--node", "99"], "argument --node: expected a CAN node id in 0..15, got 99"),
        (["dbc", "-o", "x.dbc", "--node", "16"], "argument --node: expected a CAN node id in 0..15, got 16"),
        # a nan, inf or 1e300 offset was taken, and the error after reading log and track said the
        # trials lay at "nan..nan s on its clock (offset +nan s, given)"
        (["learn", R1, "--log", "t.jsonl", "--track", "t.csv", "--tracker-offset", "nan"],
         "argument --tracker-offset: expected seconds within ±1e9 (the track's times), got 'nan'"),
        (["learn", R1, "--log", "t.jsonl", "--track", "t.csv", "--tracker-offset=-inf"],
         "argument --tracker-offset: expected seconds within ±1e9 (the track's times), got '-inf'"),
        (["learn", R1, "--log", "t.jsonl", "--track", "t.csv", "--tracker-offset", "1e300"],
         "argument --tracker-offset: expected seconds within ±1e9 (the track's times), got '1e300'"),
    ],
)
def test_a_bad_number_is_one_line_naming_the_option_and_exit_2(capsys, argv, line):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    _, err = capsys.readouterr()
    assert exit_.value.code == 2
    assert err.strip().splitlines()[-1].endswith(line)



def test_every_command_that_takes_can_takes_its_settings_too():
    """learn took --can with no --bitrate: a CAN robot at another bit rate could not be learned."""
    import argparse

    from proleg.cli.main import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    with_can = {name: {o for a in p._actions for o in a.option_strings}
                for name, p in sub.choices.items() if any("--can" in a.option_strings for a in p._actions)}
    assert {"learn", "run", "console", "calibrate"} <= set(with_can)
    for name, options in with_can.items():
        assert {"--bitrate", "--node", "--interface"} <= options, name


@pytest.mark.parametrize("argv", [["sim", R1, "--duration=--"], ["gait", R1, "--max-transitions=--"],
                                  ["run", R1, "--sim", "--states=--"], ["check", R1, "--rows=--"]])
def test_an_option_given_a_bare_double_dash_is_a_usage_error(capsys, argv):
    """Python 3.11's argparse hands --option=-- an empty list without its type: sim
    --duration=-- was a TypeError traceback, --max-transitions=-- said "got []"."""
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and "expected a value, got '--'" in err and "Traceback" not in err


@pytest.mark.parametrize("command", [["check", "paper-r1", "--rows", "1"], ["sim", "paper-r1", "--measure-matrix", "--hold-range"]])
def test_jobs_past_what_a_machine_holds_are_refused(capsys, command):
    """``--jobs 1000`` started a thousand simulated robots (100-200 MB each) before any row ran."""
    with pytest.raises(SystemExit) as e:
        main([*command, "--jobs", "1000"])
    assert e.value.code == 2
    assert "argument --jobs: expected at most 64 worker processes, got 1000" in capsys.readouterr().err
