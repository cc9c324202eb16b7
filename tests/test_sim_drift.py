"""A coil's drift (``inject_drift``) is one model, ``sim.sma.checked_drift`` and ``drifted``,
for the table plant and the physical plant: each spelled the checks and the fading again."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from proleg.errors import SimError
from proleg.robot import load_robot
from proleg.sim.physical import PhysicalPlant
from proleg.sim.plant import Plant
from proleg.sim.sma import checked_drift, drifted

R1 = Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml"


@pytest.mark.parametrize("mode, rate, step, why", [
    ("heat", 0.1, 0.0, "mode must be 'power', 'temperature' or 'stroke', got 'heat'"),
    ("power", -0.1, 0.0, "rate must be ≥ 0, got -0.1"),
    ("power", math.nan, 0.0, "rate must be ≥ 0, got nan"),
    ("stroke", 0.1, 1.0, "step must be in [0, 1) for mode 'stroke', got 1.0"),
    ("temperature", 0.1, math.nan, "step must be a finite number of °C for mode 'temperature', got nan"),
    ("temperature", 0.1, math.inf, "step must be a finite number of °C for mode 'temperature', got inf"),
])
def test_both_plants_refuse_a_bad_drift_in_the_same_words(mode, rate, step, why):
    for plant in (Plant(), PhysicalPlant(load_robot(R1))):
        with pytest.raises(SimError) as e:
            plant.inject_drift(0, rate, mode, step)
        assert str(e.value) == f"inject_drift: {why}", type(plant).__name__
    assert checked_drift("temperature", 2, 5) == ("temperature", 2.0, 5.0)  # °C: a step past 1 is fine


def test_a_drift_fades_heating_and_stroke_and_shifts_temperatures_with_on_time():
    assert drifted(("power", 0.5, 0.2), 2.0) == pytest.approx(0.8 * math.exp(-1.0))
    assert drifted(("stroke", 0.0, 0.5), 100.0) == 0.5
    assert drifted(("temperature", 0.5, 3.0), 2.0) == 4.0
