"""The live console on one robot: a textual UI (``ConsoleApp``) and a plain line printer
(``run_plain``), both fed by the client's message stream through a ``Notifier``."""

from .app import ConsoleApp, ConsoleModel, LimbView, describe_event, run_plain

__all__ = ["ConsoleApp", "ConsoleModel", "LimbView", "describe_event", "run_plain"]
