"""The example robots beyond the paper on the default (physical) plant, with the controller's
default hold (issue 14): several limbs are held at once while others fall, and no robot file
needs ``hold_duty = 0`` for that any more."""

from __future__ import annotations

from pathlib import Path

import pytest

from proleg.report import SimSession
from proleg.robot import load_robot
from proleg.sim.physical import PhysicalPlant
from proleg.sim.simulators import open_simulated

ROOT = Path(__file__).resolve().parents[1]

CATERPILLAR_REACH = (
    "caterpillar-4's three-level pads need ψ ≥ 35° + h/2 + hold margin for their top level, and "
    "the physical plant's 80 mm body with four contacts bends a pad to at most ≈ 22° with its own "
    "coil (≈ 29° with a neighbour's): the robot file's ψ* are a plausible model for the table "
    "plant, not for this body (test_caterpillar_pads_cannot_reach_their_top_level_on_this_body)")


def _walk(name: str, direction: str, seconds: float = 40.0):
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    assert robot.control.hold_duty > 0.0  # the default hold: no workaround in the file
    sim = open_simulated(robot)  # the default plant: physical
    assert sim.plant_kind == "physical"
    session = SimSession(sim)
    session.advance(0.2)
    return session.run_gait(direction, 0, seconds)


@pytest.mark.parametrize("direction", ["+x", "-x"])
def test_inchworm_walks_both_ways_on_the_physical_plant_without_faults(direction):
    report = _walk("inchworm-3", direction)
    sign = 1 if direction == "+x" else -1
    assert report.faults == [] and report.errors == []
    assert report.cycles >= 3, report.cycles
    assert sign * report.displacement_mm > 0, report.displacement_mm
    assert sum(sign * d > 0 for d in report.cycle_displacements_mm) >= len(report.cycle_displacements_mm) - 1


@pytest.mark.xfail(strict=True, reason=CATERPILLAR_REACH)
@pytest.mark.parametrize("direction", ["+x", "-x"])
def test_caterpillar_walks_both_ways_on_the_physical_plant_without_faults(direction):
    report = _walk("caterpillar-4", direction, 30.0)
    assert report.faults == [] and report.cycles >= 3


def test_caterpillar_pads_cannot_reach_their_top_level_on_this_body():
    robot = load_robot(ROOT / "robots" / "caterpillar-4.toml")
    plant = PhysicalPlant(robot)
    n = len(robot.actuators)
    rear = [lb.name for lb in robot.limbs].index("rear")
    best = 0.0
    for j in range(n):
        for k in range(n):
            c = [0.0] * n
            c[j] = c[k] = 1.0
            plant.pose(c)
            best = max(best, float(plant.psi_deg[rear]))
    top = robot.limbs[rear].psi_star_deg[-1] + robot.limbs[rear].hysteresis_deg / 2
    assert best < top, (best, top)
