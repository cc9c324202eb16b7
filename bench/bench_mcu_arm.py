"""arm-emu benchmark: the exact bluepill firmware.elf of each example robot on the emulated
STM32F103 (``proleg.emu.arm``), walking its +x gait 0 in closed loop with the plant.

Per robot: tick budget (busy µs per tick from app_tick entry to the next tick wait:
mean / p99 / max, and as % of the tick period; issue 11's target p99 ≤ 70 %, max ≤ 90 %),
the share of it spent in hal_i2c_write_read (polled I2C), flash/RAM of the build, the
gait's displacement, and the emulation speed (emulated s per wall s, issue 11 quotes
0.24x for a plain unicorn harness). Prints a table and writes
bench/results/mcu_arm.json. Exit status 1 if a robot misses the budget target.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_firmware import machine  # noqa: E402

from proleg.emu.arm import ArmEmuRobot, bluepill_elf  # noqa: E402
from proleg.errors import ProlegError  # noqa: E402
from proleg.link import RobotClient  # noqa: E402
from proleg.link.sim_link import SimLink  # noqa: E402
from proleg.robot import load_robot  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "mcu_arm.json"
ROBOTS = ("paper-r1", "paper-r2", "paper-r3")
WALK_S = 10.0
SEED = 1


def run(name: str) -> dict:
    robot = load_robot(ROOT / "robots" / f"{name}.toml")
    try:
        elf = bluepill_elf(robot)
    except ProlegError as e:
        return {"robot": name, "skipped": str(e).splitlines()[0]}
    manifest = json.loads((elf.parent / "proleg-build.json").read_text())
    sim = ArmEmuRobot(robot, elf, seed=SEED)
    i2c = sim.board.time_in("hal_i2c_begin")
    client = RobotClient(SimLink(sim))
    client.connect()
    client.start(0, "+x")
    sim.board.busy_us.clear()
    i2c[0] = i2c[1] = 0
    t0, e0 = time.perf_counter(), sim.time_s
    sim.advance(WALK_S)
    wall = time.perf_counter() - t0
    b = sim.board.tick_budget()
    period = b.tick_period_us
    i2c_us = i2c[0] / 72 / max(1, b.ticks)
    return {
        "robot": name,
        "flash_used": manifest["flash_used"],
        "ram_used": manifest["ram_used"],
        "tick_period_us": period,
        "tick_busy_us": {"ticks": b.ticks, "mean": round(b.mean, 1), "p99": round(b.p99, 1), "max": round(b.max, 1)},
        "busy_pct": {"mean": round(100 * b.mean / period, 1), "p99": round(100 * b.p99 / period, 1),
                     "max": round(100 * b.max / period, 1)},
        "i2c_us_per_tick": round(i2c_us, 1),
        "displacement_mm": round(sim.plant.displacement_mm, 2),
        "emulated_s": round(sim.time_s - e0, 3),
        "wall_s": round(wall, 2),
        "speed_x_real_time": round((sim.time_s - e0) / wall, 2),
        "pass": b.p99 <= 0.7 * period and b.max <= 0.9 * period,
    }


def main() -> int:
    rows = [run(n) for n in ROBOTS]
    print(f"{'robot':10} {'flash':>7} {'tick':>5} {'mean':>7} {'p99':>7} {'max':>7} {'i2c':>6} {'speed':>6}  target")
    for r in rows:
        if "skipped" in r:
            print(f"{r['robot']:10} skipped: {r['skipped']}")
            continue
        t = r["tick_busy_us"]
        print(f"{r['robot']:10} {r['flash_used']:>7,} {r['tick_period_us']:>5} {t['mean']:>7} {t['p99']:>7} {t['max']:>7} "
              f"{r['i2c_us_per_tick']:>6} {r['speed_x_real_time']:>5}x  {'ok' if r['pass'] else 'MISSED'}")
    RESULTS.write_text(json.dumps({"machine": machine(), "walk_s": WALK_S, "seed": SEED, "robots": rows}, indent=2) + "\n")
    return 0 if all(r.get("pass", True) for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
