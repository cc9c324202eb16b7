"""Physical plant benchmark: the paper's R1 with ``proleg.sim.physical.PhysicalPlant`` in
closed loop with its host-sim firmware, walking its +x gait for 120 s simulated.
Target: ≥ 100× real time (wall clock; the CPU-time rate, simulated s per s of this process's
CPU, is printed beside it because the machine is shared and wall time counts the waiting). Also the plant alone (µs per 2 ms step) and the measured matrix.

The larger example robots (``LARGER``: three, four limbs, planar) walk their gait 0 +x the
same way, reported beside R1 (no target: their bodies have more sections, each tabulated on its
own, ``proleg.body``; a check or learn run on them costs in proportion).

``--measure-matrix`` as a lab runs it (``measure_matrix``, seed 1, two samples per transition) on
the larger bodies (``MATRIX_ROBOTS``: caterpillar-4, 36 states and 140 transitions, and the six-limb
tests/fixtures/caterpillar-6.toml, 64 states and 384), wall and CPU seconds (no target: it was
25.9 and 100 CPU s before the idealised drive and the coils' step were made cheaper), and
caterpillar-4's ``--hold-range`` one margin after another and with its margins in worker
processes (``jobs``: the machine's cores).

Prints a table and writes bench/results/plant.json. Exit status 1 if the target is missed, or if
the hold range measured in workers is not the one measured without.
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
from proleg.sim.physical.measure import measure_matrix_range  # noqa: E402
from proleg.sim.closed_loop import SimulatedRobot, sim_library  # noqa: E402
from proleg.report import SimSession  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "plant.json"
ROBOT = ROOT / "robots" / "paper-r1.toml"
SPEED_S = 120.0
TARGET = 100.0
LARGER = ("inchworm-3", "caterpillar-4", "planar-4")
MATRIX_ROBOTS = (ROOT / "robots" / "caterpillar-4.toml", ROOT / "tests" / "fixtures" / "caterpillar-6.toml")
HOLD_RANGE_ROBOT = ROOT / "robots" / "caterpillar-4.toml"


def _timed(f, *args, **kwargs) -> tuple[object, float, float]:
    """f's result, wall seconds, this process's and its children's CPU seconds."""
    t0, c0 = time.perf_counter(), _cpu_s()
    got = f(*args, **kwargs)
    return got, time.perf_counter() - t0, _cpu_s() - c0


def _cpu_s() -> float:
    """User + system CPU seconds of this process and of the (finished) worker processes it waited for."""
    import resource

    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _measure_matrix_rows() -> dict:
    """--measure-matrix on the larger bodies, and --hold-range with and without workers."""
    out: dict = {}
    for path in MATRIX_ROBOTS:
        robot = load_robot(path)
        m, wall, cpu = _timed(measure_matrix, robot, seed=1)
        out[robot.name] = {"states": len(m.states), "transitions": robot.transitions.n_transitions,
                           "samples": int(m.samples.sum()), "wall_s": wall, "cpu_s": cpu}
    robot = load_robot(HOLD_RANGE_ROBOT)
    jobs = os.cpu_count() or 1
    ranges = {}
    for n in sorted({1, jobs}):
        r, wall, cpu = _timed(measure_matrix_range, robot, seed=1, jobs=n)
        ranges[n] = r
        out[f"{robot.name} --hold-range --jobs {n}"] = {"wall_s": wall, "cpu_s": cpu}
    first = json.dumps(ranges[1].to_json())
    out["hold_range_same_whatever_jobs"] = all(json.dumps(r.to_json()) == first for r in ranges.values())
    return out


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
    out["measure_matrix_larger"] = larger_m = _measure_matrix_rows()
    rows = [("plant alone", f"{out['plant_us_per_step']:.1f} µs / 2 ms step", ""),
            *[_row(f"R1 {d}, firmware + physical plant", r) for d, r in runs.items()],
            ("target", f"≥ {TARGET:.0f}×", "PASS" if out["pass"] else "FAIL"),
            *[_row(f"{name} +x", r) for name, r in larger.items()],
            ("measure_matrix R1", f"{out['measure_matrix_wall_s']:.2f} s wall", ""),
            *[(f"measure_matrix {name}", f"{r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU",
               f"{r['states']} states, {r['transitions']} transitions, {r['samples']} samples" if "states" in r else "")
              for name, r in larger_m.items() if isinstance(r, dict)],
            ("hold range the same whatever --jobs", "yes" if larger_m["hold_range_same_whatever_jobs"] else "NO", "")]
    for a, b, c in rows:
        print(f"{a:<48} {b:<28} {c}")
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(out, indent=1) + "\n")
    return 0 if out["pass"] and larger_m["hold_range_same_whatever_jobs"] else 1


if __name__ == "__main__":
    sys.exit(main())
