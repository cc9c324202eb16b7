"""Links to robots (serial, CAN, simulated board), the robot client and its consumers.

python-can's shape: one ``Link`` interface, ``RobotClient`` turning its bytes into one
decoded-message stream, ``Notifier`` fanning that stream out to ``Listener``s (console,
recorder, printer, tests). See ``docs/ARCHITECTURE.md`` and each module's docstring.
"""

from .base import Link, LinkDisconnected
from .client import CommandRefused, FirmwareStats, LinkStats, Received, ReplyTimeout, RobotClient, RobotInfo
from .listeners import BufferedReader, CallbackListener, Listener, Notifier, Printer

__all__ = [
    "BufferedReader",
    "CallbackListener",
    "CommandRefused",
    "FirmwareStats",
    "Link",
    "LinkDisconnected",
    "LinkStats",
    "Listener",
    "Notifier",
    "Printer",
    "Received",
    "ReplyTimeout",
    "RobotClient",
    "RobotInfo",
]
