"""The live console on one robot: a textual UI (``ConsoleApp``) and a plain line printer
(``run_plain``), both fed by the client's message stream through a ``Notifier``."""

from .app import ConsoleApp
from .model import ConsoleModel, LimbView
from .plain import run_plain
from .names import RobotNames, describe_event

__all__ = ["ConsoleApp", "ConsoleModel", "LimbView", "RobotNames", "describe_event", "run_plain"]
