"""The commands that talk to a robot take their link options from one place
(``cli.robot_link.add_link_options``): learn spelled its own copy, whose --port help had
drifted from run's."""

from __future__ import annotations

import argparse

from proleg.cli.main import build_parser

LINK = ("--port", "--can", "--interface", "--bitrate", "--node", "--baudrate", "--timeout")


def _options(command: str) -> dict[str, tuple]:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    return {opt: (a.help, a.metavar, a.type, a.default)
            for a in sub._actions for opt in a.option_strings if opt in LINK}


def test_every_command_on_a_link_offers_the_same_link_options_in_the_same_words():
    run = _options("run")
    assert set(run) == set(LINK)
    for command in ("load-gait", "set-param", "calibrate", "learn"):
        assert _options(command) == run, command
