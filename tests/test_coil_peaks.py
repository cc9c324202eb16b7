"""Each coil's hottest in a simulated run (``peak_temperature_c``; ``proleg sim`` reports it as
``coil_peak_c`` and warns past the 120 °C that wears NiTi out). The firmware senses no coil
temperature, so the simulator is where a lab sees that a run cooked a coil (docs/safety.md)."""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.cli import main
from proleg.cli.sim_command import _peaks_text
from proleg.paths import robots_dir
from proleg.robot import load_robot
from proleg.sim.closed_loop import make_plant

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


def test_a_coil_past_120_c_is_warned_about_by_name_and_the_others_are_not():
    lines = _peaks_text({"sma-left": 72.4, "sma-right": 130.2})
    assert lines[0] == "  coils, hottest: sma-left 72 °C, sma-right 130 °C"
    assert lines[1:] == ["  WARNING: coil sma-right reached 130 °C, past the 120 °C that wears NiTi out"]
    assert _peaks_text({"a": 120.0})[1:] == []


def test_proleg_sim_reports_each_coils_hottest(capsys):
    assert main(["sim", str(R1), "--duration", "8", "--json"]) == 0
    peaks = json.loads(capsys.readouterr().out)["coil_peak_c"]
    assert list(peaks) == ["sma-left", "sma-right"]
    assert all(64.0 < t < 120.0 for t in peaks.values()), peaks  # past As (64 °C): both coils moved their limbs
    assert main(["sim", str(R1), "--duration", "8"]) == 0
    out = capsys.readouterr().out
    assert "  coils, hottest: sma-left " in out and "WARNING" not in out
