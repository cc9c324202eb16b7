"""`proleg gait --json` on robots with many tied optimal gaits: every tie is checked for
feasibility on the hardware (gait/feasibility.py) and written out. The 8-limb shared-coil
robot of tests/fixtures (256 states, 10,000 ties a direction, 46 MB of JSON) took 12.5 s
here before the per-step answers, the state labels and the coil-debt loop were remembered
or unrolled, 3.8 s after (target ≤ 6 s on this 2-core machine; the output is byte for byte
the same; the text report shows the first 10 ties).

    .venv/bin/python bench/bench_gait_report.py

Prints a table and writes bench/results/gait_report.json.
"""

from __future__ import annotations

import contextlib
import io
import json
import platform
import resource
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results" / "gait_report.json"
CASES = [  # (robot file, target seconds for `proleg gait ROBOT --json`)
    ("tests/fixtures/eight-shared.toml", 6.0),
    ("robots/caterpillar-4.toml", 2.0),
]


def run(robot: str) -> dict:
    from proleg.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    started = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["gait", str(ROOT / robot), "--json"])
    wall = time.perf_counter() - started
    doc = json.loads(out.getvalue())
    answers = doc if isinstance(doc, list) else doc.get("results", [doc])
    ties = sum(len(a.get("gaits", [])) for a in answers if isinstance(a, dict))
    return {"robot": robot, "exit": code, "time_s": wall, "ties": ties, "json_mb": len(out.getvalue()) / 1e6}


def main() -> int:
    rows = []
    print(f"{'robot':<36} {'ties':>7} {'JSON MB':>8} {'time s':>8}  target")
    for robot, target in CASES:
        row = run(robot)
        row["target_s"] = target
        row["pass"] = row["exit"] == 0 and row["time_s"] <= target
        rows.append(row)
        print(f"{robot:<36} {row['ties']:>7} {row['json_mb']:>8.1f} {row['time_s']:>8.2f}  "
              f"≤ {target:g} s: {'PASS' if row['pass'] else 'FAIL'}", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({"machine": {"python": platform.python_version(), "machine": platform.machine()},
                                   "peak_rss_mb": peak, "cases": rows}, indent=1) + "\n")
    print(f"peak RSS {peak:.0f} MB; wrote {RESULTS.relative_to(ROOT)}")
    return 0 if all(r["pass"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
