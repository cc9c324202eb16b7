"""Physical plant benchmark: the paper's R1 with ``proleg.sim.physical.PhysicalPlant`` in
closed loop with its host-sim firmware, walking its +x gait for 120 s simulated.
Target: ≥ 100× real time (wall clock; the CPU-time rate, simulated s per s of this process's
CPU, is printed beside it because the machine is shared and wall time counts the waiting). Also the plant alone (µs per 2 ms step) and the measured matrix.

The larger example robots (``LARGER``: three, four limbs, planar) walk their gait 0 +x the
same way, reported beside R1 (no target: their bodies have more sections, each tabulated on its
own, ``proleg.body``; a check or learn run on them costs in proportion).

Prints a table and writes bench/results/plant.json. Exit status 1 if the target is missed.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_firmware import machine  # noqa: E402

from proleg.robot import load_robot  # noqa: E402
from proleg.sim.physical import PhysicalPlant, measure_matrix  # noqa: E402
from proleg.sim.closed_loop import SimulatedRobot, sim_library  # noqa: E402
from proleg.report import SimSession  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "plant.json"
ROBOT = ROOT / "robots" / "paper-r1.toml"
SPEED_S = 120.0
TARGET = 100.0
LARGER = ("inchworm-3", "caterpillar-4", "planar-4")


def _closed_loop(robot, lib, direction: str) -> dict:
    """The firmware on the physical plant for SPEED_S simulated seconds: its rate and walk."""
    sim = SimulatedRobot(robot, library=lib, plant=PhysicalPlant(robot))
    t0, c0 = time.perf_counter(), time.process_time()
    run = SimSession(sim).run_gait(direction, 0, SPEED_S)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    return {"sim_s_per_wall_s": (SPEED_S + 0.05) / wall, "sim_s_per_cpu_s": (SPEED_S + 0.05) / cpu,
            "displacement_mm": run.displacement_mm, "speed_mm_s": run.displacement_mm / SPEED_S, "cycles": run.cycles,
            "faults": [f"{f.code}@{f.time_s:.1f}s" for f in run.faults]}


def _row(name: str, r: dict) -> tuple[str, str, str]:
    return (name, f"{r['sim_s_per_wall_s']:.0f}× wall ({r['sim_s_per_cpu_s']:.0f}× CPU)",
            f"{r['speed_mm_s']:+.3f} mm/s, {r['cycles']} cycles, faults: {', '.join(r['faults']) or 'none'}")


def main() -> int:
    robot = load_robot(ROBOT)
    lib = sim_library(robot)
    out: dict = {"machine": machine(), "load_average": list(os.getloadavg()), "inputs": {"robot": "paper-r1", "simulated_s": SPEED_S}}
    # plant alone
    p = PhysicalPlant(robot)
    n = 20000
    t0 = time.perf_counter()
    for k in range(n):
        ph = (k // 1500) % 4
        p.step(0.002, [0.6 if ph in (0, 1) else 0.0, 0.6 if ph in (1, 2) else 0.0])
        p.limb_truth(0)
        p.limb_truth(1)
    out["plant_us_per_step"] = (time.perf_counter() - t0) / n * 1e6
    # closed loop
    runs = {d: _closed_loop(robot, lib, d) for d in ("+x", "-x")}
    out["closed_loop"] = runs
    larger = {}
    for name in LARGER:
        other = load_robot(ROOT / "robots" / f"{name}.toml")
        larger[name] = _closed_loop(other, sim_library(other), "+x")
    out["larger_robots_closed_loop"] = larger
    speed = min(r["sim_s_per_wall_s"] for r in runs.values())
    out["pass"] = speed >= TARGET
    t0 = time.perf_counter()
    m = measure_matrix(robot, repeats=1)
    out["measure_matrix_wall_s"] = time.perf_counter() - t0
    out["measured_matrix"] = m.to_json()
    rows = [("plant alone", f"{out['plant_us_per_step']:.1f} µs / 2 ms step", ""),
            *[_row(f"R1 {d}, firmware + physical plant", r) for d, r in runs.items()],
            ("target", f"≥ {TARGET:.0f}×", "PASS" if out["pass"] else "FAIL"),
            *[_row(f"{name} +x", r) for name, r in larger.items()],
            ("measure_matrix R1", f"{out['measure_matrix_wall_s']:.2f} s wall", "")]
    for a, b, c in rows:
        print(f"{a:<36} {b:<24} {c}")
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(out, indent=1) + "\n")
    return 0 if out["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
