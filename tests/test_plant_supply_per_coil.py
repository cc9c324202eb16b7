"""A robot file's per-coil ``[plant] supply_v`` list is each coil's own supply on the physical
plant (``supply_v=NAME:value``), not a ``power_scale``.

It used to become the highest voltage and a ``power_scale`` of (V_j / V_max)² per coil. So a
``--condition power_scale=1`` (a coil's crimp, nothing to do with its supply) put R1's 3 V
right coil on 7.4 V (72 °C instead of 43 °C in a 20 s run), and the run's
``effective_conditions`` named ``power_scale=sma-right:0.164…``, which ``--condition`` refused
("0.164354 is outside [0.2, 2] ×").
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest

from proleg.paths import robots_dir
from proleg.robot import load_robot, robot_from_dict
from proleg.sim.closed_loop import condition_strings, make_plant, plant_conditions

R1 = robots_dir() / "paper-r1.toml"


def _r1(plant: dict):
    doc = copy.deepcopy(tomllib.loads(R1.read_text()))
    doc["plant"] = plant
    return robot_from_dict(doc, Path("r1-two-supplies.toml"))


def _steady(robot, conditions=()):
    return make_plant(robot, "physical", list(conditions)).steady_coil_temperature_c(0.3)


def test_a_coils_own_supply_survives_a_power_scale_condition():
    robot = _r1({"supply_v": [7.4, 3.0]})
    left, right = _steady(robot)
    assert right < left - 20  # the 3 V coil is the cooler one
    assert _steady(robot, ["power_scale=1"]) == pytest.approx([left, right])
    assert _steady(robot, ["power_scale=sma-left:1"]) == pytest.approx([left, right])


def test_the_effective_conditions_of_a_weak_coils_supply_can_be_given_back():
    robot = _r1({"supply_v": [7.4, 3.0]})
    effective = condition_strings(plant_conditions(robot, []))
    assert effective == ["supply_v=sma-left:7.4", "supply_v=sma-right:3.0"]
    plain = load_robot(R1)  # no [plant]: the strings alone give the same coils
    assert _steady(plain, effective) == pytest.approx(_steady(robot))


def test_a_bare_supply_condition_puts_every_coil_on_it():
    robot = _r1({"supply_v": [7.4, 3.0]})
    assert _steady(robot, ["supply_v=5"]) == pytest.approx(_steady(load_robot(R1), ["supply_v=5"]))
    left, right = _steady(robot, ["supply_v=sma-right:7.4"])
    assert left == pytest.approx(right)


def test_one_supply_for_every_coil_is_one_number_as_before():
    robot = _r1({"supply_v": 6.0})
    cond = plant_conditions(robot, [])
    assert cond.get("supply_v") == 6.0 and condition_strings(cond) == ["supply_v=6.0"]
    assert _steady(_r1({"supply_v": [6.0, 6.0]})) == pytest.approx(_steady(robot))
