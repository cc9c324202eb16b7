"""Reports on runs of a robot: what the firmware said next to what the plant did.

``gait_run``: ``GaitRunListener`` turns the client's message stream into a ``GaitRun``
(cycles, displacement per cycle, faults, telemetry counts); ``SimSession`` runs a gait on
a simulated robot through the one protocol client and returns that report.
"""

from .gait_run import Fault, GaitRun, GaitRunListener, SimSession

__all__ = ["Fault", "GaitRun", "GaitRunListener", "SimSession"]
