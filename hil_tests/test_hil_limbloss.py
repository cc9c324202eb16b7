"""Limb loss on the board (issue 15): the run-time limb→actuator map, and the firmware's own
fallback when a coil dies (on host-sim and on the exact Nano / bluepill images)."""

from __future__ import annotations

import pytest

from proleg.link.client import CommandRefused
from proleg.protocol.definition import ErrorCode, EventKind


def _compiled_map(robot) -> tuple[int, ...]:
    index = {a.name: i for i, a in enumerate(robot.actuators)}
    return tuple(index[limb.actuator] for limb in robot.limbs)


def test_the_limb_actuator_map_is_read_set_checked_and_restored(target):
    client, robot = target.client, target.robot
    compiled = _compiled_map(robot)
    got = client.request("GET_ACTUATOR_MAP")
    assert tuple(got.actuators) == compiled and got.lost == 0xFF
    everything_on_first = (0,) * len(robot.limbs)
    client.request("SET_ACTUATOR_MAP", actuators=everything_on_first)
    assert tuple(client.request("GET_ACTUATOR_MAP").actuators) == everything_on_first
    with pytest.raises(CommandRefused) as e:
        client.request("SET_ACTUATOR_MAP", actuators=(len(robot.actuators),) + (0,) * (len(robot.limbs) - 1))
    assert e.value.error == ErrorCode.OUT_OF_RANGE and e.value.detail == 0
    client.request("SET_ACTUATOR_MAP", actuators=())
    assert tuple(client.request("GET_ACTUATOR_MAP").actuators) == compiled


@pytest.mark.plant
@pytest.mark.emu_long
@pytest.mark.robot("paper-r1")
def test_without_a_host_r1_falls_back_to_its_one_coil_gait_and_moves_on(target):
    sim = target.sim
    target.client.start(0, "+x")
    target.wait(6.0)
    sim.inject("dead-actuator:sma-right")
    received = target.wait(20.0)
    kinds = [(r.message.kind, r.message.code) for r in received if r.message.name == "EVENT"]
    assert (int(EventKind.FALLBACK), 1) in kinds, kinds
    t_fb = next(r.time for r in received
                if r.message.name == "EVENT" and r.message.kind == EventKind.FALLBACK)
    after = [r.truth["displacement_mm"] for r in received if r.time >= t_fb and "displacement_mm" in r.truth]
    assert after[-1] - after[0] > 2.0, f"moved {after[-1] - after[0]:+.2f} mm after the fallback"
    # the remaining coil raises both ends alone, and is not cooked doing it (R1: about 80 °C; 95 °C
    # while the fallback still heated it to hold the far end, docs/plant.md "Off the grid")
    assert max(sim.plant.peak_temperature_c) < 120.0, sim.plant.peak_temperature_c
    assert tuple(target.client.request("GET_ACTUATOR_MAP").actuators) == (0, 0)
