"""A coil through its transformation is heated no more at full strokes (docs/control.md, "The
knee"): the two measured overheats of the stroke robot, with no fault, before the knee watch.

- A host moves the left ψ* to 70° (SET_PARAM, inside the band rules): the left end cannot
  cross its band alone, creeps at ≈ 3°/s on the other coil's warmth, and its coil was heated at
  the drive duty to the on-time limit every cycle: 166 °C.
- The random sweep's worn, heavy row (bench/bench_sweep.py seed 3): the left coil was heated
  0.5 s past the end of its worn travel, 125 °C.
"""

from __future__ import annotations

from pathlib import Path

from proleg.link.level import calibrate_level
from proleg.report import claim
from proleg.report.gait_run import SimSession
from proleg.robot import load_robot
from proleg.sim.closed_loop import SimulatedRobot
from proleg.sim.physical.materials import NITI_OVERHEAT_C

STROKE = Path(__file__).resolve().parents[1] / "robots" / "paper-r1-stroke.toml"


def test_a_psi_star_the_limb_cannot_cross_alone_does_not_overheat_its_coil():
    robot = load_robot(STROKE)
    sim = SimulatedRobot(robot, seed=1, plant="physical")
    session = SimSession(sim)
    session.advance(0.2)
    assert calibrate_level(session.client).ok
    session.client.set_param("psi_star_cdeg", 0, 7000)
    session.advance(0.2)
    run = session.run_gait("+x", 0, 30.0)
    session.advance(2.0)
    peak = max(sim.plant.peak_temperature_c)
    # before: 166 °C, ≈ 7 s of every 30 above 120 °C; now its coil is left at the hold duty once
    # spent (≈ 95 °C) and the step times out, the coils cooling
    assert peak < NITI_OVERHEAT_C - 10, peak
    assert run.fault_stops > 0 and "STATE_TIMEOUT" in {str(f.code) for f in run.faults}, run.faults
    assert max(sim.plant.temperature_c) < 60  # 2 s after the stop


def test_the_worn_heavy_stroke_robot_of_the_sweep_walks_without_overheating():
    robot = load_robot(STROKE)
    row = claim.GridPoint("seed 3 worn heavy", (), "random",
                          ("fatigue_cycles=16229", "psi_star_shift_deg=front:-1.2", "mass_g=7.3"), ())
    out = claim.feedback_run(robot, row, duration_s=40.0)
    # before: 3.86 mm/s at 125 °C, no fault; now ≈ 4.7 mm/s at ≈ 101 °C
    assert out.completed and out.fault == "", out
    assert out.coil_peak_c < NITI_OVERHEAT_C - 10, out
    assert out.speed_mm_s > 3.0, out
