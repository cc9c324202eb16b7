"""Opening a link from a URL: the registry, lazy imports, one-line errors."""

from __future__ import annotations

import subprocess
import sys

import pytest

from proleg.errors import LinkError
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
    with pytest.raises(LinkError, match="node must be an integer"):
        open_link("can://virtual/proleg-factory?node=x")


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
