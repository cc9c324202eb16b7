"""Opening a link from a URL: the registry, lazy imports, one-line errors."""

from __future__ import annotations

import subprocess
import sys

import pytest

from proleg.errors import LinkError, UsageError
from proleg.link import RobotClient, open_link
from proleg.link.factory import LINKS, link_url
from proleg.link.serial_link import SerialLink
from proleg.link.sim_link import SimLink


def test_an_unknown_scheme_is_one_line_naming_the_known_ones():
    with pytest.raises(LinkError) as e:
        open_link("usb://robot")
    assert str(e.value).startswith("usb://robot: unknown link scheme 'usb'; known: ")
    for scheme in ("can", "serial", "sim"):
        assert scheme in str(e.value)


def test_pyserial_urls_and_serial_scheme_open_a_serial_link():
    link = open_link("loop://")
    assert isinstance(link, SerialLink)
    link.close()
    with pytest.raises(LinkError, match="/dev/proleg-no-such-port"):
        open_link("serial:///dev/proleg-no-such-port")
    with pytest.raises(LinkError, match="/dev/proleg-no-such-port"):
        open_link("/dev/proleg-no-such-port")  # a bare device path


def test_sim_scheme_runs_a_bundled_robot_by_name():
    with RobotClient(open_link("sim://paper-r1")) as client:
        link = client.link
        assert isinstance(link, SimLink) and link.board.robot.name == "paper-r1"
        assert client.connect().robot_name == "paper-r1"


def test_can_url_needs_a_channel_from_itself_or_python_can_configuration(tmp_path, monkeypatch):
    for var in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))  # no ~/.canrc
    with pytest.raises(LinkError, match="no CAN channel: give one"):
        open_link("can://")
    with pytest.raises(UsageError, match=r"node: expected an integer in 0\.\.15, got 'x'"):
        open_link("can://virtual/proleg-factory?node=x")


@pytest.mark.parametrize("url, words", [
    ("can://virtual/ch0?node=abc", "can://virtual/ch0?node=abc: node: expected an integer in 0..15, got 'abc'"),
    ("can://virtual/ch0?bitrate=abc", "bitrate: expected an integer in 1..1000000, got 'abc'"),
    ("can://virtual/ch0?bitrate=0", "bitrate: expected an integer in 1..1000000, got 0"),
    ("sim://paper-r1?seed=abc", "sim://paper-r1?seed=abc: seed: expected an integer in 0..4294967295, got 'abc'"),
    ("sim://paper-r1?speed=abc", "speed: expected a finite number above 0 (times real time) or 'max', got 'abc'"),
    ("sim://paper-r1?speed=1e-9", "speed: expected at least 0.001 times real time, or 'max', got '1e-9'"),
    ("serial:///dev/ttyS0?baudrate=abc", "baudrate: expected an integer in 1..12000000, got 'abc'"),
    ("serial:///dev/ttyS0?baudrate=99999999999999", "baudrate: expected an integer in 1..12000000, got 99999999999999"),
    # pyserial's words were "Could not open port …: 'debug|info|warning|error'" and "'<=' not
    # supported between instances of 'int' and 'NoneType'", exit 1 as if the link had failed
    ("socket://localhost:99999", "socket://localhost:99999: port 99999 is outside 1..65535 (expected socket://"),
    ("socket://localhost:+5", "socket://localhost:+5: port '+5' is not a number"),
    ("socket://localhost", "socket://localhost: no TCP port (expected socket://HOST:PORT, e.g."),
    ("rfc2217://x", "rfc2217://x: no TCP port (expected rfc2217://HOST:PORT"),
])
def test_a_bad_url_setting_is_a_usage_error_naming_it(url, words):
    # these were a LinkError (exit 1) or a traceback (baudrate=abc, speed=abc)
    with pytest.raises(UsageError) as e:
        open_link(url)
    assert words in str(e.value)


def test_an_overflowing_baud_rate_from_a_library_caller_is_a_link_error():
    with pytest.raises(LinkError, match="cannot open serial port loop://"):
        SerialLink("loop://", 99999999999999, opener=lambda *a, **k: (_ for _ in ()).throw(OverflowError("too big")))


def test_cli_options_map_to_urls():
    assert link_url(port="/dev/ttyUSB0") == "/dev/ttyUSB0"
    assert link_url(can_channel="can0", interface="pcan", node=2) == "can://pcan/can0?node=2"
    assert link_url(sim="robots/paper-r1.toml") == "sim://robots/paper-r1.toml"
    with pytest.raises(LinkError, match="exactly one"):
        link_url()
    assert set(LINKS) >= {"serial", "can", "sim", "socket", "loop"}


def test_opening_a_serial_link_does_not_import_python_can_or_the_simulator():
    code = ("import sys; from proleg.link import open_link; open_link('loop://').close(); "
            "print('can' in sys.modules, 'proleg.sim.closed_loop' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def _my_robot(tmp_path, name: str = "my-worm"):
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    path = tmp_path / f"{name}.toml"
    path.write_text((root / "robots" / "paper-r1.toml").read_text().replace('name = "paper-r1"', f'name = "{name}"'))
    return path


def test_sim_name_is_the_commands_own_robot_file_when_it_is_that_name(tmp_path, capsys):
    # docs/planar.md's form with one's own robot: it looked only among the bundled robots and
    # failed on a path the user never gave
    from proleg.cli import main

    robot = _my_robot(tmp_path)
    link = open_link("sim://my-worm?plant=table", robot_file=robot)
    assert link.board.robot.name == "my-worm"
    link.close()
    assert main(["run", str(robot), "--port", "sim://my-worm?plant=table", "--duration", "1"]) == 0
    assert "my-worm on sim my-worm" in capsys.readouterr().out


def test_sim_name_matching_neither_file_nor_bundled_robot_says_how_to_name_a_file(tmp_path, capsys):
    from proleg.cli import main

    robot = _my_robot(tmp_path)
    assert main(["run", str(robot), "--port", "sim://other", "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "no such robot file" not in err
    assert err.startswith("proleg: error: sim://other: sim://other names a bundled robot (caterpillar-4, ")
    assert err.endswith(f"or the command's robot file by its file name (other.toml) (the robot file given is {robot}); "
                        "for another robot file write sim://path/to/file.toml or sim:///absolute/path/to/file.toml")
    with pytest.raises(UsageError, match="sim://nosuch names a bundled robot"):
        open_link("sim://nosuch")
    link = open_link("sim://paper-r1", robot_file=robot)  # not the file's name: the bundled robot
    assert link.board.robot.name == "paper-r1"
    link.close()


def test_a_bundled_name_stays_the_bundled_robot_even_when_the_robot_file_has_that_name(tmp_path):
    # an edited copy of paper-r1.toml is compared with the board the bundled file built
    # (test_link_watchdog: the console's identity check)
    edited = _my_robot(tmp_path, "paper-r1")
    edited.write_text(edited.read_text() + "\n# edited\n")
    link = open_link("sim://paper-r1", robot_file=edited)
    assert link.board.robot.path != edited and link.board.robot.path.name == "paper-r1.toml"
    link.close()


def test_a_one_limb_robot_on_sim_says_how_to_run_it_on_the_table_plant(tmp_path, capsys):
    """run/console/set-param/calibrate --sim on a one-limb robot ended in the physical plant's
    "(--plant table simulates it from its matrix)", an option none of them has. The error
    names the --port URL that does it, and that URL runs."""
    from proleg.cli import main

    path = tmp_path / "mono.toml"
    path.write_text('[robot]\nname = "mono"\n[[limb]]\nname = "only"\npsi_star_deg = [20.0]\nactuator = "c"\n'
                    '[[actuator]]\nname = "c"\n[transitions]\nmatrix = [[0, 1], [1, 0]]\n')
    assert main(["run", str(path), "--sim", "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip()
    hint = f'--port "sim://{path}?plant=table"'
    assert "\n" not in err and hint in err and "mono has one" in err, err
    assert "--plant table" not in err
    assert main(["run", str(path), "--port", f"sim://{path}?plant=table", "--duration", "1"]) == 0
    capsys.readouterr()
    assert main(["run", str(path), "--port", f"sim://{path}?seed=7&speed=max", "--duration", "1"]) == 2
    assert f'--port "sim://{path}?seed=7&speed=max&plant=table"' in capsys.readouterr().err  # its other settings kept
