"""``--udp HOST:PORT`` is read and its host resolved before a command opens anything
(``record.udp.resolve_endpoint``, from ``cli.main.udp_options``): a host that resolved to
nothing was said only once the robot was connected (the simulated board built and booted,
a real one reset by the port's opening), and a ``--record`` file was left behind holding its
header alone; a host name with an empty label (``a..b``) ended in a UnicodeError traceback."""

from __future__ import annotations

import socket

import pytest

from build_checks import cli
from proleg.errors import LinkError, UsageError
from proleg.record.udp import parse_endpoint, resolve_endpoint

EXAMPLE = "expected HOST:PORT, e.g. 127.0.0.1:9870"

COMMANDS = {
    "sim": ("sim", "paper-r1", "--duration", "1"),
    "run": ("run", "paper-r1", "--sim", "--duration", "1"),
    "console": ("console", "--sim", "paper-r1", "--plain", "--duration", "1"),
}


@pytest.fixture
def nothing_opens(monkeypatch):
    """Opening a link or the simulated board fails the test: the endpoint is checked first."""
    from proleg.cli import link_commands, robot_commands
    from proleg.sim import simulators

    def opened(*args, **kwargs):  # pragma: no cover (must not be reached)
        raise AssertionError("opened before --udp was checked")

    monkeypatch.setattr(simulators, "open_simulated", opened)
    monkeypatch.setattr(link_commands, "open_link", opened)
    monkeypatch.setattr(robot_commands, "open_client", opened)


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("endpoint, message", [
    ("nosuchhost.invalid:9870", "--udp nosuchhost.invalid:9870: no host 'nosuchhost.invalid' (Name or service not "
                                "known); expected HOST:PORT of a host that resolves, e.g. 127.0.0.1:9870"),
    ("localhost:99999", f"--udp localhost:99999: port 99999 is outside 1..65535 ({EXAMPLE})"),
    ("localhost:0", f"--udp localhost:0: port 0 is outside 1..65535 ({EXAMPLE})"),
    (":x", f"--udp :x: no HOST before ':' ({EXAMPLE})"),
    ("host:x", f"--udp host:x: port 'x' is not a number ({EXAMPLE})"),
    ("host:", f"--udp host:: no PORT after ':' ({EXAMPLE})"),
    ("nowhere", f"--udp nowhere: no ':PORT' ({EXAMPLE})"),
    ("a..b:5", f"--udp a..b:5: 'a..b' is no host name; {EXAMPLE}"),
])
def test_a_bad_udp_endpoint_is_one_line_before_anything_opens(capsys, monkeypatch, tmp_path, nothing_opens,
                                                              command, endpoint, message):
    real = socket.getaddrinfo

    def getaddrinfo(host, *args, **kwargs):  # no DNS needed: .invalid never resolves
        if host.endswith(".invalid"):
            raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")
        return real(host, *args, **kwargs)

    monkeypatch.setattr(socket, "getaddrinfo", getaddrinfo)
    record = tmp_path / "run.csv"
    code, out, err = cli(capsys, *COMMANDS[command], "--record", record, "--udp", endpoint)
    assert (code, out, err) == (2, "", f"proleg: error: {message}\n")
    assert not record.exists()  # no recording left with its header alone


def test_a_resolver_that_cannot_answer_is_a_link_failure_said_first(capsys, monkeypatch, tmp_path, nothing_opens):
    def offline(*args, **kwargs):
        raise socket.gaierror(socket.EAI_AGAIN, "Temporary failure in name resolution")

    monkeypatch.setattr(socket, "getaddrinfo", offline)
    code, _, err = cli(capsys, *COMMANDS["run"], "--udp", "plotter.lab:9870")
    assert (code, err) == (1, "proleg: error: --udp plotter.lab:9870: cannot resolve 'plotter.lab' now (Temporary "
                              "failure in name resolution): is the network up? (an IP address needs no resolver)\n")


def test_endpoints_that_are_fine():
    assert parse_endpoint("[::1]:9870") == ("::1", 9870)
    assert parse_endpoint(" localhost : 9870 ") == ("localhost", 9870)
    e = resolve_endpoint("127.0.0.1:9870")
    assert (e.host, e.port, e.family, e.address) == ("127.0.0.1", 9870, socket.AF_INET, ("127.0.0.1", 9870))
    with pytest.raises(UsageError):
        resolve_endpoint("127.0.0.1:65536")
    assert not issubclass(UsageError, LinkError)


def _telemetry_rx():
    """One TELEMETRY frame of paper-r1, as a listener receives it."""
    from types import SimpleNamespace

    fields = {"time_ms": 20, "seq": 1, "measured": 0, "target": 0, "gait": 0, "direction": 0, "step": 0,
              "flags": 0, "psi": [0, 0], "duty": [0, 0]}
    return SimpleNamespace(message=SimpleNamespace(name="TELEMETRY", fields=fields), time=0.02, truth={})


def _streamer(endpoint: str):
    from proleg.record import RecordingMeta, UdpStreamer
    from proleg.paths import robots_dir
    from proleg.robot import load_robot

    meta = RecordingMeta.for_robot(robot=load_robot(robots_dir() / "paper-r1.toml"))
    return UdpStreamer(endpoint, "plotjuggler", meta)


def test_a_broadcast_address_is_streamed_to():
    """Every send to 255.255.255.255 (or a subnet's .255, PlotJuggler on another machine of the
    LAN) failed with EACCES without SO_BROADCAST: nothing streamed, nothing said, exit 0."""
    streamer = _streamer("255.255.255.255:9870")
    try:
        streamer.on_message(_telemetry_rx())
        if streamer.errors and not streamer.sent:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:  # no broadcast route here at all?
                s.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
                try:
                    s.sendto(b"x", ("255.255.255.255", 9870))
                except OSError as e:
                    pytest.skip(f"this machine sends no broadcast: {e}")
        assert (streamer.sent, streamer.errors) == (1, 0)
    finally:
        streamer.stop()


def test_a_send_that_fails_but_for_nobody_listening_is_said_once(caplog):
    import errno

    streamer = _streamer("127.0.0.1:9870")

    class Failing:
        def __init__(self, code: int):
            self.code = code

        def sendto(self, data, addr):
            raise OSError(self.code, {errno.EACCES: "Permission denied", errno.ECONNREFUSED: "Connection refused"}
                          [self.code])

        def close(self):
            pass

    streamer._sock = Failing(errno.ECONNREFUSED)  # nobody listening yet: the stream's ordinary lot
    for _ in range(3):
        streamer.on_message(_telemetry_rx())
    assert streamer.errors == 3 and not caplog.records
    streamer._sock = Failing(errno.EACCES)
    for _ in range(3):
        streamer.on_message(_telemetry_rx())
    assert streamer.errors == 6
    assert [r.getMessage() for r in caplog.records] == [
        "warning: --udp 127.0.0.1:9870: cannot send (Permission denied): the stream does not reach it; the run goes on"]
    streamer.stop()
