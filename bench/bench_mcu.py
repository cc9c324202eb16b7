"""MCU tick budget on both emulated MCUs, in one file: bench/results/mcu.json.

avr-emu (the exact arduino-nano firmware.elf on simavr) and arm-emu (the exact bluepill
firmware.elf on unicorn). For every robots/*.toml that builds for the board: the robot
walks its +x gait 0 in closed loop with the plant for RUN_S emulated seconds at its
configured tick rate (after 0.2 s of boot, not measured). Per control tick the emulator
counts CPU cycles from the end of the tick wait to the start of the next one (busy).
Reported per MCU and robot: busy mean / p99 / max (µs and fraction of the period), ticks
that overran the period, I2C per tick and its share of the busy time (avr: bus owned
START..STOP; arm: CPU time inside hal_i2c_poll, tick and idle), the stack peak, the firmware's clock
against emulated real time (avr), gait cycles, emulation speed (emulated s per wall s,
and per CPU s of the process: the wall figure includes the machine's other load) and
flash size. One extra avr row runs paper-r1 at tick_hz = 2000 to show what an overrun
does to the firmware's clock.

From the rows each MCU's per-tick cost model is derived, the one ``proleg build`` checks
a robot's tick_hz against (``[budget]`` in boards/*.toml, written by hand from this
output): busy p99 ≤ base + per_limb × limbs for every example robot (see cost_model).

``--mcu atmega328p`` (or stm32f103) measures one MCU and keeps the other's section of
the results file as its last run wrote it (each section has its templates' hash).

Target (issue 11): p99 ≤ 70 % and max ≤ 90 % of the tick period for every example
robot at its configured rate. Prints a table, writes bench/results/mcu.json (machine,
inputs' hashes; no timestamps). Exit status 1 if a target is missed. ``--mcu stm32f103``
(or ``atmega328p``, repeatable) measures only those MCUs; the other sections of mcu.json stay
as their last run wrote them.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "host" / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_firmware import machine, sha256, tree_sha256  # noqa: E402

from proleg.emu.arm import ArmEmuRobot, bluepill_elf  # noqa: E402
from proleg.emu.avr import AvrEmuRobot, nano_build_dir  # noqa: E402
from proleg.emu.avr.budget import MAX_LIMIT, P99_LIMIT  # noqa: E402
from proleg.errors import BuildError, ProlegError  # noqa: E402
from proleg.robot import load_robot  # noqa: E402
from proleg.link.listeners import Listener  # noqa: E402
from proleg.report import SimSession  # noqa: E402

RESULTS = ROOT / "bench" / "results" / "mcu.json"
RUN_S = 10.0
BOOT_S = 0.2
SEED = 1


def measure_arm(robot) -> dict:
    """The same run on the emulated bluepill; the same fields where arm-emu measures them."""
    elf = bluepill_elf(robot)
    manifest = json.loads((elf.parent / "proleg-build.json").read_text())
    sim = ArmEmuRobot(robot, elf, seed=SEED)
    board = sim.board
    i2c = board.time_in("hal_i2c_poll")  # the background I2C state machine's CPU time, in the tick and idle
    session = SimSession(sim)
    session.advance(BOOT_S)
    board.clear_ticks()
    i2c[0] = i2c[1] = 0
    t0, c0, e0 = time.perf_counter(), time.process_time(), sim.time_s
    run = session.run_gait("+x", 0, RUN_S)
    wall, cpu, emulated = time.perf_counter() - t0, time.process_time() - c0, sim.time_s - e0
    b = board.tick_budget()
    period = b.tick_period_us
    i2c_us = i2c[0] / 72 / max(1, b.ticks)
    return {
        "tick_hz": robot.control.tick_hz,
        "tick_period_us": period,
        "tick_busy_us": {"mean": round(b.mean, 1), "p99": round(b.p99, 1), "max": round(b.max, 1)},
        "busy_p99_fraction": round(b.p99 / period, 4),
        "busy_max_fraction": round(b.max / period, 4),
        "meets_target": b.p99 <= P99_LIMIT * period and b.max <= MAX_LIMIT * period,
        "ticks": b.ticks,
        "overruns": sum(1 for x in board.busy_us if x > period),
        "i2c_us": {"mean": round(i2c_us, 1), "share_of_busy": round(i2c_us / b.mean, 4) if b.mean else 0.0},
        "i2c_in_tick": False,  # background state machine: i2c_us is CPU time, mostly between ticks
        "stack_peak_bytes": board.stack_peak_bytes(),
        "emulated_s": round(emulated, 3),
        "wall_s": round(wall, 3),
        "cpu_s": round(cpu, 3),
        "emulation_speed": round(emulated / wall, 3),
        "emulation_speed_cpu": round(emulated / cpu, 3),
        "firmware_clock_ratio": None,
        "gait_cycles": run.cycles,
        "mean_cycle_mm": run.mean_cycle_mm,
        "faults": [f.code for f in run.faults],
        "flash_used": manifest["flash_used"],
        "ram_used": manifest["ram_used"],
    }


def cost_model(rows: dict[str, dict], robots: dict[str, object]) -> dict | None:
    """busy p99 ≤ base + per_limb × limbs for every configured-rate row (worst case).

    per_limb: the least-squares slope of busy p99 over the number of limbs when the rows
    have more than one limb count (never below 0), else the I2C time per IMU read inside
    the busy time; base: then the smallest value that puts every robot on or under the
    line, so the model never promises less than a measured robot needed."""
    if any(r.get("i2c_in_tick") is False for r in rows.values()):
        return limb_fit(rows, robots)  # the I2C runs in the background (arm)
    points = []
    for name, r in rows.items():
        if "skipped" in r or "@" in name:
            continue
        points.append((len(robots[name].limbs), r["tick_busy_us"]["p99"], r["i2c_us"]["mean"], name))
    if not points:
        return None
    counts = {p[0] for p in points}
    if len(counts) > 1:
        mx = sum(p[0] for p in points) / len(points)
        my = sum(p[1] for p in points) / len(points)
        slope = sum((p[0] - mx) * (p[1] - my) for p in points) / sum((p[0] - mx) ** 2 for p in points)
        per_limb = max(0.0, slope)
        how = "least-squares slope over the limb counts, base raised to the worst robot"
    else:
        per_limb = max(p[2] / p[0] for p in points)
        how = "I2C time per IMU read, base = the worst robot's rest"
    base = max(p[1] - per_limb * p[0] for p in points)
    base, per_limb = math.ceil(base), math.ceil(per_limb)
    worst = max(points, key=lambda p: p[1] - per_limb * p[0])
    return {"tick_us_base": base, "tick_us_per_limb": per_limb, "how": how, "worst": worst[3],
            "from": ", ".join(sorted(p[3] for p in points))}


def limb_fit(rows: dict[str, dict], robots: dict[str, object]) -> dict | None:
    """Where the I2C runs in the background (arm: its CPU time is mostly outside the tick), the
    per-limb cost is fitted from the rows' limb counts: the worst p99 per count, per_limb the
    steepest rise between counts, base what the worst row leaves (an upper envelope)."""
    worst: dict[int, float] = {}
    for name, r in rows.items():
        if "skipped" not in r and "@" not in name:
            n = len(robots[name].limbs)
            worst[n] = max(worst.get(n, 0.0), r["tick_busy_us"]["p99"])
    counts = sorted(worst)
    if len(counts) < 2:
        return None
    per_limb = max((worst[b] - worst[a]) / (b - a) for a, b in zip(counts, counts[1:]))
    per_limb = max(0.0, per_limb)
    base = max(worst[n] - per_limb * n for n in counts)
    top = max(counts, key=lambda n: worst[n] - per_limb * n)
    kept = {n: r for n, r in rows.items() if "skipped" not in r and "@" not in n}
    worst_robot = max((n for n in kept if len(robots[n].limbs) == top), key=lambda n: kept[n]["tick_busy_us"]["p99"])
    return {"tick_us_base": math.ceil(base), "tick_us_per_limb": math.ceil(per_limb),
            "how": "steepest rise of the worst p99 between limb counts, base what the worst row leaves",
            "worst": worst_robot, "from": ", ".join(sorted(kept))}


def measure(robot) -> dict:
    build = nano_build_dir(robot)
    manifest = json.loads((build / "proleg-build.json").read_text())
    sim = AvrEmuRobot(robot, build / "firmware.elf", seed=SEED)
    clock: list[tuple[float, int]] = []

    class Clock(Listener):
        def on_message(self, received) -> None:
            if received.message.name == "TELEMETRY":
                clock.append((received.time, received.message.time_ms))

    session = SimSession(sim, listeners=[Clock()])
    session.advance(BOOT_S)
    sim.board.clear_ticks()
    clock.clear()
    run = session.run_gait("+x", 0, RUN_S)
    budget = sim.board.tick_budget()
    ratio = None
    if len(clock) >= 2:
        (t0, ms0), (t1, ms1) = clock[0], clock[-1]
        ratio = (ms1 - ms0) / 1000 / (t1 - t0)
    return {
        "tick_hz": robot.control.tick_hz,
        **budget.as_dict(),
        "firmware_clock_ratio": None if ratio is None else round(ratio, 4),
        "gait_cycles": run.cycles,
        "mean_cycle_mm": run.mean_cycle_mm,
        "faults": [f.code for f in run.faults],
        "flash_used": manifest["flash_used"],
        "ram_used": manifest["ram_used"],
        "markers": sim.board.markers.how if sim.board.markers else "GPIOR0",
    }


#: (MCU, simulated board, firmware board, measure, emulator)
MCUS = (
    ("atmega328p", "avr-emu", "arduino-nano", measure, "simavr 1.6 + proleg avr-emu harness"),
    ("stm32f103", "arm-emu", "bluepill-f103", measure_arm, "unicorn 2.1 + proleg arm-emu peripheral models"),
)


def run_mcu(measure_one, board: str, cases: list) -> dict[str, dict]:
    rows: dict[str, dict] = {}
    for name, robot in cases:
        try:
            rows[name] = measure_one(robot)
        except (BuildError, ProlegError) as e:
            # the checkout's own path is not part of the result (it named another clone's /tmp)
            why = str(e).splitlines()[0].replace(f"{ROOT}/", "")
            rows[name] = {"skipped": f"does not build or run on {board}: {why}"}
        print(f"  {board} {name}: done", flush=True)
    return rows


def table(rows: dict[str, dict]) -> bool:
    head = ("robot", "tick", "busy mean/p99/max µs", "p99/max % of tick", "overruns", "I2C µs (share)",
            "stack peak B", "fw clock", "cycles", "speed", "target")
    out = [head]
    ok = True
    for name, r in rows.items():
        if "skipped" in r:
            out.append((name, "", r["skipped"], "", "", "", "", "", "", "", ""))
            continue
        configured = "@" not in name
        meets = r["meets_target"]
        ok &= meets or not configured
        b = r["tick_busy_us"]
        out.append((
            name,
            f"{r['tick_hz']} Hz",
            f"{b['mean']:.0f} / {b['p99']:.0f} / {b['max']:.0f}",
            f"{100 * r['busy_p99_fraction']:.0f} / {100 * r['busy_max_fraction']:.0f}",
            f"{r['overruns']:,}/{r['ticks']:,}",
            f"{r['i2c_us']['mean']:.0f} ({100 * r['i2c_us']['share_of_busy']:.0f} %)",
            str(r["stack_peak_bytes"]),
            f"{r['firmware_clock_ratio']:.3f}×" if r["firmware_clock_ratio"] else "-",
            str(r["gait_cycles"]),
            f"{r['emulation_speed']:.2f}× ({r['emulation_speed_cpu']:.2f}× cpu)",
            ("PASS" if meets else "FAIL") if configured else "(info)",
        ))
    w = [max(len(row[i]) for row in out) for i in range(len(head))]
    for row in out:
        print("  ".join(f"{c:<{w[i]}}" for i, c in enumerate(row)))
    return ok


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mcu", action="append", choices=[m[0] for m in MCUS],
                        help="measure only this MCU (repeatable); the others' sections of "
                             "bench/results/mcu.json are kept as their last run wrote them")
    args = parser.parse_args(argv)
    selected = set(args.mcu or [m[0] for m in MCUS])
    try:
        previous = json.loads(RESULTS.read_text())["mcus"]
    except (OSError, ValueError, KeyError):
        previous = {}
    t_start = time.perf_counter()
    robot_files = sorted((ROOT / "robots").glob("*.toml"))
    robots = {p.stem: load_robot(p) for p in robot_files}
    r1 = robots["paper-r1"]
    fast_r1 = dataclasses.replace(r1, control=dataclasses.replace(r1.control, tick_hz=2000))
    mcus: dict[str, dict] = {}
    ok = True
    for mcu, sim_board, board, measure_one, emulator in MCUS:
        if mcu not in selected:
            if mcu in previous:
                mcus[mcu] = previous[mcu]
                ok &= all(r.get("meets_target", True) for n, r in previous[mcu]["robots"].items() if "@" not in n)
            continue
        cases = list(robots.items()) + ([("paper-r1@2000Hz", fast_r1)] if sim_board == "avr-emu" else [])
        rows = run_mcu(measure_one, sim_board, cases)
        print(f"\n{mcu} ({sim_board}: the exact {board} firmware.elf on {emulator})")
        ok &= table(rows)
        model = cost_model(rows, robots)
        if model:
            print(f"per-tick cost model for boards/{board}.toml [budget]: tick_us_base = {model['tick_us_base']}, "
                  f"tick_us_per_limb = {model['tick_us_per_limb']} (busy p99, {model['how']}; worst "
                  f"{model['worst']}; from {model['from']})")
        mcus[mcu] = {
            "firmware_templates_sha256": tree_sha256(ROOT / "firmware_templates"),
            "simulated_board": sim_board,
            "board": board,
            "emulator": emulator,
            "board_sha256": sha256(ROOT / "boards" / f"{board}.toml"),
            "robots": rows,
            "budget_model": model,
        }
    print(f"target: busy p99 ≤ {100 * P99_LIMIT:.0f} % and max ≤ {100 * MAX_LIMIT:.0f} % of the tick period")

    results = {
        "machine": machine(),
        "inputs": {
            "robots_sha256": {p.stem: sha256(p) for p in robot_files},
            "firmware_templates_sha256": tree_sha256(ROOT / "firmware_templates"),
            "run_s": RUN_S,
            "boot_s": BOOT_S,
            "gait": "+x 0",
            "seed": SEED,
        },
        "targets": {"busy_p99_fraction": P99_LIMIT, "busy_max_fraction": MAX_LIMIT},
        "mcus": mcus,
        "all_targets_met": ok,
        "bench_seconds": round(time.perf_counter() - t_start, 1),
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1) + "\n")
    print(f"all targets {'met' if ok else 'NOT met'}; wrote {RESULTS.relative_to(ROOT)} in {results['bench_seconds']} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
