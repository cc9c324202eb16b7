"""Links to robots (serial, CAN, simulated board), the one protocol client and its listeners.

python-can's shape: one ``Link`` interface (``base``; ``serial_link``, ``can_link``,
``sim_link``), opened from a URL by ``factory.open_link``; ``RobotClient`` (``client``) turning
its bytes into one decoded-message stream (``stream``, ``received``) and matching replies to commands as the
protocol definition says (``replies``); ``Notifier`` fanning that stream out to ``Listener``s (``listeners``; the
console, the recorder and the gait report live in their own packages above this one).
"""

from .base import Link, LinkDisconnected
from .factory import open_link, register_link
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
    "open_link",
    "register_link",
]
