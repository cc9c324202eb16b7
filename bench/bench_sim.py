"""Closed-loop simulation benchmark (R1's host-sim firmware + plant, ``proleg.sim``).

1. Speed: simulated seconds per wall second for the paper's R1 at its default tick rate
   (1 kHz) walking its +x gait (``proleg.report.SimSession.run_gait("+x", 0, 120 s)``, default 50 Hz
   telemetry). Target ≥ 100× real time.
2. Endurance: SET_TELEMETRY_RATE 100, then one simulated hour of the +x gait: TELEMETRY
   frames expected (100 Hz × the run, ≈ 360,000) vs received, frames lost by sequence
   gaps (target: none), link errors, faults, gait cycles and wall time.

The host-sim library is built (or taken from the cache) before timing starts.
Prints a table and writes bench/results/sim.json (machine information and the inputs'
hashes; no timestamps). Exit status 1 if a target is missed.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_firmware import machine, sha256, tree_sha256  # noqa: E402

from proleg.robot import load_robot  # noqa: E402
from proleg.sim.closed_loop import SimulatedRobot, sim_library  # noqa: E402
from proleg.report import SimSession  # noqa: E402
from proleg.errors import LinkError  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "sim.json"
ROBOT = ROOT / "robots" / "paper-r1.toml"
SPEED_S = 120.0
SPEED_TARGET = 100.0
HOUR_S = 3600.0
TELEMETRY_HZ = 100
SEED = 1


def speed(robot, lib: Path) -> dict:
    sim = SimulatedRobot(robot, library=lib, seed=SEED)
    session = SimSession(sim)
    t0 = time.perf_counter()
    run = session.run_gait("+x", 0, SPEED_S)
    wall = time.perf_counter() - t0
    simulated = SPEED_S + 0.05  # run_gait runs 50 ms past STOP
    return {
        "tick_hz": robot.control.tick_hz,
        "telemetry_hz": robot.control.telemetry_hz,
        "simulated_s": simulated,
        "wall_s": wall,
        "sim_s_per_wall_s": simulated / wall,
        "target": SPEED_TARGET,
        "pass": simulated / wall >= SPEED_TARGET,
        "cycles": run.cycles,
        "displacement_mm": run.displacement_mm,
        "faults": len(run.faults),
    }


def hour(robot, lib: Path) -> dict:
    sim = SimulatedRobot(robot, library=lib, seed=SEED)
    session = SimSession(sim)
    try:
        acked = session.request("SET_TELEMETRY_RATE", hz=TELEMETRY_HZ).name == "ACK"
    except LinkError:
        acked = False
    t0 = time.perf_counter()
    run = session.run_gait("+x", 0, HOUR_S)
    wall = time.perf_counter() - t0
    # Frames are counted from START until 50 ms after STOP (run_gait's tail).
    expected = round((HOUR_S + 0.05) * TELEMETRY_HZ)
    return {
        "telemetry_hz": TELEMETRY_HZ,
        "set_rate_acked": acked,
        "simulated_s": HOUR_S,
        "wall_s": wall,
        "sim_s_per_wall_s": HOUR_S / wall,
        "frames_expected": expected,
        "frames_received": run.telemetry_frames,
        "frames_lost_by_seq_gap": run.telemetry_lost,
        "link_errors": run.link_errors,
        "pass": acked and run.telemetry_lost == 0 and not run.link_errors
        and abs(run.telemetry_frames - expected) <= 1,
        "cycles": run.cycles,
        "mean_cycle_mm": run.mean_cycle_mm,
        "displacement_mm": run.displacement_mm,
        "faults": [f"{f.code}@{f.time_s:.1f}s" for f in run.faults],
    }


def main() -> int:
    t_start = time.perf_counter()
    robot = load_robot(ROBOT)
    t0 = time.perf_counter()
    lib = sim_library(robot)
    lib_s = time.perf_counter() - t0
    sp = speed(robot, lib)
    hr = hour(robot, lib)

    rows = [
        (f"R1 +x, {sp['tick_hz']} Hz tick, {SPEED_S:.0f} s simulated",
         f"{sp['sim_s_per_wall_s']:.0f}× real time", f"target ≥ {SPEED_TARGET:.0f}×", "PASS" if sp["pass"] else "FAIL"),
        (f"R1 +x, 1 h simulated, telemetry {TELEMETRY_HZ} Hz", f"{hr['wall_s']:.1f} s wall",
         f"{hr['sim_s_per_wall_s']:.0f}× real time", ""),
        ("  TELEMETRY frames expected / received", f"{hr['frames_expected']:,} / {hr['frames_received']:,}", "", ""),
        ("  lost by sequence gaps", f"{hr['frames_lost_by_seq_gap']:,}", "target 0",
         "PASS" if hr["pass"] else "FAIL"),
        ("  link errors", ", ".join(f"{k} {v}" for k, v in hr["link_errors"].items()) or "none", "", ""),
        ("  gait cycles / mean per cycle", f"{hr['cycles']:,} / {hr['mean_cycle_mm'] or 0:.2f} mm",
         f"faults: {', '.join(hr['faults']) or 'none'}", ""),
    ]
    w = [max(len(r[i]) for r in rows) for i in range(3)]
    for a, b, c, d in rows:
        print(f"{a:<{w[0]}}  {b:>{w[1]}}  {c:<{w[2]}}  {d}")

    ok = sp["pass"] and hr["pass"]
    results = {
        "machine": machine(),
        "inputs": {
            "robot": "paper-r1",
            "robot_sha256": sha256(ROBOT),
            "firmware_templates_sha256": tree_sha256(ROOT / "firmware_templates"),
            "seed": SEED,
            "speed_simulated_s": SPEED_S,
            "endurance_simulated_s": HOUR_S,
            "endurance_telemetry_hz": TELEMETRY_HZ,
        },
        "host_sim_library_s": lib_s,
        "speed": sp,
        "endurance_1h": hr,
        "all_targets_met": ok,
        "bench_seconds": round(time.perf_counter() - t_start, 1),
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1) + "\n")
    print(f"all targets {'met' if ok else 'NOT met'}; wrote {RESULTS.relative_to(ROOT)} in {results['bench_seconds']} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
