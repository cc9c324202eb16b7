"""Opening a link to a robot for a command: ``--port`` / ``--can`` / ``--sim`` and their
settings (``add_link_options``, ``link_settings``), a connected client on them
(``open_client``), and the check that the board runs the robot file given
(``check_robot_name``). ``run``, ``load-gait``, ``set-param``, ``calibrate``, ``learn`` and the
console take their links here."""

from __future__ import annotations

import argparse
import logging
from typing import Any

from ..errors import LinkError, UsageError
from ..link.serial_link import DEFAULT_BAUDRATE
from .number_args import baudrate, can_bitrate, can_node, reply_timeout

log = logging.getLogger("proleg")


def add_link_options(p: argparse.ArgumentParser, *, sim_takes_robot: bool, required: bool = True,
                     sim_help: str = "") -> None:
    """``--port`` / ``--can`` / ``--sim`` (exactly one; at most one unless ``required``) and
    their settings; ``sim_help`` says more of ``--sim`` where a command simulates more."""
    src = p.add_mutually_exclusive_group(required=required)
    src.add_argument("--port", metavar="URL", help="serial port or pyserial URL: /dev/ttyUSB0, COM3, socket://host:port")
    src.add_argument("--can", metavar="CHANNEL", help="CAN channel (python-can), e.g. can0")
    if sim_takes_robot:
        src.add_argument("--sim", metavar="ROBOT", help=sim_help or "the robot's firmware on the simulated board")
    else:
        src.add_argument("--sim", action="store_true", help=sim_help or "ROBOT's firmware on the simulated board")
    p.add_argument("--interface", help="python-can interface for --can (default: CAN_INTERFACE or ~/.canrc, else socketcan)")
    p.add_argument("--bitrate", type=can_bitrate, metavar="BIT/S",
                   help="with --can: CAN bit rate (default: CAN_BITRATE or ~/.canrc)")
    p.add_argument("--node", type=can_node, help="with --can: CAN node id of the robot, 0..15 (default 0)")
    p.add_argument("--baudrate", type=baudrate, help=f"with --port: serial baud rate (default {DEFAULT_BAUDRATE})")
    p.add_argument("--timeout", type=reply_timeout, default=0.5, metavar="S",
                   help="reply timeout per command (default 0.5 s, 0.01..60)")


#: Link settings that belong to one link option: dest → (the setting's option, that link's option).
LINK_SETTINGS = {"baudrate": ("--baudrate", "--port"), "node": ("--node", "--can"),
                 "bitrate": ("--bitrate", "--can"), "interface": ("--interface", "--can")}


def link_settings(args: argparse.Namespace) -> dict[str, Any]:
    """baudrate, node, bitrate and interface for the link the options choose, defaults filled
    in (their options default to None). A setting of another link is a UsageError: it would be
    ignored (``--sim --baudrate -5`` used to run)."""
    for dest, (option, link) in LINK_SETTINGS.items():
        if getattr(args, dest, None) is not None and getattr(args, link[2:], None) is None:
            raise UsageError(f"{option}: only with {link} (a setting of that link, which this command does not use)")
    return {"baudrate": getattr(args, "baudrate", None) or DEFAULT_BAUDRATE, "node": getattr(args, "node", None) or 0,
            "bitrate": getattr(args, "bitrate", None), "interface": getattr(args, "interface", None)}


def open_client(args: argparse.Namespace, robot_path: str | None = None, *, speed: float | None = None,
                robot: Any = None):
    """A connected ``RobotClient`` on the link the options name (the simulated board runs
    flat out unless ``speed`` paces it). With ``robot`` (the loaded robot file): a board that
    runs another robot is refused before anything is sent to it, and the heartbeat keeps
    pace with the file's link watchdog."""
    from ..link.client import RobotClient
    from ..link.factory import link_url, open_link

    sim = args.sim
    if sim is True:
        sim = robot_path
    elif sim is False:
        sim = None
    if isinstance(sim, str):
        from .main import robot_arg

        sim = robot_arg(sim)
    given = link_settings(args)
    url = link_url(port=args.port, can_channel=args.can, interface=given["interface"], node=given["node"], sim=sim,
                   bitrate=given["bitrate"])
    robot_file = None
    if robot_path is not None:
        from .main import robot_arg

        robot_file = robot_arg(robot_path)
    link = open_link(url, baudrate=given["baudrate"], speed=speed, robot_file=robot_file)
    client = RobotClient(link, timeout=args.timeout, watchdog_ms=None if robot is None else robot.safety.link_watchdog_ms)
    try:
        info = client.connect()
        if robot is not None:
            check_robot_name(info, robot, client.link.description)
    except BaseException:
        client.close()
        raise
    log.debug("connected to %s on %s (build %08x)", info.robot_name, link.description, info.build_id)
    return client


def check_robot_name(info: Any, robot: Any, link: str) -> None:
    """LinkError unless the board's INFO names ``robot`` (its first 15 characters): learning,
    calibrating or loading a gait for one robot on a board that runs another records or sends
    what the file says of the wrong body."""
    from ..robot import info_name

    if info.robot_name != info_name(robot.name):
        raise LinkError(f"{link} runs robot {info.robot_name!r}, not {robot.name!r} ({robot.path}); "
                        "give the robot file it was built from")
