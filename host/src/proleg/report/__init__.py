"""Reports on runs of a robot: what the firmware said next to what the plant did.

``gait_run``: ``GaitRunListener`` turns the client's message stream into a ``GaitRun``
(cycles, displacement per cycle, faults, telemetry counts); ``SimSession`` runs a gait on
a simulated robot through the one protocol client and returns that report.
``robot_run``: ``run_gait_on`` runs a gait on any robot through its client (``proleg run``).
"""

from .gait_run import Fault, GaitRun, GaitRunListener, SimSession
from .robot_run import check_gait, run_gait_on

__all__ = ["Fault", "GaitRun", "GaitRunListener", "SimSession", "check_gait", "run_gait_on"]
