"""The physical plant: SMA thermal model, body shape, anchor/slip friction mechanics.

``PhysicalPlant(robot, conditions)`` is a drop-in for ``proleg.sim.plant.Plant`` in
``SimulatedRobot(robot, plant=...)``; ``measure_matrix(robot)`` measures the robot's transition
reward matrix on it; ``parse_conditions(["power=0.8", ...])`` builds its ``Conditions``.
See docs/plant.md for the model, its constants and their sources.
"""

from .conditions import KEYS as CONDITION_KEYS
from .conditions import Conditions, describe_keys, parse_conditions
from .measure import (HistoryRange, MatrixRange, MeasuredMatrix, measure_history_range, measure_matrix,
                      measure_matrix_range)
from .plant import PhysicalParams, PhysicalPlant

__all__ = ["CONDITION_KEYS", "Conditions", "HistoryRange", "MatrixRange", "MeasuredMatrix", "PhysicalParams",
           "PhysicalPlant", "describe_keys", "measure_history_range", "measure_matrix", "measure_matrix_range",
           "parse_conditions"]
