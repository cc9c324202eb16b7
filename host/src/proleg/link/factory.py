"""Open a link from one URL-like string, python-can style: a registry of schemes, each
opener imported only when used (so opening a serial port never imports python-can).

    open_link("/dev/ttyUSB0")                         # a bare device path (or COM3, a pty path)
    open_link("serial:///dev/ttyUSB0", baudrate=115200)
    open_link("socket://host:7000")                   # any pyserial URL (socket, rfc2217, loop...)
    open_link("can://socketcan/can0?node=1&bitrate=500000")
    open_link("can://can0")                           # interface, bit rate from python-can's config
    open_link("can://")                               # channel too (CAN_CHANNEL, ~/.canrc)
    open_link("sim://paper-r1")                       # a bundled robot, or sim://path/to/ROBOT.toml
    open_link("sim://planar-4?plant=table")           # ... on the table plant (planar pose)
    open_link("sim://tri?plant=table", robot_file="lab/tri.toml")  # the command's own robot file

``sim://NAME`` is the bundled robot NAME, else the command's robot file when it is NAME.toml
(``robot_file``: the ROBOT argument, ``proleg run lab/tri.toml --port sim://tri``); one that
is neither is a ``UsageError`` saying how to name a file (``sim:///abs/path.toml``).

A ``sim://`` link's ``board`` is the ``SimulatedRobot`` (``link.board.robot`` its description).
An unknown scheme is a ``LinkError`` naming the known ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import parse_qsl, urlsplit

from ..errors import LinkError, UsageError
from .base import Link

#: pyserial's own URL schemes (``serial.serial_for_url``): passed to the serial link whole
PYSERIAL_SCHEMES = ("socket", "rfc2217", "loop", "spy", "alt", "hwgrep")


def _open_serial(url: str, rest: str, query: dict[str, str], options: dict[str, Any]) -> Link:
    from .serial_link import DEFAULT_BAUDRATE, SerialLink

    scheme = url.split("://", 1)[0]
    port = url if scheme in PYSERIAL_SCHEMES or "://" not in url else rest
    if not port:
        raise LinkError(f"{url}: no serial device (expected serial:///dev/ttyUSB0)")
    if scheme in NETWORK_SCHEMES:
        _network_port(url, scheme)
    from .serial_link import MAX_BAUDRATE

    baudrate = _int(url, "baudrate", query.get("baudrate", options.get("baudrate") or DEFAULT_BAUDRATE), 1, MAX_BAUDRATE)
    return SerialLink(port, baudrate)


#: pyserial's schemes that connect to HOST:PORT over TCP
NETWORK_SCHEMES = ("socket", "rfc2217")


def _network_port(url: str, scheme: str) -> int:
    """A ``socket://`` or ``rfc2217://`` URL's TCP port, 1..65535; a ``UsageError`` naming what is
    wrong. pyserial said "Could not open port socket://host:99999: 'debug|info|warning|error'"
    for a port out of range or not a number, and "'<=' not supported between instances of 'int'
    and 'NoneType'" for none at all (exit 1, as if the link had failed)."""
    example = f"expected {scheme}://HOST:PORT, e.g. {scheme}://127.0.0.1:7000"
    netloc = urlsplit(url).netloc
    _host, colon, text = netloc.rpartition(":")
    if not colon or not text or "]" in text:
        raise UsageError(f"{url}: no TCP port ({example})")
    if not text.isascii() or not text.isdigit():  # pyserial reads digits alone ('+5' failed as 'abc' did)
        raise UsageError(f"{url}: port {text!r} is not a number ({example})")
    port = int(text)
    if not 1 <= port <= 65535:
        raise UsageError(f"{url}: port {port} is outside 1..65535 ({example})")
    return port


def _open_can(url: str, rest: str, query: dict[str, str], options: dict[str, Any]) -> Link:
    from .can_link import CanLink

    # can://INTERFACE/CHANNEL, can://CHANNEL or can:// — the rest from python-can's configuration
    interface, slash, channel = rest.partition("/")
    if not slash:
        interface, channel = "", interface
    from ..protocol.can import MAX_NODE
    from .can_link import MAX_BITRATE

    bitrate = query.get("bitrate", options.get("bitrate"))
    return CanLink(channel or None, interface or query.get("interface") or options.get("interface"),
                   node=_int(url, "node", query.get("node", options.get("node") or 0), 0, MAX_NODE),
                   bitrate=None if bitrate is None else _int(url, "bitrate", bitrate, 1, MAX_BITRATE))


def _open_sim(url: str, rest: str, query: dict[str, str], options: dict[str, Any]) -> Link:
    from ..robot import load_robot
    from ..sim.closed_loop import SimulatedRobot
    from .sim_link import SimLink

    if not rest:
        raise LinkError(f"{url}: expected sim://ROBOT (a bundled robot name or a robot file)")
    path = Path(rest) if rest.endswith(".toml") or "/" in rest else _named_robot(url, rest, options.get("robot_file"))
    robot = load_robot(path)
    seed = _int(url, "seed", query.get("seed", options.get("seed", 1)), 0, 2**32 - 1)
    speed = options.get("speed", None)
    if "speed" in query:
        speed = None if query["speed"] == "max" else _speed(url, query["speed"])
    plant = query.get("plant", options.get("plant"))  # "physical" (default) or "table" (the planar pose)
    if plant in (None, "physical") and len(robot.limbs) < 2:
        # the physical plant's own refusal names sim's --plant table, which run/console/set-param/
        # calibrate --sim do not have: a one-limb robot had no way to be run there
        from urllib.parse import urlencode

        kept = urlencode({**{k: v for k, v in query.items() if k != "plant"}, "plant": "table"})
        raise UsageError(f"{url}: the physical plant needs two limbs at least, {robot.name} has one: "
                        f"--port \"sim://{rest}?{kept}\" simulates it from its matrix (the table plant)")
    return SimLink(SimulatedRobot(robot, seed=seed, plant=plant), speed=speed, description=f"sim {robot.name}")


def _named_robot(url: str, name: str, robot_file: str | Path | None) -> Path:
    """The robot file ``sim://NAME`` means: the bundled robot NAME, else the command's own
    ``robot_file`` when it is NAME.toml (``UsageError`` when neither: a bad argument). The
    bundled robot comes first, so an edited copy of it is still compared with the board the
    bundled file built (the console's identity check)."""
    from ..paths import robots_dir

    bundled = robots_dir() / f"{name}.toml"
    if bundled.is_file():
        return bundled
    if robot_file is not None and Path(robot_file).name == f"{name}.toml":
        return Path(robot_file)
    known = ", ".join(sorted(p.stem for p in robots_dir().glob("*.toml")))
    mine = f" (the robot file given is {robot_file})" if robot_file is not None else ""
    raise UsageError(f"{url}: sim://{name} names a bundled robot ({known}) or the command's robot file by its "
                    f"file name ({name}.toml){mine}; for another robot file write sim://path/to/file.toml or "
                    f"sim:///absolute/path/to/file.toml")


Opener = Callable[[str, str, dict[str, str], dict[str, Any]], Link]

#: scheme -> opener(url, rest after "scheme://", query, options)
LINKS: dict[str, Opener] = {
    "serial": _open_serial,
    "can": _open_can,
    "sim": _open_sim,
    **{scheme: _open_serial for scheme in PYSERIAL_SCHEMES},
}


def register_link(scheme: str, opener: Opener) -> None:
    """Add a link type (e.g. an emulated MCU board) under ``scheme://``."""
    LINKS[scheme] = opener


def open_link(url: str, **options: Any) -> Link:
    """The link ``url`` names; ``options`` (baudrate, node, bitrate, seed, speed) fill in what
    the URL's query does not say; ``robot_file``: the command's robot file, which
    ``sim://NAME`` means when it is NAME.toml and NAME is no bundled robot."""
    if "://" not in url:
        return _open_serial(url, url, {}, options)  # a bare device path
    scheme = url.split("://", 1)[0].lower()
    opener = LINKS.get(scheme)
    if opener is None:
        raise LinkError(f"{url}: unknown link scheme {scheme!r}; known: {', '.join(sorted(LINKS))} "
                        "(or a bare device path)")
    parts = urlsplit(url)
    rest = url.split("://", 1)[1].split("?", 1)[0]
    if scheme == "serial" and rest.startswith("/") is False and parts.netloc:
        rest = parts.netloc + parts.path
    return opener(url, rest, dict(parse_qsl(parts.query)), options)


def link_url(*, port: str | None = None, can_channel: str | None = None, interface: str | None = None,
             node: int = 0, sim: str | Path | None = None, bitrate: int | None = None) -> str:
    """The URL for the CLI's ``--port`` / ``--can`` / ``--sim`` options (exactly one).
    ``can_channel=""`` and ``interface=None`` leave them to python-can's configuration."""
    chosen = [x for x in (port, can_channel, sim) if x is not None]
    if len(chosen) != 1:
        raise LinkError("give exactly one of --port URL, --can CHANNEL or --sim ROBOT.toml")
    if port is not None:
        return port
    if can_channel is not None:
        where = f"{interface}/{can_channel}" if interface else can_channel
        return f"can://{where}?node={node}" + (f"&bitrate={bitrate}" if bitrate is not None else "")
    return f"sim://{sim}"


def _int(url: str, name: str, value: Any, lo: int, hi: int) -> int:
    """The URL's (or the options') ``name`` as an integer in lo..hi; a UsageError otherwise."""
    try:
        v = int(str(value), 0)
    except ValueError:
        raise UsageError(f"{url}: {name}: expected an integer in {lo}..{hi}, got {value!r}") from None
    if not lo <= v <= hi:
        raise UsageError(f"{url}: {name}: expected an integer in {lo}..{hi}, got {v}")
    return v


def _speed(url: str, text: str) -> float:
    from .sim_link import MIN_SPEED

    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (v > 0 and math.isfinite(v)):
        raise UsageError(f"{url}: speed: expected a finite number above 0 (times real time) or 'max', got {text!r}")
    if v < MIN_SPEED:  # a simulated second in years: as --speed refuses it
        raise UsageError(f"{url}: speed: expected at least {MIN_SPEED:g} times real time, or 'max', got {text!r}")
    return v
