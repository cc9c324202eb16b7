"""Each coil's hottest in a simulated run (``peak_temperature_c``; ``proleg sim`` reports it as
``coil_peak_c`` and warns past the 120 °C that wears NiTi out). The firmware senses no coil
temperature, so the simulator is where a lab sees that a run cooked a coil (docs/safety.md)."""

from __future__ import annotations

import asyncio
import csv
import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.cli import main
from proleg.cli.sim_command import _peaks_text
from proleg.console import ConsoleApp, LimbView, RobotNames
from proleg.link.client import RobotClient
from proleg.link.sim_link import SimLink
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.closed_loop import make_plant
from proleg.sim.simulators import open_host_sim

R1 = robots_dir() / "paper-r1.toml"


@pytest.mark.parametrize("kind", ["physical", "table"])
@settings(max_examples=15, deadline=None)
@given(duties=st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1), st.integers(1, 60)), min_size=1, max_size=8))
def test_the_peak_is_the_hottest_temperature_of_every_step(kind, duties):
    """Against the brute force: the temperatures read after every step, their maximum."""
    plant = make_plant(load_robot(R1), kind)
    seen = list(plant.temperature_c)
    for left, right, steps in duties:
        for _ in range(steps):
            plant.step(0.01, [left, right])
            seen = [max(a, b) for a, b in zip(seen, plant.temperature_c)]
    assert plant.peak_temperature_c == pytest.approx(seen, abs=1e-9)
    plant.reset_peak()  # from here: a run measured on a plant that has run before
    seen = list(plant.temperature_c)
    for left, right, steps in duties[::-1]:
        for _ in range(steps):
            plant.step(0.01, [right, left])
            seen = [max(a, b) for a, b in zip(seen, plant.temperature_c)]
    assert plant.peak_temperature_c == pytest.approx(seen, abs=1e-9)


def test_a_coil_past_120_c_is_warned_about_by_name_and_the_others_are_not():
    lines = _peaks_text({"sma-left": 72.4, "sma-right": 130.2})
    assert lines[0] == "  coils, hottest: sma-left 72 °C, sma-right 130 °C"
    assert lines[1:] == ["  WARNING: coil sma-right reached 130 °C, past the 120 °C that wears NiTi out"]
    assert _peaks_text({"a": 120.0})[1:] == []
    # just past 120 °C: not "reached 120 °C, past the 120 °C", a message contradicting itself
    assert _peaks_text({"a": 120.3}) == ["  coils, hottest: a 120.3 °C",
                                         "  WARNING: coil a reached 120.3 °C, past the 120 °C that wears NiTi out"]
    assert _peaks_text({"a": 119.6}) == ["  coils, hottest: a 119.6 °C"]


def test_proleg_sim_reports_each_coils_hottest(capsys):
    assert main(["sim", str(R1), "--duration", "8", "--json"]) == 0
    peaks = json.loads(capsys.readouterr().out)["coil_peak_c"]
    assert list(peaks) == ["sma-left", "sma-right"]
    assert all(64.0 < t < 120.0 for t in peaks.values()), peaks  # past As (64 °C): both coils moved their limbs
    assert main(["sim", str(R1), "--duration", "8"]) == 0
    out = capsys.readouterr().out
    assert "  coils, hottest: sma-left " in out and "WARNING" not in out


def test_a_sim_recording_carries_each_coils_temperature(capsys, tmp_path):
    """The recording's truth columns: the plant's coil temperatures at each frame, never
    above the run's peak and within a few degrees of it (50 Hz frames of a coil heating
    at most ≈ 100 K/s)."""
    rec = tmp_path / "run.csv"
    assert main(["sim", str(R1), "--duration", "8", "--json", "--record", str(rec)]) == 0
    peaks = json.loads(capsys.readouterr().out)["coil_peak_c"]
    rows = list(csv.DictReader(rec.open()))
    for name, column in (("sma-left", "temp_sma_left_c"), ("sma-right", "temp_sma_right_c")):
        seen = [float(r[column]) for r in rows if r.get(column)]
        assert len(seen) > 300 and seen[0] == pytest.approx(25.0, abs=0.01)  # the plant's ambient at boot
        assert peaks[name] - 3.0 < max(seen) <= peaks[name] + 0.05


def test_the_console_shows_a_simulated_coils_temperature_beside_its_duty():
    robot = load_robot(R1)
    sim = open_host_sim(robot)
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s, speed=8.0, description="sim paper-r1"))
    client.connect()
    app = ConsoleApp(client, limbs=[LimbView(limb.name, limb.psi_star_deg) for limb in robot.limbs],
                     levels=robot.levels, names=RobotNames.for_robot(robot), robot=robot)
    seen = {}

    async def scenario() -> None:
        async with app.run_test(size=(80, 24)) as pilot:  # the README: it fits 80×24
            await pilot.press("s")  # gait 0 in +x
            for _ in range(200):
                await pilot.pause(0.05)
                if sim.time_s > 3.0:
                    break
            app.refresh_view()
            seen["duty"] = str(app.query_one("#duty").content)
            seen["temps"] = list(sim.plant.temperature_c)
            await pilot.press("q")

    asyncio.run(scenario())
    client.close()
    lines = seen["duty"].splitlines()
    assert len(lines) == 2 and all(line.endswith("°C (sim)") for line in lines), seen["duty"]
    shown = [float(line.split()[-3]) for line in lines]
    assert all(abs(s - t) < 10.0 for s, t in zip(shown, seen["temps"])), (shown, seen["temps"])
    assert max(shown) > 40.0  # heated: the gait's first rise is under way by 3 s


def test_the_coil_temperatures_are_truth_over_the_simulated_can_link_as_over_uart():
    """hil tests --link can (sim_can_link) read the truth through a hop with the plant and not
    the robot: it had displacement_mm and no temp_<actuator>_c."""
    from proleg.link.sim_can_link import sim_can_link
    from proleg.sim.simulators import open_simulated

    robot = load_robot(R1)
    link = sim_can_link(open_simulated(robot, "host-sim", link="can", seed=2))
    try:
        truth = link.truth()
    finally:
        link.close()
    assert sorted(truth) == ["displacement_mm", "temp_sma_left_c", "temp_sma_right_c"]
    assert truth["temp_sma_left_c"] == pytest.approx(25.0)  # the plant's ambient, before anything heats


def test_the_temperature_columns_follow_the_duty_columns_order(capsys, tmp_path):
    """Sorted by name they read front, head, rear, tail on caterpillar-4, whose duties (and the
    robot file) go tail, rear, front, head."""
    rec = tmp_path / "run.csv"
    assert main(["sim", "caterpillar-4", "--duration", "1", "--record", str(rec)]) in (0, 1)
    header = rec.read_text().splitlines()[0].split(",")
    duties = [c[len("duty_"):-len("_pct")] for c in header if c.startswith("duty_")]
    temps = [c[len("temp_"):-len("_c")] for c in header if c.startswith("temp_")]
    assert temps == duties == ["sma_tail", "sma_rear", "sma_front", "sma_head"]


def test_a_build_time_overheat_warning_just_past_120_c_shows_the_tenth():
    """'would settle at 120 °C with this supply, past the 120 °C' contradicted itself."""
    from types import SimpleNamespace

    from proleg.sim.plant_warnings import overheat_warnings

    robot = load_robot(R1)
    ceiling = robot.safety.hold_ceiling(robot.control.hold_duty)
    settles = {robot.safety.max_duty: 150.0, ceiling: 120.3, robot.safety.mean_ceiling: 110.0}
    plant = SimpleNamespace(conditions={"ambient_c": 25.0},
                            steady_coil_temperature_c=lambda duty: [settles[duty]] * 2)
    lines = overheat_warnings(robot, plant)
    assert len(lines) == 2 and all("would settle at 120.3 °C with this supply, past the 120 °C" in line
                                   for line in lines), lines


def test_a_run_that_heats_a_coil_past_120_c_fails_though_no_fault_latched(capsys):
    """The stroke robot with one coil drawing 1.5× its twin's power: no fault, the robot walks,
    and its strong coil waits warm at 199 °C. The claim bench counts such a run as overheated;
    proleg sim exited 0."""
    code = main(["sim", "paper-r1-stroke", "--duration", "30", "--condition", "coil_mismatch=0.5", "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["faults"] == [] and doc["cycles"] >= 2  # nothing the firmware could see
    assert doc["coil_peak_c"]["sma-right"] > 120.0 > doc["coil_peak_c"]["sma-left"]
    assert code == 1 and doc["errors"] == [
        f"coil sma-right reached {doc['coil_peak_c']['sma-right']:.0f} °C in the simulated run, past the 120 °C "
        "that wears NiTi out (no board senses it: docs/safety.md)"]
    assert f"proleg: error: {doc['errors'][0]}\n" in captured.err
