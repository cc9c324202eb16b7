"""The claim off the grid: the ψ-feedback firmware under random conditions nobody tuned for.

The claim bench (bench_claim.py) walks a fixed grid of 66 conditions. A controller can be
fitted to a fixed grid without anyone meaning to, so this bench draws conditions at random:
each row is three keys of the physical plant (docs/plant.md, "Conditions") drawn at random
from the ranges below, at strengths between and beyond the grid's mild and strong ones, on
limbs and coils named as the grid names them (`rear`, `front`: the first and last limb, or on
a robot with limbs of those names, those limbs: caterpillar-4's prolegs). For each row, as in
the claim bench:

- the idealised drive (true ψ and ψ*, the firmware's envelope: ``claim.idealised_walk``) says
  whether the coils can complete the gait under it at all;
- the firmware walks gait 0 on the simulated board, started as a user starts it (a flat
  calibration, then the ground: ``claim.feedback_run``), for the claim bench's run length.

A row is *missed* when the idealised drive walks it and the firmware does not complete it (a
fault stop, the wrong way, or a coil past 120 °C), and a *dirty stop* when neither walks it and
the firmware's stop heated a coil past 120 °C. The verdicts are ``proleg check``'s
(``proleg.report.sweep.Row``): a row where the idealised drive makes under 5 % of its speed on
the nominal plant, and the firmware drifts back without a fault and with cool coils, is
*drifted*, not missed (the gait does not carry the robot there). The draws are seeded (``--seed``): the same rows
each run, different ones with another seed.

    python bench/bench_sweep.py                        # six example robots (ROBOTS), 30 rows each
    python bench/bench_sweep.py --robot robots/X.toml --rows 50 --seed 3

Writes bench/results/sweep.json (or sweep-NAME.json for one --robot) and prints the table.
"""

from __future__ import annotations

import argparse
import json
import logging
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))

from proleg.interrupts import in_workers  # noqa: E402
from proleg.report import sweep  # noqa: E402
from proleg.robot import load_robot  # noqa: E402
from proleg.physics.materials import NITI_OVERHEAT_C  # noqa: E402

#: The example robots whose gait 0 walks +x on the physical plant: not paper-r3 (the idealised drive
#: walks it backwards: docs/plant.md, "R3") nor planar-4 (its +x gait is a library heading).
ROBOTS = ("paper-r1", "paper-r2", "paper-r1-stroke", "paper-r1-one-actuator", "inchworm-3", "caterpillar-4")
ROWS = 30


def run_row(args: tuple[str, int, tuple[str, ...], float]) -> tuple[str, int, sweep.Row]:
    name, i, conditions, run_s = args
    return name, i, sweep.run_row(load_robot(ROOT / "robots" / f"{name}.toml"), conditions, run_s, name=f"{name} #{i}")


def judged(rows: list[sweep.Row], nominal_mm_s: float | None) -> list[sweep.Row]:
    """One robot's rows with ``proleg check``'s verdicts (``sweep.barely_moving`` against the
    idealised drive's nominal speed): a row where that drive makes under 5 % of it, and the
    firmware drifts back without a fault and cool, is *drifted*, not missed. The bench counted
    those missed: it kept no nominal speed to measure them against."""
    return sweep.barely_moving(rows, nominal_mm_s)


def row_json(name: str, i: int, row: sweep.Row) -> dict:
    d = row.to_json()
    return {"robot": name, "row": i, "conditions": d["conditions"], "possible": row.possible,
            "why_not": row.why_not, "idealised_mm_s": d["idealised_mm_s"], "completed": row.completed,
            "speed_mm_s": d["speed_mm_s"], "fault": row.fault, "note": row.note, "coil_peak_c": d["coil_peak_c"],
            "reported": row.reported, "barely_moves": row.barely_moves, "verdict": row.verdict,
            "missed": row.missed, "drifted": row.drifted, "dirty_stop": row.hot_stop}


def summary(rows: list[sweep.Row]) -> dict:
    """``proleg check``'s summary of one robot's rows (``sweep.summary``)."""
    return sweep.summary(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", type=Path, help="one robot file in robots/ (default: the six of ROBOTS)")
    ap.add_argument("--rows", type=int, default=ROWS, help=f"random rows per robot (default {ROWS})")
    ap.add_argument("--seed", type=int, default=1, help="seed of the draws (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    args = ap.parse_args()
    if args.rows < 1:
        ap.error("--rows: at least 1")
    names = (args.robot.stem,) if args.robot else ROBOTS
    if args.robot and args.robot.resolve().parent != (ROOT / "robots").resolve():
        ap.error(f"--robot {args.robot}: one of the robot files in {ROOT / 'robots'}")
    t0 = time.perf_counter()
    draws = sweep.draw_rows(args.rows, args.seed)
    jobs = []
    nominal_mm_s: dict[str, float | None] = {}
    for name in names:
        robot = load_robot(ROOT / "robots" / f"{name}.toml")
        logging.disable(logging.WARNING)
        run_s, nominal = sweep.run_length(robot)  # as proleg check: the idealised drive on the nominal plant
        logging.disable(logging.NOTSET)
        nominal_mm_s[name] = nominal.speed_mm_s
        jobs += [(name, i, c, run_s) for i, c in enumerate(draws)]
    done = list(in_workers(run_row, jobs, args.jobs, "running a row"))
    judged_rows = {n: judged([row for robot, _, row in done if robot == n], nominal_mm_s[n]) for n in names}
    by_robot = {n: summary(judged_rows[n]) for n in names}
    rows = [row_json(n, i, row) for n in names for i, row in enumerate(judged_rows[n])]

    print(f"\nψ-feedback under {args.rows} random conditions a robot ({sweep.KEYS_PER_ROW} keys each, seed {args.seed})")
    print(f"{'robot':22} {'possible':>8} {'completed':>9} {'drifted':>7} {'missed':>6} {'impossible':>10} "
          f"{'fw walks':>8} {'clean stop':>10} {'>120 °C':>7} {'hottest °C':>10}")
    for n, s in by_robot.items():
        print(f"{n:22} {s['possible']:8d} {s['completed_where_possible']:9d} {s['drifted']:7d} {s['missed']:6d} "
              f"{s['impossible']:10d} {s['impossible_completed_by_the_firmware']:8d} "
              f"{s['impossible_stopped_below_120c']:10d} {s['overheated']:7d} {s['hottest_c']:10.1f}")
    for heading, pick in (("rows the firmware did not complete where the idealised drive walks, or stopped hot:",
                           lambda r: r["missed"] or r["dirty_stop"]),
                          ("rows where the gait barely moves the robot (under 5 % of the idealised nominal speed) "
                           "and the firmware drifted back, no fault, coils cool (not missed):", lambda r: r["drifted"])):
        picked = [r for r in rows if pick(r)]
        if picked:
            print(f"\n{heading}")
        for r in picked:
            what = r["fault"] or r["note"] or "no fault"
            print(f"  {r['robot']:22} {' '.join(r['conditions']):70} {what} (peak {r['coil_peak_c']:.0f} °C; "
                  f"idealised {r['idealised_mm_s']} mm/s)")
    out = {
        "benchmark": "sweep",
        "machine": {"python": platform.python_version(), "platform": platform.platform()},
        "inputs": {"robots": list(names), "rows": args.rows, "seed": args.seed, "keys_per_row": sweep.KEYS_PER_ROW,
                   "overheat_c": NITI_OVERHEAT_C, "barely_moves_below": sweep.BARELY},
        "idealised_nominal_mm_s": {n: None if v is None else round(v, 4) for n, v in nominal_mm_s.items()},
        "summary": by_robot, "rows": rows, "bench_wall_s": round(time.perf_counter() - t0, 1),
    }
    path = ROOT / "bench" / "results" / (f"sweep-{args.robot.stem}.json" if args.robot else "sweep.json")
    path.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
