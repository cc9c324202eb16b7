"""The supply's sag behind ``supply_ohm`` is the sag of a coil's PWM on-phase.

A coil heats only while its MOSFET is on, when it draws its full current through the source
resistance. The plant sagged the supply by every coil's *mean* current (duty × V/R), so a
coil at duty d < 1 saw too little sag: R1's coil behind 50 Ω settled at 53.8 °C at duty 0.6
and at 51.7 °C at duty 1 (more heat from less duty), and behind 20 Ω at 84.7 °C where
``steady_coil_temperature_c``, which the warnings advise with, says 66.7 °C.
"""

from __future__ import annotations

import pytest

from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.physical import PhysicalPlant, parse_conditions


def _settled(conditions: list[str], duties: list[float], seconds: float = 30.0) -> PhysicalPlant:
    plant = PhysicalPlant(load_robot(robots_dir() / "paper-r1.toml"), parse_conditions(conditions))
    for _ in range(round(seconds / 0.002)):
        plant.step(0.002, duties)
    return plant


@pytest.mark.parametrize("ohm", [2.7, 20.0, 50.0])
def test_a_coil_heats_more_at_more_duty_behind_any_source_resistance(ohm):
    temps = [_settled([f"supply_ohm={ohm}"], [d, 0.0]).temperature_c[0] for d in (0.3, 0.6, 1.0)]
    assert temps[0] < temps[1] < temps[2], temps


@pytest.mark.parametrize("ohm, duty", [(20.0, 0.3), (20.0, 0.6), (50.0, 0.6), (8.0, 0.45)])
def test_one_coil_settles_where_the_warnings_say(ohm, duty):
    plant = _settled([f"supply_ohm={ohm}"], [duty, 0.0])
    assert plant.temperature_c[0] == pytest.approx(plant.steady_coil_temperature_c(duty)[0], abs=0.5)


def test_two_coils_on_together_sag_each_other_and_at_full_duty_as_before():
    alone = _settled(["supply_ohm=20"], [1.0, 0.0]).temperature_c[0]
    both = _settled(["supply_ohm=20"], [1.0, 1.0]).temperature_c
    assert both[0] == pytest.approx(both[1], abs=0.5) and both[0] < alone - 10
    nominal = _settled([], [0.6, 0.0]).temperature_c[0]  # no source resistance: no sag at all
    assert nominal == pytest.approx(_settled([], [0.6, 0.0]).steady_coil_temperature_c(0.6)[0], abs=0.5)


def test_the_condition_help_says_a_lone_coil_sags_too():
    """``--condition help`` said "supply sag when they draw together", and one coil alone sags
    behind ``supply_ohm`` (above: 20 °C cooler at 20 Ω than at none)."""
    from proleg.sim.physical import describe_keys

    line = next(ln for ln in describe_keys().splitlines() if ln.startswith("supply_ohm "))
    assert "sags while it draws" in line and "when they draw together" not in line, line
    alone = _settled(["supply_ohm=20"], [1.0, 0.0]).temperature_c[0]
    assert alone < _settled([], [1.0, 0.0]).temperature_c[0] - 10
